//! The vertex the χ² tests sample at, its density models, and the outcomes they bin.

use super::*;

/// A unit normal on no axis, so no coordinate shortcut can hide a bug.
pub(crate) fn normal() -> Vec3 {
    Vec3::new(0.3, 0.4, 0.87).normalize()
}

/// The unit direction at polar angle `theta` and azimuth `phi` about `n`.
pub(crate) fn about(n: DVec3, theta: f64, phi: f64) -> DVec3 {
    let (t, b) = frame(n);
    let (st, ct) = theta.sin_cos();
    (t * (st * phi.cos()) + b * (st * phi.sin()) + n * ct).normalize()
}

/// An orthonormal `(t, b)` completing unit `axis`, independent of the crate's `basis`.
pub(crate) fn frame(axis: DVec3) -> (DVec3, DVec3) {
    let helper = if axis.x.abs() < 0.9 {
        DVec3::X
    } else {
        DVec3::Y
    };
    let t = helper.cross(axis).normalize();
    (t, axis.cross(t))
}

pub(crate) fn material(kd: Vec3, ks: Vec3, ns: f32) -> Material {
    Material {
        name: "test".into(),
        kd,
        ks: Vec3::ZERO,
        glossy: Glossy::Phong { ks, ns },
        mirror: false,
        ke: Vec3::ZERO,
        two_sided: true,
        conductor: None,
        dielectric: None,
        textures: None,
    }
}

/// Coloured albedos whose channel sums and channel maxima give different lobe probabilities
/// (0.615 against 0.667 for the Lambertian lobe), so a max-for-sum slip is visible.
pub(crate) const KD: Vec3 = Vec3::new(0.5, 0.4, 0.3);
pub(crate) const KS: Vec3 = Vec3::new(0.25, 0.25, 0.25);
/// "Grazing": `wo` 80° from the normal, so the lobe axis is 10° above the horizon.
pub(crate) const GRAZING: f64 = 80.0 * PI / 180.0;

/// A material seen from `wo` (f32, as in the renderer) at polar angle `theta_o` from `n`.
pub(crate) struct Vertex {
    pub(crate) m: Material,
    pub(crate) n: Vec3,
    pub(crate) wo: Vec3,
    /// The shading tangent, orthogonal to `n` (anisotropic lobes follow it).
    pub(crate) s: Vec3,
}

/// Phong's albedo and exponent of `m`.
pub(crate) fn phong(m: &Material) -> (Vec3, f32) {
    match m.glossy {
        Glossy::Phong { ks, ns } => (ks, ns),
        _ => (Vec3::ZERO, 1.0),
    }
}

impl Vertex {
    pub(crate) fn new(m: Material, theta_o: f64) -> Self {
        let n = normal();
        let wo = about(n.as_dvec3(), theta_o, 0.3).as_vec3().normalize();
        let s = frame(n.as_dvec3()).0.as_vec3();
        Self { m, n, wo, s }
    }

    pub(crate) fn nd(&self) -> DVec3 {
        self.n.as_dvec3().normalize()
    }

    /// The Phong lobe's axis, the mirror direction of `wo`, as `brdf` computes it.
    pub(crate) fn lobe_axis(&self) -> DVec3 {
        genpath::scene::material::reflect(self.wo, self.n)
            .as_dvec3()
            .normalize()
    }

    /// The shading frame.
    pub(crate) fn frame(&self) -> Frame {
        Frame::new(self.n, self.s)
    }

    /// `d` in the shading frame: (tangent, bitangent `n × s`, normal) components.
    pub(crate) fn local(&self, d: DVec3) -> DVec3 {
        let (n, s) = (self.nd(), self.s.as_dvec3().normalize());
        DVec3::new(s.dot(d), n.cross(s).dot(d), n.dot(d))
    }

    pub(crate) fn pdf(&self, d: DVec3) -> f64 {
        bsdf::pdf(&self.m, self.frame(), self.wo, d.as_vec3())
    }

    /// One draw: the direction above the surface, or `None` for a rejected one. A sample
    /// whose own `pdf` differs from `bsdf::pdf` (what `pdf_path` re-evaluates) is a bug.
    pub(crate) fn sample(&self, u: [f64; 3]) -> Option<DVec3> {
        let s = bsdf::sample(&self.m, self.frame(), self.wo, u)?;
        assert_eq!(
            s.pdf,
            bsdf::pdf(&self.m, self.frame(), self.wo, s.wi),
            "{s:?}"
        );
        assert!(!s.delta);
        Some(s.wi.as_dvec3().normalize())
    }
}

/// The BRDF sampler's density written out again from the model (design §4), with knobs to
/// break it: Lambertian `cos/π` above the surface with probability `p_diffuse`, else the
/// lobe `norm/(2π)·cos^exponent α` about the mirror direction (zero beyond 90° from it).
#[derive(Clone, Copy)]
pub(crate) struct Model {
    pub(crate) p_diffuse: f64,
    pub(crate) exponent: f64,
    pub(crate) norm: f64,
}

impl Model {
    /// The right model: lobe chosen by the albedos' channel sums, `(n+1)/(2π)`.
    pub(crate) fn of(m: &Material) -> Self {
        let sum = |c: Vec3| c.as_dvec3().element_sum();
        let (ks, ns) = phong(m);
        let ns = ns as f64;
        Self {
            p_diffuse: sum(m.kd) / (sum(m.kd) + sum(ks)),
            exponent: ns,
            norm: ns + 1.0,
        }
    }

    pub(crate) fn pdf(self, v: &Vertex, d: DVec3) -> f64 {
        let cos = v.nd().dot(d);
        let c = v.lobe_axis().dot(d);
        let diffuse = if cos > 0.0 { cos / PI } else { 0.0 };
        let phong = if c > 0.0 {
            self.norm / (2.0 * PI) * c.powf(self.exponent)
        } else {
            0.0
        };
        self.p_diffuse * diffuse + (1.0 - self.p_diffuse) * phong
    }

    /// The Phong lobe alone, normalised over the sphere.
    pub(crate) fn lobe(self, v: &Vertex, d: DVec3) -> f64 {
        Self {
            p_diffuse: 0.0,
            ..self
        }
        .pdf(v, d)
    }
}

// ---------------------------------------------------------------- the outcome binning

/// Rings × sectors of the quadrature of the "no direction" outcome over the lower hemisphere.
pub(crate) const BELOW_RINGS: usize = 8;
pub(crate) const BELOW_SECTORS: usize = 16;

/// Directions above the surface in `above`'s bins, plus the outcome "no direction" (see the
/// file's header). A direction returned below the surface falls in no bin: χ² fails.
pub(crate) struct Outcomes {
    pub(crate) above: SphereBins,
    /// Bins about `−n` whose first `BELOW_RINGS` rings are exactly the lower hemisphere.
    pub(crate) below: SphereBins,
    pub(crate) n: DVec3,
}

impl Outcomes {
    pub(crate) fn new(n: DVec3, above: SphereBins) -> Self {
        Self {
            above,
            below: SphereBins::equal_area(-n, 2 * BELOW_RINGS, BELOW_SECTORS),
            n,
        }
    }
}

impl Binning for Outcomes {
    type Point = Option<DVec3>;

    fn bins(&self) -> usize {
        self.above.bins() + 1
    }

    fn bin_of(&self, x: &Option<DVec3>) -> Option<usize> {
        match x {
            None => Some(self.above.bins()),
            Some(d) if d.dot(self.n) > 0.0 => self.above.bin_of(d),
            Some(_) => None,
        }
    }

    fn integrate(&self, bin: usize, pdf: &dyn Fn(&Option<DVec3>) -> f64) -> f64 {
        let n = self.n;
        if bin < self.above.bins() {
            let upper = |d: &DVec3| if d.dot(n) > 0.0 { pdf(&Some(*d)) } else { 0.0 };
            self.above.integrate(bin, &upper)
        } else {
            let lower = |d: &DVec3| if d.dot(n) <= 0.0 { pdf(&Some(*d)) } else { 0.0 };
            (0..BELOW_RINGS * BELOW_SECTORS)
                .map(|b| self.below.integrate(b, &lower))
                .sum()
        }
    }
}

/// A density of directions as a density of outcomes. "No direction" has a probability, not a
/// density; the harness asks for it only to count samples without a positive density, which
/// a rejection is not, so it gets 1.
pub(crate) fn on_outcomes(
    pdf: impl Fn(DVec3) -> f64 + Copy,
) -> impl Fn(&Option<DVec3>) -> f64 + Copy {
    move |x| x.map_or(1.0, pdf)
}

/// Bins about the lobe axis: `4/ns` in `h = 1 − cos θ` holds 98 % of a lobe
/// `∝ cos^ns ≈ e^{−ns·h}`, cut into 16 equal rings (an e-fold every 4), so even the lobe of
/// `ns = 1e4`, 0.01 rad wide, spans 16 × 16 bins; 16 rings of geometric widths cover the
/// tail and the rest of the sphere (so no ring holds a whole steep tail, which would cost
/// the quadrature dearly).
pub(crate) fn lobe_bins(axis: DVec3, ns: f64) -> SphereBins {
    let split = (4.0 / ns).min(1.0);
    let ratio = (2.0 / split).powf(1.0 / 16.0);
    let mut edges: Vec<f64> = (0..16).map(|i| split * i as f64 / 16.0).collect();
    edges.extend((0..16).map(|i| split * ratio.powi(i)));
    edges.push(2.0);
    SphereBins::new(axis, edges, 16)
}

/// Draws from the BRDF sampler at `v` and accepts `bsdf::pdf`; returns what the wrong
/// densities need.
pub(crate) fn check_brdf(
    name: &str,
    v: &Vertex,
    bins: SphereBins,
    seed: u64,
) -> (Outcomes, Histogram) {
    let outcomes = Outcomes::new(v.nd(), bins);
    let (hist, c) = chi2_test(
        &outcomes,
        SAMPLES,
        seed,
        |u| v.sample(u),
        on_outcomes(|d| v.pdf(d)),
    );
    let none = outcomes.above.bins();
    let observed = hist.counts[none] as f64 / SAMPLES as f64;
    let expected = outcomes.integrate(none, &on_outcomes(|d| v.pdf(d)));
    println!("{name}: no direction in {observed:.5} of the draws, {expected:.5} expected");
    FAMILY.accept(name, &hist, &c);
    (outcomes, hist)
}

/// [`reject_model`] with `right`'s normalisation that of the BRDF, `(ns + 2)/(2π)`, in
/// place of the sampled lobe's `(ns + 1)/(2π)`.
pub(crate) fn reject_brdf_normalisation(
    name: &str,
    v: &Vertex,
    outcomes: &Outcomes,
    hist: &Histogram,
    right: Model,
) {
    let brdf_norm = Model {
        norm: right.exponent + 2.0,
        ..right
    };
    let name = format!("{name} with (ns+2)/(2π) in the pdf");
    reject_model(&name, v, outcomes, hist, brdf_norm);
}

pub(crate) fn reject_model(
    name: &str,
    v: &Vertex,
    outcomes: &Outcomes,
    hist: &Histogram,
    wrong: Model,
) {
    FAMILY.reject(
        name,
        &chi2(outcomes, hist, on_outcomes(|d| wrong.pdf(v, d))),
    );
}

/// The model must be the sampler's density, so that each wrong one differs from it only by
/// its knob: checked at the sampler's own directions, taken as exact unit vectors. (Before
/// `brdf` renormalised `wi` in f64, the f32 length error put the density at `ns = 1e4` off
/// by up to 3e-4 here.)
pub(crate) fn assert_model_is_the_pdf(v: &Vertex) {
    let model = Model::of(&v.m);
    let mut checked = 0;
    for i in 0..10_000 {
        let u = [
            (i as f64 + 0.5) / 1e4,
            ((i * 37) % 101) as f64 / 101.0,
            0.37,
        ];
        if let Some(s) = bsdf::sample(&v.m, v.frame(), v.wo, u) {
            let (want, got) = (s.pdf, model.pdf(v, s.wi.as_dvec3().normalize()));
            assert!((got - want).abs() <= 1e-6 * want, "{got} {want}");
            checked += 1;
        }
    }
    assert!(checked > 5_000);
}

// ---------------------------------------------------------------- χ² of the BRDF sampler
