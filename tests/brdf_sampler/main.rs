//! Statistical tests of the BRDF sampler, of a mixture of samplers at one vertex (design §4,
//! §5, §10) and of the renderer's guided BSDF (`genpath::guiding::GuidedBsdf`): χ² of sample
//! histograms against the densities the renderer evaluates, each paired with deliberately
//! wrong densities that the same histogram must reject; and `∫ pdf` by quadrature that does
//! not use the samplers; Mitsuba's smooth `plastic` against Mitsuba's values (`plastic`).
//! Run with `cargo test --profile release-tests --test brdf_sampler` (`-- --nocapture` prints every statistic).
//!
//! The outcome of a draw: `bsdf::pdf` is the density, over the full sphere, of the direction
//! the sampler *generates*; the Phong lobe about the mirror direction can put some of it below
//! the surface, and `bsdf::sample` returns `None` for those draws (they carry no energy). The
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
#[path = "../../src/sampling/chi2.rs"]
mod chi2;
mod guided;
mod microfacet;
mod mixture;
mod plastic;
mod quadrature;
mod roughdielectric;
mod vertex;

use chi2::{chi2, chi2_test, Binning, Family, Histogram, SphereBins};
use genpath::guiding::lattice::facing;
use genpath::guiding::square::to_square;
use genpath::guiding::{Guide, GuidedBsdf, Record, SpatialField};
use genpath::math::gauss_legendre;
use genpath::path::generator::{DirectionSampler, PathGenerator, Step};
use genpath::path::mixture::Mixture as GenMixture;
use genpath::path::pt::{Bsdf, PathGuide, VertexBsdf};
use genpath::sampling::anchor::AnchorSampler;
use genpath::sampling::light_point::LightPointSampler;
use genpath::sampling::{sample_rng, uniform};
use genpath::scene::material::bsdf::{self, Frame};
use genpath::scene::{Glossy, Material};
use glam::{DVec3, Vec3};
use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::Arc;

/// The χ² tests in this binary that must accept (11 here and in its modules, 10 in
/// `microfacet`, 5 in `roughdielectric`, 2 in `plastic`).
const FAMILY: Family = Family { tests: 28 };
const SAMPLES: u64 = 4_000_000;

use vertex::*;

#[test]
fn brdf_diffuse() {
    let v = Vertex::new(material(KD, Vec3::ZERO, 1.0), 0.7);
    let (outcomes, hist) = check_brdf("diffuse", &v, SphereBins::equal_area(v.nd(), 16, 32), 41);
    assert_eq!(hist.counts[outcomes.above.bins()], 0, "diffuse rejections");
    // A normalised density of the wrong shape: ∝ cos^1.1 instead of cos.
    let n = v.nd();
    let k = 1.1;
    let wrong = |d: DVec3| (k + 1.0) / (2.0 * PI) * n.dot(d).max(0.0).powf(k);
    FAMILY.reject(
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
            p_diffuse: max(v.m.kd) / (max(v.m.kd) + max(phong(&v.m).0)),
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
            reject_brdf_normalisation(&name, &v, &outcomes, &hist, right);
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
    reject_brdf_normalisation(name, &v, &outcomes, &hist, Model::of(&v.m));
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
    FAMILY.reject(
        &format!("{name} renormalised to the upper hemisphere"),
        &chi2(&outcomes, &hist, on_outcomes(renormalised)),
    );
}
