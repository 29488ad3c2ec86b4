//! χ² of a mixture of samplers at one vertex.

use super::vertex::*;
use super::*;

/// `Σ w_k p_k` at one vertex (design §5): the BRDF (diffuse + Phong ns = 100), a wide anchor
/// cone and a tiny one, each component picked with probability `w_k` by `u[0]`.
pub(crate) struct Mixture {
    pub(crate) v: Vertex,
    pub(crate) x: DVec3,
    pub(crate) anchors: [AnchorSampler; 2],
    pub(crate) w: [f64; 3],
}

impl Mixture {
    pub(crate) fn new() -> Self {
        let v = Vertex::new(material(KD, KS, 100.0), 0.8);
        let x = DVec3::new(0.3, -0.2, 0.1);
        let n = v.nd();
        // A wide cone next to the highlight (the lobe axis is at azimuth 0.3 + π) and a
        // tiny one elsewhere, both wholly above the surface.
        let a1 = x + 3.0 * about(n, 0.7, 0.3 + PI + 0.5);
        let a2 = x + 2.0 * about(n, 1.0, 2.0);
        let anchors = [
            AnchorSampler::new(a1, 0.2, 0.9).unwrap(),
            AnchorSampler::new(a2, 1e-3, 0.5).unwrap(),
        ];
        Self {
            v,
            x,
            anchors,
            w: [0.3, 0.5, 0.2],
        }
    }

    /// A direction above the surface, or `None`: the BRDF's rejection, or any component's
    /// direction at or below the surface (the path ends there in the renderer too).
    pub(crate) fn sample(&self, u: [f64; 3]) -> Option<DVec3> {
        let [wb, w1, w2] = self.w;
        let d = if u[0] < wb {
            self.v.sample([u[0] / wb, u[1], u[2]])
        } else if u[0] < wb + w1 {
            Some(self.anchors[0].sample(self.x, [(u[0] - wb) / w1, u[1], u[2]]))
        } else {
            Some(self.anchors[1].sample(self.x, [(u[0] - wb - w1) / w2, u[1], u[2]]))
        };
        d.filter(|d| d.dot(self.v.nd()) > 0.0)
    }

    /// `Σ w_k p_k(d)` with the given weights (the right ones are `self.w`).
    pub(crate) fn pdf_with(&self, w: [f64; 3], d: DVec3) -> f64 {
        w[0] * self.v.pdf(d)
            + w[1] * self.anchors[0].pdf(self.x, d)
            + w[2] * self.anchors[1].pdf(self.x, d)
    }

    pub(crate) fn pdf(&self, d: DVec3) -> f64 {
        self.pdf_with(self.w, d)
    }

    pub(crate) fn tiny_axis(&self) -> DVec3 {
        self.anchors[1].axis(self.x)
    }
}

#[test]
pub(crate) fn mixture_of_brdf_and_two_anchors() {
    let mix = Mixture::new();
    // Bins about the tiny cone with 4 rings inside it (~10⁵ samples each); the wide
    // cone, the lobe and the horizon cross bins, which the adaptive quadrature resolves.
    let theta_c = mix.anchors[1].theta_c;
    let hc = 2.0 * (0.5 * theta_c).sin().powi(2);
    let mut edges: Vec<f64> = (0..4).map(|i| hc * i as f64 / 4.0).collect();
    edges.extend((0..32).map(|i| hc + (2.0 - hc) * i as f64 / 32.0));
    edges.push(2.0);
    let outcomes = Outcomes::new(mix.v.nd(), SphereBins::new(mix.tiny_axis(), edges, 32));
    let (hist, c) = chi2_test(
        &outcomes,
        SAMPLES,
        51,
        |u| mix.sample(u),
        on_outcomes(|d| mix.pdf(d)),
    );
    FAMILY.accept(
        "mixture 0.3 BRDF + 0.5 anchor(0.2, 0.9) + 0.2 anchor(1e-3, 0.5)",
        &hist,
        &c,
    );
    FAMILY.reject(
        "mixture with weights summing to 1.05",
        &chi2(
            &outcomes,
            &hist,
            on_outcomes(|d| mix.pdf_with([0.3, 0.5, 0.25], d)),
        ),
    );
    FAMILY.reject(
        "mixture without the tiny cone's pdf",
        &chi2(
            &outcomes,
            &hist,
            on_outcomes(|d| mix.pdf_with([0.3, 0.5, 0.0], d)),
        ),
    );
}
