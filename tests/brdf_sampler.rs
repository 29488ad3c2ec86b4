//! Statistical tests of the BRDF sampler, of a mixture of samplers at one vertex (design §4,
//! §5, §10) and of the renderer's guided BSDF (`genpath::guiding::GuidedBsdf`): χ² of sample
//! histograms against the densities the renderer evaluates, each paired with deliberately
//! wrong densities that the same histogram must reject; and `∫ pdf` by quadrature that does
//! not use the samplers. Run with
//! `cargo test --release --test brdf_sampler` (`-- --nocapture` prints every statistic).
//!
//! The outcome of a draw: `brdf::pdf` is the density, over the full sphere, of the direction
//! the sampler *generates*; the Phong lobe about the mirror direction can put some of it below
//! the surface, and `brdf::sample` returns `None` for those draws (they carry no energy). The
//! sampler does not hand the rejected directions out, so the honest event space is: a
//! direction above the surface, binned, or "no direction", one more bin whose expected
//! probability is `∫ pdf` over the lower hemisphere — computed by its own quadrature, not as
//! `1 − Σ(other bins)`, so a density of the wrong total mass shows in that bin too. This is
//! also exactly what a path vertex sees (`path/generator.rs` ends the path when `cos ≤ 0`).
// Without feature `testing` the guided BSDF's tests (whose must-reject twins scale the
// guide, a fault injection) are left out, and with them the use of their helpers.
#![cfg_attr(not(feature = "testing"), allow(dead_code, unused_imports))]

// The shared harness; its triangle binning serves the light sampler's tests, not these.
#[allow(dead_code)]
#[path = "../src/sampling/chi2.rs"]
mod chi2;

use chi2::{chi2, chi2_test, sidak, Binning, Chi2, Histogram, SphereBins};
use genpath::guiding::lattice::facing;
use genpath::guiding::square::to_square;
use genpath::guiding::{Guide, GuidedBsdf, Record, SpatialField};
use genpath::path::generator::{DirectionSampler, PathGenerator, Step};
use genpath::path::mixture::Mixture as GenMixture;
use genpath::path::pt::{Bsdf, PathGuide, VertexBsdf};
use genpath::sampling::anchor::AnchorSampler;
use genpath::sampling::brdf;
use genpath::sampling::light_point::LightPointSampler;
use genpath::sampling::{sample_rng, uniform};
use genpath::scene::Material;
use glam::{DVec3, Vec3};
use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::Arc;

/// χ² tests in this file that must accept: the Šidák correction's count (keep it in step).
const CHI2_TESTS: usize = 11;
const SAMPLES: u64 = 4_000_000;

fn significance() -> f64 {
    sidak(0.01, CHI2_TESTS)
}

fn accept(name: &str, hist: &Histogram, c: &Chi2) {
    println!("accept {name}: {c}");
    assert_eq!(
        hist.bad_pdf, 0,
        "{name}: samples without finite positive pdf"
    );
    assert!(
        c.impossible.is_none() && c.p_value > significance(),
        "{name}: {c}, significance {:.2e}",
        significance()
    );
}

fn reject(name: &str, c: &Chi2) {
    println!("reject {name}: {c}");
    assert!(
        c.p_value <= significance(),
        "{name} was not rejected: {c}, significance {:.2e}",
        significance()
    );
}

// ---------------------------------------------------------------- the vertex

/// A unit normal on no axis, so no coordinate shortcut can hide a bug.
fn normal() -> Vec3 {
    Vec3::new(0.3, 0.4, 0.87).normalize()
}

/// The unit direction at polar angle `theta` and azimuth `phi` about `n`.
fn about(n: DVec3, theta: f64, phi: f64) -> DVec3 {
    let (t, b) = frame(n);
    let (st, ct) = theta.sin_cos();
    (t * (st * phi.cos()) + b * (st * phi.sin()) + n * ct).normalize()
}

/// An orthonormal `(t, b)` completing unit `axis`, independent of the crate's `basis`.
fn frame(axis: DVec3) -> (DVec3, DVec3) {
    let helper = if axis.x.abs() < 0.9 {
        DVec3::X
    } else {
        DVec3::Y
    };
    let t = helper.cross(axis).normalize();
    (t, axis.cross(t))
}

fn material(kd: Vec3, ks: Vec3, ns: f32) -> Material {
    Material {
        name: "test".into(),
        kd,
        ks,
        ns,
        mirror: false,
        ke: Vec3::ZERO,
        two_sided: true,
        conductor: None,
    }
}

/// Coloured albedos whose channel sums and channel maxima give different lobe probabilities
/// (0.615 against 0.667 for the Lambertian lobe), so a max-for-sum slip is visible.
const KD: Vec3 = Vec3::new(0.5, 0.4, 0.3);
const KS: Vec3 = Vec3::new(0.25, 0.25, 0.25);
/// "Grazing": `wo` 80° from the normal, so the lobe axis is 10° above the horizon.
const GRAZING: f64 = 80.0 * PI / 180.0;

/// A material seen from `wo` (f32, as in the renderer) at polar angle `theta_o` from `n`.
struct Vertex {
    m: Material,
    n: Vec3,
    wo: Vec3,
}

impl Vertex {
    fn new(m: Material, theta_o: f64) -> Self {
        let n = normal();
        let wo = about(n.as_dvec3(), theta_o, 0.3).as_vec3().normalize();
        Self { m, n, wo }
    }

    fn nd(&self) -> DVec3 {
        self.n.as_dvec3().normalize()
    }

    /// The Phong lobe's axis, the mirror direction of `wo`, as `brdf` computes it.
    fn lobe_axis(&self) -> DVec3 {
        brdf::reflect(self.wo, self.n).as_dvec3().normalize()
    }

    fn pdf(&self, d: DVec3) -> f64 {
        brdf::pdf(&self.m, self.n, self.wo, d.as_vec3())
    }

    /// One draw: the direction above the surface, or `None` for a rejected one. A sample
    /// whose own `pdf` differs from `brdf::pdf` (what `pdf_path` re-evaluates) is a bug.
    fn sample(&self, u: [f64; 3]) -> Option<DVec3> {
        let s = brdf::sample(&self.m, self.n, self.wo, u)?;
        assert_eq!(s.pdf, brdf::pdf(&self.m, self.n, self.wo, s.wi), "{s:?}");
        assert!(!s.delta);
        Some(s.wi.as_dvec3().normalize())
    }
}

/// The BRDF sampler's density written out again from the model (design §4), with knobs to
/// break it: Lambertian `cos/π` above the surface with probability `p_diffuse`, else the
/// lobe `norm/(2π)·cos^exponent α` about the mirror direction (zero beyond 90° from it).
#[derive(Clone, Copy)]
struct Model {
    p_diffuse: f64,
    exponent: f64,
    norm: f64,
}

impl Model {
    /// The right model: lobe chosen by the albedos' channel sums, `(n+1)/(2π)`.
    fn of(m: &Material) -> Self {
        let sum = |c: Vec3| c.as_dvec3().element_sum();
        let ns = m.ns as f64;
        Self {
            p_diffuse: sum(m.kd) / (sum(m.kd) + sum(m.ks)),
            exponent: ns,
            norm: ns + 1.0,
        }
    }

    fn pdf(self, v: &Vertex, d: DVec3) -> f64 {
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
    fn lobe(self, v: &Vertex, d: DVec3) -> f64 {
        Self {
            p_diffuse: 0.0,
            ..self
        }
        .pdf(v, d)
    }
}

// ---------------------------------------------------------------- the outcome binning

/// Rings × sectors of the quadrature of the "no direction" outcome over the lower hemisphere.
const BELOW_RINGS: usize = 8;
const BELOW_SECTORS: usize = 16;

/// Directions above the surface in `above`'s bins, plus the outcome "no direction" (see the
/// file's header). A direction returned below the surface falls in no bin: χ² fails.
struct Outcomes {
    above: SphereBins,
    /// Bins about `−n` whose first `BELOW_RINGS` rings are exactly the lower hemisphere.
    below: SphereBins,
    n: DVec3,
}

impl Outcomes {
    fn new(n: DVec3, above: SphereBins) -> Self {
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
fn on_outcomes(pdf: impl Fn(DVec3) -> f64 + Copy) -> impl Fn(&Option<DVec3>) -> f64 + Copy {
    move |x| x.map_or(1.0, pdf)
}

/// Bins about the lobe axis: `4/ns` in `h = 1 − cos θ` holds 98 % of a lobe
/// `∝ cos^ns ≈ e^{−ns·h}`, cut into 16 equal rings (an e-fold every 4), so even the lobe of
/// `ns = 1e4`, 0.01 rad wide, spans 16 × 16 bins; 16 rings of geometric widths cover the
/// tail and the rest of the sphere (so no ring holds a whole steep tail, which would cost
/// the quadrature dearly).
fn lobe_bins(axis: DVec3, ns: f64) -> SphereBins {
    let split = (4.0 / ns).min(1.0);
    let ratio = (2.0 / split).powf(1.0 / 16.0);
    let mut edges: Vec<f64> = (0..16).map(|i| split * i as f64 / 16.0).collect();
    edges.extend((0..16).map(|i| split * ratio.powi(i)));
    edges.push(2.0);
    SphereBins::new(axis, edges, 16)
}

/// Draws from the BRDF sampler at `v` and accepts `brdf::pdf`; returns what the wrong
/// densities need.
fn check_brdf(name: &str, v: &Vertex, bins: SphereBins, seed: u64) -> (Outcomes, Histogram) {
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
    accept(name, &hist, &c);
    (outcomes, hist)
}

fn reject_model(name: &str, v: &Vertex, outcomes: &Outcomes, hist: &Histogram, wrong: Model) {
    reject(
        name,
        &chi2(outcomes, hist, on_outcomes(|d| wrong.pdf(v, d))),
    );
}

/// The model must be the sampler's density, so that each wrong one differs from it only by
/// its knob: checked at the sampler's own directions, taken as exact unit vectors. (Before
/// `brdf` renormalised `wi` in f64, the f32 length error put the density at `ns = 1e4` off
/// by up to 3e-4 here.)
fn assert_model_is_the_pdf(v: &Vertex) {
    let model = Model::of(&v.m);
    let mut checked = 0;
    for i in 0..10_000 {
        let u = [
            (i as f64 + 0.5) / 1e4,
            ((i * 37) % 101) as f64 / 101.0,
            0.37,
        ];
        if let Some(s) = brdf::sample(&v.m, v.n, v.wo, u) {
            let (want, got) = (s.pdf, model.pdf(v, s.wi.as_dvec3().normalize()));
            assert!((got - want).abs() <= 1e-6 * want, "{got} {want}");
            checked += 1;
        }
    }
    assert!(checked > 5_000);
}

// ---------------------------------------------------------------- χ² of the BRDF sampler

#[test]
fn brdf_diffuse() {
    let v = Vertex::new(material(KD, Vec3::ZERO, 1.0), 0.7);
    let (outcomes, hist) = check_brdf("diffuse", &v, SphereBins::equal_area(v.nd(), 16, 32), 41);
    assert_eq!(hist.counts[outcomes.above.bins()], 0, "diffuse rejections");
    // A normalised density of the wrong shape: ∝ cos^1.1 instead of cos.
    let n = v.nd();
    let k = 1.1;
    let wrong = |d: DVec3| (k + 1.0) / (2.0 * PI) * n.dot(d).max(0.0).powf(k);
    reject(
        "diffuse with pdf ∝ cos^1.1",
        &chi2(&outcomes, &hist, on_outcomes(wrong)),
    );
}

/// Diffuse + Phong at normal and at grazing incidence; rejects the lobe chosen by the
/// albedos' maximum channel, and, where the χ² can see it (the relative error `1/(ns+1)`
/// against the bins' noise), the BRDF's normalisation `(ns+2)/(2π)` in the pdf, else a lobe
/// exponent off by 5 % (which needs the lobe resolved by the bins).
fn check_glossy(ns: f32, seed: u64) {
    for (incidence, theta_o, seed) in [("normal", 0.0, seed), ("grazing", GRAZING, seed + 1)] {
        let v = Vertex::new(material(KD, KS, ns), theta_o);
        assert_model_is_the_pdf(&v);
        let name = format!("diffuse+Phong ns={ns} at {incidence} incidence");
        // A lobe as wide as ns = 10's is resolved by bins about the normal, which put the
        // horizon, where the lobe is cut, on a bin edge rather than across bins.
        let bins = if ns <= 10.0 {
            SphereBins::equal_area(v.nd(), 32, 32)
        } else {
            lobe_bins(v.lobe_axis(), ns as f64)
        };
        let (outcomes, hist) = check_brdf(&name, &v, bins, seed);
        let right = Model::of(&v.m);
        let max = |c: Vec3| c.max_element() as f64;
        let by_max = Model {
            p_diffuse: max(v.m.kd) / (max(v.m.kd) + max(v.m.ks)),
            ..right
        };
        reject_model(
            &format!("{name} with the lobe chosen by max channel"),
            &v,
            &outcomes,
            &hist,
            by_max,
        );
        if ns <= 100.0 {
            let brdf_norm = Model {
                norm: right.exponent + 2.0,
                ..right
            };
            reject_model(
                &format!("{name} with (ns+2)/(2π) in the pdf"),
                &v,
                &outcomes,
                &hist,
                brdf_norm,
            );
        } else {
            let e = 1.05 * right.exponent;
            let wider = Model {
                exponent: e,
                norm: e + 1.0,
                ..right
            };
            reject_model(
                &format!("{name} with exponent 1.05·ns"),
                &v,
                &outcomes,
                &hist,
                wider,
            );
        }
    }
}

#[test]
fn brdf_glossy_ns_10() {
    check_glossy(10.0, 42);
}

#[test]
fn brdf_glossy_ns_1000() {
    check_glossy(1000.0, 44);
}

#[test]
fn brdf_glossy_ns_10000() {
    check_glossy(1e4, 46);
}

/// Pure Phong at grazing incidence: ~4 % of the lobe lies below the surface, which the
/// "no direction" bin must account for.
#[test]
fn brdf_pure_phong_ns_100() {
    let v = Vertex::new(material(Vec3::ZERO, KS, 100.0), GRAZING);
    assert_model_is_the_pdf(&v);
    let name = "pure Phong ns=100 at grazing incidence";
    let (outcomes, hist) = check_brdf(name, &v, lobe_bins(v.lobe_axis(), 100.0), 48);
    let right = Model::of(&v.m);
    let brdf_norm = Model {
        norm: right.exponent + 2.0,
        ..right
    };
    reject_model(
        &format!("{name} with (ns+2)/(2π) in the pdf"),
        &v,
        &outcomes,
        &hist,
        brdf_norm,
    );
    // The rejected mass is part of the test: a pdf that dropped it (the lobe renormalised to
    // the upper hemisphere) must fail too.
    let below: f64 = (0..BELOW_RINGS * BELOW_SECTORS)
        .map(|b| {
            outcomes.below.integrate(b, &|d| {
                if d.dot(v.nd()) <= 0.0 {
                    v.pdf(*d)
                } else {
                    0.0
                }
            })
        })
        .sum();
    let renormalised = |d: DVec3| {
        if v.nd().dot(d) > 0.0 {
            v.pdf(d) / (1.0 - below)
        } else {
            0.0
        }
    };
    reject(
        &format!("{name} renormalised to the upper hemisphere"),
        &chi2(&outcomes, &hist, on_outcomes(renormalised)),
    );
}

// ---------------------------------------------------------------- χ² of a mixture

/// `Σ w_k p_k` at one vertex (design §5): the BRDF (diffuse + Phong ns = 100), a wide anchor
/// cone and a tiny one, each component picked with probability `w_k` by `u[0]`.
struct Mixture {
    v: Vertex,
    x: DVec3,
    anchors: [AnchorSampler; 2],
    w: [f64; 3],
}

impl Mixture {
    fn new() -> Self {
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
    fn sample(&self, u: [f64; 3]) -> Option<DVec3> {
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
    fn pdf_with(&self, w: [f64; 3], d: DVec3) -> f64 {
        w[0] * self.v.pdf(d)
            + w[1] * self.anchors[0].pdf(self.x, d)
            + w[2] * self.anchors[1].pdf(self.x, d)
    }

    fn pdf(&self, d: DVec3) -> f64 {
        self.pdf_with(self.w, d)
    }

    fn tiny_axis(&self) -> DVec3 {
        self.anchors[1].axis(self.x)
    }
}

#[test]
fn mixture_of_brdf_and_two_anchors() {
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
    accept(
        "mixture 0.3 BRDF + 0.5 anchor(0.2, 0.9) + 0.2 anchor(1e-3, 0.5)",
        &hist,
        &c,
    );
    reject(
        "mixture with weights summing to 1.05",
        &chi2(
            &outcomes,
            &hist,
            on_outcomes(|d| mix.pdf_with([0.3, 0.5, 0.25], d)),
        ),
    );
    reject(
        "mixture without the tiny cone's pdf",
        &chi2(
            &outcomes,
            &hist,
            on_outcomes(|d| mix.pdf_with([0.3, 0.5, 0.0], d)),
        ),
    );
}

// ---------------------------------------------------------------- χ² of the guided BSDF

/// A guided vertex (diffuse + Phong ns = 10, seen from 0.7 rad) under a [`Guide`] whose
/// first level mixes the BRDF (weight 0.4) with two anchor cones (0.35, 0.25), and whose
/// spatial field, trained at the vertex on records around one direction above the surface,
/// samples the level's BRDF share and, past the level, guides beside the BRDF alone.
struct Guided {
    v: Vertex,
    x: Vec3,
    guide: Guide,
}

impl Guided {
    fn new() -> Self {
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
    fn bsdf<'a>(&'a self, guide: &'a Guide, k: usize) -> GuidedBsdf<'a> {
        let bsdf = Bsdf {
            material: &self.v.m,
            n: self.v.n,
            wo: self.v.wo,
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
fn check_guided(name: &str, k: usize, samplers: usize, seed: u64) {
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
        assert!(!s.delta && bsdf.eval(s.wi) == brdf::eval(&g.v.m, g.v.n, g.v.wo, s.wi));
        Some(s.wi.as_dvec3().normalize()).filter(|d| d.dot(nd) > 0.0)
    };
    let pdf = |d: DVec3| bsdf.pdf(d.as_vec3());
    let (hist, c) = chi2_test(&outcomes, SAMPLES, seed, sample, on_outcomes(pdf));
    assert!(
        mismatched as u64 <= SAMPLES / 1000,
        "{name}: {mismatched} densities differ from pdf's"
    );
    accept(name, &hist, &c);
    let wrong = g.guide.clone().with_pdf_error(1.1);
    let wrong_bsdf = g.bsdf(&wrong, k);
    let wrong_pdf = |d: DVec3| wrong_bsdf.pdf(d.as_vec3());
    reject(
        &format!("{name} with the guide's densities × 1.1"),
        &chi2(&outcomes, &hist, on_outcomes(wrong_pdf)),
    );
}

#[cfg(feature = "testing")] // the must-reject twin scales the guide (a fault injection)
/// Level 0: the BRDF's share (itself half the spatial field's region), the two cones.
#[test]
fn guided_bsdf_with_anchor_cones_and_a_spatial_field() {
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
fn guided_bsdf_past_the_levels() {
    check_guided("guided BSDF past the levels: field 0.5, BRDF 0.5", 1, 1, 62);
}

// ---------------------------------------------------------------- ∫ pdf by quadrature

/// Gauss–Legendre nodes and weights on [-1, 1] (Newton on the Legendre recurrence).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let k = k as f64;
                    (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// A spherical cap, given by its unit axis and half-angle.
#[derive(Clone, Copy)]
struct Cap {
    axis: DVec3,
    half_angle: f64,
}

/// The upper hemisphere of the surface with normal `n`, as a cap: its edge is the horizon.
fn hemisphere(n: DVec3) -> Cap {
    Cap {
        axis: n,
        half_angle: FRAC_PI_2,
    }
}

/// `∫ f dω` over the sphere, for an `f` that is smooth except on the edges of `caps` and on
/// the rings `θ ∈ theta_splits` about `axis` (put a sharp lobe on `axis`). Polar coordinates
/// about `axis`: θ is cut into panels at the splits and where a ring touches a cap's edge,
/// each ring's φ into arcs where it crosses a cap's edge, so that every Gauss–Legendre panel
/// sees a smooth integrand; θ panels cluster their nodes at both ends, where an arc's length
/// grows like a square root. Shares nothing with the χ² harness or the samplers.
fn sphere_integral(
    f: impl Fn(DVec3) -> f64,
    axis: DVec3,
    theta_splits: &[f64],
    caps: &[Cap],
) -> f64 {
    const NODES: usize = 48;
    let nodes = gauss_legendre(NODES);
    let (t, b) = frame(axis);
    // Each cap's axis in polar coordinates (θa, φa), with its half-angle.
    let polar: Vec<(f64, f64, f64)> = caps
        .iter()
        .map(|c| {
            let (x, y, z) = (c.axis.dot(t), c.axis.dot(b), c.axis.dot(axis));
            (x.hypot(y).atan2(z), y.atan2(x), c.half_angle)
        })
        .collect();
    let mut edges = vec![0.0, PI];
    edges.extend_from_slice(theta_splits);
    for &(ta, _, tc) in &polar {
        edges.extend([(ta - tc).abs(), ta + tc, 2.0 * PI - ta - tc]);
    }
    edges.retain(|e| (0.0..=PI).contains(e));
    edges.sort_by(f64::total_cmp);
    edges.dedup_by(|a, b| (*a - *b).abs() < 1e-15);
    let gauss = |a: f64, b: f64, g: &dyn Fn(f64) -> f64| -> f64 {
        let half = 0.5 * (b - a);
        nodes
            .iter()
            .map(|&(x, w)| w * half * g(a + half * (1.0 + x)))
            .sum()
    };
    let ring = |theta: f64| -> f64 {
        let (st, ct) = theta.sin_cos();
        let mut cuts = vec![0.0, 2.0 * PI];
        for &(ta, pa, tc) in &polar {
            // The ring meets the cap's edge where d·a = cos θc.
            let arg = (tc.cos() - ct * ta.cos()) / (st * ta.sin());
            if arg.abs() < 1.0 {
                let half = arg.acos();
                cuts.extend([
                    (pa - half).rem_euclid(2.0 * PI),
                    (pa + half).rem_euclid(2.0 * PI),
                ]);
            }
        }
        cuts.sort_by(f64::total_cmp);
        let at = |phi: f64| {
            let (sp, cp) = phi.sin_cos();
            f(t * (st * cp) + b * (st * sp) + axis * ct)
        };
        st * cuts.windows(2).map(|w| gauss(w[0], w[1], &at)).sum::<f64>()
    };
    // θ = a + (b − a)(1 − cos πs)/2 over s ∈ [0, 1] turns √(θ − a) into sin(πs/2).
    let clustered = |a: f64, b: f64| {
        gauss(0.0, 1.0, &|s| {
            let theta = a + 0.5 * (b - a) * (1.0 - (PI * s).cos());
            ring(theta) * 0.5 * (b - a) * PI * (PI * s).sin()
        })
    };
    edges.windows(2).map(|w| clustered(w[0], w[1])).sum()
}

/// θ splits for a lobe `cos^ns` on the axis: at 1, 2, 4, … its width `1/√ns`, and at 90°
/// where it is cut off.
fn lobe_splits(ns: f64) -> Vec<f64> {
    let mut s: Vec<f64> = (0..6)
        .map(|k| (1 << k) as f64 / ns.sqrt())
        .filter(|&t| t < 3.0)
        .collect();
    s.push(FRAC_PI_2);
    s
}

/// For diffuse and diffuse + Phong at normal and grazing incidence, asserts:
/// * the quadrature is exact for the f64 model: `∫ model = 1` to 1e-12;
/// * `∫ brdf::pdf = 1` over the sphere, to 1e-7 (both lobes are normalised over the sphere);
/// * `∫ brdf::pdf` over the upper hemisphere `= 1 − P(Phong)·B` to 1e-7, `B` the mass of the
///   normalised lobe `(ns+1)/(2π) cos^ns` below the surface, integrated on its own from the
///   model (so the upper and lower parts add up to 1 from two different integrands);
/// * the same quadrature sees the `(ns+2)/(2π)` normalisation: `∫ = 1 + P(Phong)/(ns+1)`,
///   more than 100 × 1e-7 off even at ns = 1e4.
#[test]
fn brdf_pdf_integrates_to_one() {
    // `brdf::pdf` takes f32 directions: rounding one by 6e-8 rad moves `cos^ns` by up to
    // ~1e-5 relative at ns = 1e4, noise that leaves ~1e-8 on the integral (the f64 model's
    // integral is exact to 1e-13 with the same nodes).
    const TOL: f64 = 1e-7;
    const EXACT: f64 = 1e-12;
    let diffuse = Vertex::new(material(KD, Vec3::ZERO, 1.0), 0.7);
    let total = sphere_integral(
        |d| diffuse.pdf(d),
        diffuse.nd(),
        &[],
        &[hemisphere(diffuse.nd())],
    );
    println!("diffuse: ∫pdf − 1 = {:.2e}", total - 1.0);
    assert!((total - 1.0).abs() < TOL, "{total}");

    let mut checked_below = false;
    for (kd, ns) in [
        (KD, 10.0),
        (KD, 100.0),
        (KD, 1000.0),
        (KD, 1e4),
        (Vec3::ZERO, 100.0),
    ] {
        for theta_o in [0.0, GRAZING] {
            let v = Vertex::new(material(kd, KS, ns), theta_o);
            let model = Model::of(&v.m);
            let p_phong = 1.0 - model.p_diffuse;
            let (n, axis) = (v.nd(), v.lobe_axis());
            let splits = lobe_splits(ns as f64);
            let caps = [hemisphere(n)];
            let integral = |f: &dyn Fn(DVec3) -> f64| sphere_integral(f, axis, &splits, &caps);
            let exact = integral(&|d| model.pdf(&v, d));
            assert!((exact - 1.0).abs() < EXACT, "{exact}");
            let total = integral(&|d| v.pdf(d));
            let upper = integral(&|d| if n.dot(d) > 0.0 { v.pdf(d) } else { 0.0 });
            let lobe_below = integral(&|d| {
                if n.dot(d) <= 0.0 {
                    model.lobe(&v, d)
                } else {
                    0.0
                }
            });
            println!(
                "kd={kd} ns={ns} θo={theta_o:.3}: ∫pdf − 1 = {:.2e}, lobe mass below B = {lobe_below:.6e}, \
                 ∫upper − (1 − P·B) = {:.2e}",
                total - 1.0,
                upper - (1.0 - p_phong * lobe_below)
            );
            assert!((total - 1.0).abs() < TOL, "{total}");
            assert!(
                (upper - (1.0 - p_phong * lobe_below)).abs() < TOL,
                "{upper} {lobe_below}"
            );
            if theta_o == 0.0 {
                // About the normal the lobe's cut-off is the horizon: nothing below.
                assert!(lobe_below.abs() < EXACT, "{lobe_below}");
            } else if ns <= 100.0 {
                // Where the lobe does reach below, the check above is not vacuous.
                assert!(lobe_below > 1e-3, "{lobe_below}");
                checked_below = true;
            }
            let brdf_norm = Model {
                norm: model.exponent + 2.0,
                ..model
            };
            let wrong = integral(&|d| brdf_norm.pdf(&v, d));
            let expected = 1.0 + p_phong / (ns as f64 + 1.0);
            assert!(
                (wrong - expected).abs() < EXACT && expected - 1.0 > 100.0 * TOL,
                "{wrong}"
            );
        }
    }
    assert!(checked_below);
}

/// `∫ Σ w_k p_k = 1` over the sphere, to 1e-8, with every cone edge and the horizon cut out
/// of the quadrature's panels; the same quadrature sees weights summing to 1.05 and an
/// omitted component.
#[test]
fn mixture_pdf_integrates_to_one() {
    const TOL: f64 = 1e-8;
    let mix = Mixture::new();
    let caps = [
        hemisphere(mix.v.nd()),
        Cap {
            axis: mix.anchors[0].axis(mix.x),
            half_angle: mix.anchors[0].theta_c,
        },
        Cap {
            axis: mix.tiny_axis(),
            half_angle: mix.anchors[1].theta_c,
        },
    ];
    let splits = lobe_splits(mix.v.m.ns as f64);
    let integral =
        |w: [f64; 3]| sphere_integral(|d| mix.pdf_with(w, d), mix.v.lobe_axis(), &splits, &caps);
    let total = integral(mix.w);
    println!("mixture: ∫pdf − 1 = {:.2e}", total - 1.0);
    assert!((total - 1.0).abs() < TOL, "{total}");
    for (w, expected) in [
        ([0.3, 0.5, 0.25], 1.05),
        ([0.3, 0.5, 0.0], 0.8),
        ([0.0, 0.5, 0.2], 0.7),
    ] {
        let wrong = integral(w);
        assert!((wrong - expected).abs() < TOL, "{w:?}: {wrong}");
    }
}
