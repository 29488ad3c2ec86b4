//! χ² of the renderer's guided BSDF.

use super::vertex::*;
use super::*;

// ---------------------------------------------------------------- χ² of the guided BSDF

/// A guided vertex (diffuse + Phong ns = 10, seen from 0.7 rad) under a [`Guide`] whose
/// first level mixes the BRDF (weight 0.4) with two anchor cones (0.35, 0.25), and whose
/// spatial field, trained at the vertex on records around one direction above the surface,
/// samples the level's BRDF share and, past the level, guides beside the BRDF alone.
pub(crate) struct Guided {
    pub(crate) v: Vertex,
    pub(crate) x: Vec3,
    pub(crate) guide: Guide,
}

impl Guided {
    pub(crate) fn new() -> Self {
        let v = Vertex::new(material(KD, KS, 10.0), 0.7);
        let (x, n) = (Vec3::new(0.3, -0.2, 0.1), v.nd());
        let light = LightPointSampler::uniform(0);
        let cone = |theta: f64, phi: f64, distance: f64, theta_c: f64, alpha: f64| {
            let anchor = x.as_dvec3() + distance * about(n, theta, phi);
            let sampler =
                DirectionSampler::Anchor(AnchorSampler::new(anchor, theta_c, alpha).unwrap());
            PathGenerator {
                steps: vec![Step {
                    sampler,
                    absorption: 0.5,
                }],
                light,
            }
        };
        let mixture = GenMixture::new(
            vec![
                PathGenerator::srt(3, 0.5, light),
                cone(0.5, 1.0, 3.0, 0.3, 0.8),
                cone(1.1, 4.0, 2.0, 0.15, 0.6),
            ],
            vec![0.4, 0.35, 0.25],
        );
        // Records over a square of side 1/16 of the square map, at a direction 0.6 rad off
        // the normal.
        let [tu, tv] = to_square(about(n, 0.6, 2.5).as_vec3());
        assert!(tu < 0.9 && tv < 0.9, "{tu} {tv}");
        let mut rng = sample_rng(8, 0, 0);
        let records: Vec<Record> = (0..4100)
            .map(|i| Record {
                p: x,
                facing: facing(v.n) as u8,
                dir: [tu + uniform(&mut rng) / 16.0, tv + uniform(&mut rng) / 16.0],
                value: 1.0 + (i % 3) as f32,
            })
            .collect();
        let field = SpatialField::train(x - Vec3::ONE, x + Vec3::ONE, records);
        let guide = Guide::new(&mixture).with_spatial(Some(Arc::new(field)));
        Self { v, x, guide }
    }

    /// The guided BSDF of `guide` at the vertex, as the `k`-th non-delta vertex of a path.
    pub(crate) fn bsdf<'a>(&'a self, guide: &'a Guide, k: usize) -> GuidedBsdf<'a> {
        let bsdf = Bsdf {
            material: (&self.v.m).into(),
            frame: self.v.frame(),
            wo: self.v.wo,
            ns: self.v.n,
        };
        guide.vertex(k, self.x, bsdf, false).bsdf
    }
}

#[cfg(feature = "testing")] // the must-reject twin scales the guide (a fault injection)
/// χ² of the guided BSDF's samples at level `k` against its `pdf`, which must accept, and
/// against the `pdf` of the same guide with its cones' and field's densities scaled by 1.1
/// (not its sampling: [`Guide::with_pdf_error`]), which must reject. Each sample's own
/// density is `pdf`'s, but for the few that rounding at a leaf's edge moves into the
/// neighbouring leaf.
pub(crate) fn check_guided(name: &str, k: usize, samplers: usize, seed: u64) {
    let g = Guided::new();
    let bsdf = g.bsdf(&g.guide, k);
    assert!(bsdf.guided() && bsdf.samplers() == samplers);
    let nd = g.v.nd();
    let outcomes = Outcomes::new(nd, SphereBins::equal_area(nd, 32, 32));
    let mut rng = sample_rng(seed, 0, 0);
    let mut mismatched = 0;
    // The guided BSDF draws from the renderer's own stream, not from the harness's numbers.
    let sample = |_: [f64; 3]| {
        let s = bsdf.sample(&mut rng)?;
        let p = bsdf.pdf(s.wi);
        mismatched += usize::from((s.pdf - p).abs() > 1e-9 * p);
        assert!(!s.delta && bsdf.eval(s.wi) == bsdf::eval(&g.v.m, g.v.frame(), g.v.wo, s.wi));
        Some(s.wi.as_dvec3().normalize()).filter(|d| d.dot(nd) > 0.0)
    };
    let pdf = |d: DVec3| bsdf.pdf(d.as_vec3());
    let (hist, c) = chi2_test(&outcomes, SAMPLES, seed, sample, on_outcomes(pdf));
    assert!(
        mismatched as u64 <= SAMPLES / 1000,
        "{name}: {mismatched} densities differ from pdf's"
    );
    FAMILY.accept(name, &hist, &c);
    let wrong = g.guide.clone().with_pdf_error(1.1);
    let wrong_bsdf = g.bsdf(&wrong, k);
    let wrong_pdf = |d: DVec3| wrong_bsdf.pdf(d.as_vec3());
    FAMILY.reject(
        &format!("{name} with the guide's densities × 1.1"),
        &chi2(&outcomes, &hist, on_outcomes(wrong_pdf)),
    );
}

#[cfg(feature = "testing")] // the must-reject twin scales the guide (a fault injection)
/// Level 0: the BRDF's share (itself half the spatial field's region), the two cones.
#[test]
pub(crate) fn guided_bsdf_with_anchor_cones_and_a_spatial_field() {
    check_guided(
        "guided BSDF, level 0: BRDF and field 0.4, cones 0.35 + 0.25",
        0,
        3,
        61,
    );
}

#[cfg(feature = "testing")] // the must-reject twin scales the guide (a fault injection)
/// Past the level: the spatial field's region beside the BRDF, half and half.
#[test]
pub(crate) fn guided_bsdf_past_the_levels() {
    check_guided("guided BSDF past the levels: field 0.5, BRDF 0.5", 1, 1, 62);
}

// ---------------------------------------------------------------- ∫ pdf by quadrature
