//! Statistical tests of the environment map's light sampling (`genpath::scene::envmap`,
//! Mitsuba's `envmap`): χ² of sampled directions against the map's own density, on a map
//! with a gradient and a small bright sun, turned by its `to_world`; each paired with
//! deliberately wrong densities that the same histogram must reject: the density without the
//! `sin θ` of the map's Jacobian (`du dv` taken for solid angle), and the density of the map
//! mirrored (`u → −u`, the direction mapping turned around). Run with
//! `cargo test --profile release-tests --test envmap` (`-- --nocapture` prints every statistic).

#[allow(dead_code)]
#[path = "../src/sampling/chi2.rs"]
mod chi2;

use chi2::{chi2, chi2_test, Family, SphereBins};
use genpath::scene::envmap::EnvMap;
use glam::{DMat3, DVec3, Vec3};

/// The χ² tests in this file that must accept.
const FAMILY: Family = Family { tests: 2 };
const SAMPLES: u64 = 4_000_000;
const W: usize = 16;
const H: usize = 9;

/// A sky brighter towards one side, a darker ground, and a sun of one texel 200 times
/// brighter than the sky.
fn texels() -> Vec<Vec3> {
    let mut t = Vec::with_capacity(W * H);
    for y in 0..H {
        for x in 0..W {
            let sky = 0.2 + 0.6 * x as f32 / W as f32;
            let c = if y < H / 2 { sky } else { 0.05 };
            t.push(Vec3::new(c, 0.9 * c, 0.7 * c + 0.02));
        }
    }
    t[2 * W + 11] = Vec3::splat(60.0);
    t
}

/// The map's frame: turned about an oblique axis.
fn frame() -> DMat3 {
    DMat3::from_axis_angle(DVec3::new(0.3, 1.0, -0.2).normalize(), 0.7)
}

fn check(to_world: DMat3, seed: u64, name: &str) {
    let map = EnvMap::new(W, H, texels(), to_world).unwrap();
    let up = to_world * DVec3::Y;
    let bins = SphereBins::equal_area(up, 32, 64);
    let (hist, c) = chi2_test(
        &bins,
        SAMPLES,
        seed,
        |u| map.sample([u[0], u[1]]).dir,
        |d| map.pdf(*d),
    );
    FAMILY.accept(name, &hist, &c);
    assert!(
        (c.pdf_total - 1.0).abs() < 1e-4,
        "{name}: ∫ pdf = {}",
        c.pdf_total
    );
    // In the map's frame `sin θ` is the length of the direction's part across its +y.
    let local = |d: &DVec3| to_world.transpose() * *d;
    let without_jacobian = |d: &DVec3| {
        let l = local(d);
        map.pdf(*d) * (1.0 - l.y * l.y).max(0.0).sqrt()
    };
    FAMILY.reject(
        &format!("{name} without the sin θ Jacobian"),
        &chi2(&bins, &hist, without_jacobian),
    );
    let mirrored = |d: &DVec3| {
        let l = local(d);
        map.pdf(to_world * DVec3::new(-l.x, l.y, l.z))
    };
    FAMILY.reject(&format!("{name} mirrored"), &chi2(&bins, &hist, mirrored));
}

#[test]
fn envmap_sampling_matches_its_density() {
    check(DMat3::IDENTITY, 71, "envmap");
}

#[test]
fn envmap_sampling_matches_its_density_when_turned() {
    check(frame(), 72, "envmap turned");
}
