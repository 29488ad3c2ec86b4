//! The anchor-point sampler (paper §5.2): more directions inside a cone around the
//! direction to an anchor point, the rest uniformly over the remainder of the sphere.
//!
//! Densities are over the full sphere of directions in solid-angle measure, in `f64`:
//! `p1 = α/Ωc` inside the cone, `p2 = (1−α)/(4π−Ωc)` outside, with `Ωc = 4π sin²(θc/2)` and
//! `4π−Ωc = 4π cos²(θc/2)`. The usual `2π(1−cos θc)` cancels catastrophically for tiny cones
//! (it is exactly 0 in `f32` for θc = 1e-4), and its complement does for cones near π.
//! Directions are parameterised by `h = 1−cos θ` (the cap of height `h` has solid angle
//! `2πh`), sampled directly rather than through `cos θ`, for the same reason.

use crate::math::basis;
use glam::DVec3;
use std::f64::consts::PI;

/// Invalid parameters of an [`AnchorSampler`].
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum AnchorError {
    #[error("anchor point {0} is not finite")]
    Anchor(DVec3),
    #[error("cone half-angle {0} is not in (0, π)")]
    ConeAngle(f64),
    #[error("probability in the cone {0} is not in (0, 1)")]
    Alpha(f64),
}

/// A cone of half-angle `theta_c` around the direction from the shading point to `anchor`,
/// holding probability `alpha`; the rest of the sphere holds `1 − alpha` uniformly.
/// `p1 < p2` (a cone that is *avoided*) is allowed.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnchorSampler {
    /// A point on a surface that the cone aims at.
    pub anchor: DVec3,
    /// Cone half-angle in (0, π).
    pub theta_c: f64,
    /// Probability mass inside the cone, in (0, 1): both densities stay positive, so every
    /// direction can be sampled and the estimator stays unbiased.
    pub alpha: f64,
}

/// Solid angle of a cone of half-angle `theta_c`: `4π sin²(θc/2)`, accurate for tiny cones.
pub fn cone_solid_angle(theta_c: f64) -> f64 {
    let s = (0.5 * theta_c).sin();
    4.0 * PI * s * s
}

impl AnchorSampler {
    pub fn new(anchor: DVec3, theta_c: f64, alpha: f64) -> Result<Self, AnchorError> {
        if !anchor.is_finite() {
            return Err(AnchorError::Anchor(anchor));
        }
        if !(theta_c > 0.0 && theta_c < PI) {
            return Err(AnchorError::ConeAngle(theta_c));
        }
        if !(alpha > 0.0 && alpha < 1.0) {
            return Err(AnchorError::Alpha(alpha));
        }
        Ok(Self {
            anchor,
            theta_c,
            alpha,
        })
    }

    /// The cone axis seen from `from`. Where `from` coincides with the anchor the direction
    /// is undefined; the axis is then +z, so that `sample` and `pdf` still agree on one
    /// valid density.
    pub fn axis(&self, from: DVec3) -> DVec3 {
        (self.anchor - from).try_normalize().unwrap_or(DVec3::Z)
    }

    /// `(h_c, g_c)`: the extent in `h = 1 − cos θ` of the cone, `[0, h_c]`, and of the rest
    /// of the sphere measured from the antipode, `g = 2 − h ∈ [0, g_c]`. Both are computed
    /// from the half-angle so neither cancels: `h_c = 2 sin²(θc/2)`, `g_c = 2 cos²(θc/2)`.
    pub fn extents(&self) -> (f64, f64) {
        let (s, c) = (0.5 * self.theta_c).sin_cos();
        (2.0 * s * s, 2.0 * c * c)
    }

    /// `(p1, p2)`: the densities inside and outside the cone, per steradian.
    pub fn densities(&self) -> (f64, f64) {
        self.densities_with_extents(self.extents())
    }

    /// [`Self::densities`] with [`Self::extents`] computed by the caller.
    pub fn densities_with_extents(&self, (hc, gc): (f64, f64)) -> (f64, f64) {
        // Ωc = 2π h_c and 4π − Ωc = 2π g_c.
        (
            self.alpha / (2.0 * PI * hc),
            (1.0 - self.alpha) / (2.0 * PI * gc),
        )
    }

    /// A unit direction from three uniform numbers in [0, 1): `u[0]` picks the cone with
    /// probability α, `u[1]` the polar coordinate, `u[2]` the azimuth.
    pub fn sample(&self, from: DVec3, u: [f64; 3]) -> DVec3 {
        self.sample_with_extents(from, u, self.extents())
    }

    /// [`Self::sample`] with [`Self::extents`] computed by the caller: for callers that
    /// sample one cone many times, this saves a `sin_cos` per direction.
    pub fn sample_with_extents(&self, from: DVec3, u: [f64; 3], (hc, gc): (f64, f64)) -> DVec3 {
        let axis = self.axis(from);
        // Uniform in h (inside) or in g = 2 − h (outside) is uniform in solid angle. Outside,
        // g is drawn directly so that directions near the antipode keep their precision.
        let (cos_t, sin_t) = if u[0] < self.alpha {
            let h = u[1] * hc;
            (1.0 - h, (h * (2.0 - h)).sqrt())
        } else {
            let g = (1.0 - u[1]) * gc;
            (g - 1.0, (g * (2.0 - g)).sqrt())
        };
        let (sin_p, cos_p) = (2.0 * PI * u[2]).sin_cos();
        let (t, b) = basis(axis);
        (t * (sin_t * cos_p) + b * (sin_t * sin_p) + axis * cos_t).normalize()
    }

    /// Solid-angle density of [`sample`](Self::sample) for the unit direction `dir`.
    pub fn pdf(&self, from: DVec3, dir: DVec3) -> f64 {
        AnchorShape::new(self).pdf(from, dir)
    }

    /// Whether unit `dir` lies strictly inside the cone: its angle to the axis is below θc,
    /// tested by [`ConeTest`] without normalising the axis. It agrees with [`inside_cone`]:
    /// the angle `2·atan2(|d−a|, |d+a|)` against the unit axis `a`, tested as
    /// `|d−a|² < tan²(θc/2)·|d+a|²`; both stay accurate near 0 and near π, where
    /// `acos(d·a)` does not, and neither needs trigonometry per direction.
    pub fn inside(&self, from: DVec3, dir: DVec3) -> bool {
        ConeTest::new(self.tan2_half()).inside(self.anchor - from, dir)
    }

    /// `tan²(θc/2)`, the constant of [`Self::inside`].
    pub fn tan2_half(&self) -> f64 {
        let (hc, gc) = self.extents();
        hc / gc
    }
}

/// An anchor cone with the constants of its density, for repeated evaluations: the fitness
/// evaluates each generator's cones on every test path, and [`AnchorSampler::pdf`] would
/// spend a `sin_cos` on each.
#[derive(Clone, Copy, Debug)]
pub struct AnchorShape {
    anchor: DVec3,
    test: ConeTest,
    /// [`AnchorSampler::densities`] `(p1, p2)`.
    inside: f64,
    outside: f64,
}

impl AnchorShape {
    pub fn new(s: &AnchorSampler) -> Self {
        // One sin_cos gives the extents, the densities and tan²(θc/2) = h_c / g_c.
        let extents = s.extents();
        let (inside, outside) = s.densities_with_extents(extents);
        Self {
            anchor: s.anchor,
            test: ConeTest::new(extents.0 / extents.1),
            inside,
            outside,
        }
    }

    /// [`AnchorSampler::pdf`].
    #[inline]
    pub fn pdf(&self, from: DVec3, dir: DVec3) -> f64 {
        if self.test.inside(self.anchor - from, dir) {
            self.inside
        } else {
            self.outside
        }
    }
}

/// Whether unit `dir` is strictly inside the cone of unit `axis` whose half-angle θc has
/// `tan²(θc/2) = tan2_half`: the reference formulation, which [`ConeTest`] must agree with.
#[inline]
pub fn inside_cone(axis: DVec3, dir: DVec3, tan2_half: f64) -> bool {
    (dir - axis).length_squared() < tan2_half * (dir + axis).length_squared()
}

/// The cone test of [`AnchorSampler::inside`] without normalising the axis: the density
/// evaluations of guides and of the fitness spend much of their time in it. With
/// `d = anchor − from` of any length and unit `dir`, `dir·d = |d| cos α` and
/// `|dir × d| = |d| sin α` for the angle α between them, and `dir` is inside where
/// `tan² α < tan² θc` on the cone's side (`θc < π/2`), or anywhere but the opposite cone of
/// half-angle `π − θc` (`θc > π/2`). No square root, no division; the cross product keeps
/// directions near the axis (or its opposite) accurate, as `|d − a|` does in
/// [`inside_cone`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeTest {
    /// `tan² θc = 4t / (1 − t)²` for `t = tan²(θc/2)` (infinite at `θc = π/2`).
    tan2: f64,
    /// `θc > π/2`.
    wide: bool,
}

impl ConeTest {
    /// The test of the cone with `tan²(θc/2) = tan2_half`.
    pub fn new(tan2_half: f64) -> Self {
        let t = tan2_half;
        Self {
            tan2: 4.0 * t / ((1.0 - t) * (1.0 - t)),
            wide: t > 1.0,
        }
    }

    /// Whether unit `dir` is strictly inside the cone around `d = anchor − from`. Where `d`
    /// is zero (or too short or long to square), the axis is [`AnchorSampler::axis`]'s.
    #[inline]
    pub fn inside(&self, d: DVec3, dir: DVec3) -> bool {
        let l2 = d.length_squared();
        if !(l2 > 1e-150 && l2 < 1e150) {
            return self.inside_degenerate(d, dir);
        }
        self.test(d, dir)
    }

    /// [`Self::inside`] where `d` cannot be squared: around its direction, or +z.
    #[cold]
    fn inside_degenerate(&self, d: DVec3, dir: DVec3) -> bool {
        self.test(d.try_normalize().unwrap_or(DVec3::Z), dir)
    }

    #[inline(always)]
    fn test(&self, d: DVec3, dir: DVec3) -> bool {
        let c = dir.dot(d);
        let near_axis = dir.cross(d).length_squared() < self.tan2 * (c * c);
        if self.wide {
            c > 0.0 || !near_axis
        } else {
            c > 0.0 && near_axis
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solid_angle_is_stable_and_matches_the_cap_formula() {
        for theta in [0.3, 1.0, 2.5] {
            let cap = 2.0 * PI * (1.0 - f64::cos(theta));
            assert!(
                (cone_solid_angle(theta) - cap).abs() < 1e-12 * cap,
                "{theta}"
            );
        }
        // 4π sin²(θ/2) ≈ πθ² for tiny θ, where 1 − cos θ has no significant digit left.
        let theta: f64 = 1e-9;
        let small = PI * theta * theta;
        assert!((cone_solid_angle(theta) - small).abs() < 1e-12 * small);
        assert!((cone_solid_angle(PI) - 4.0 * PI).abs() < 1e-12);
    }

    #[test]
    fn rejects_invalid_parameters() {
        let a = DVec3::new(0.0, 1.0, 0.0);
        assert!(AnchorSampler::new(a, 0.3, 0.5).is_ok());
        assert_eq!(
            AnchorSampler::new(a, 0.0, 0.5),
            Err(AnchorError::ConeAngle(0.0))
        );
        assert_eq!(
            AnchorSampler::new(a, PI, 0.5),
            Err(AnchorError::ConeAngle(PI))
        );
        assert_eq!(
            AnchorSampler::new(a, 0.3, 1.0),
            Err(AnchorError::Alpha(1.0))
        );
        assert!(AnchorSampler::new(a, 0.3, f64::NAN).is_err());
        assert!(AnchorSampler::new(DVec3::splat(f64::INFINITY), 0.3, 0.5).is_err());
    }

    #[test]
    fn samples_land_on_the_chosen_side_even_for_extreme_cones() {
        let from = DVec3::new(0.3, -0.2, 0.1);
        let anchor = DVec3::new(-1.0, 2.0, 0.5);
        for theta_c in [1e-7, 1e-4, 1.0, PI - 1e-4, PI - 1e-7] {
            let s = AnchorSampler::new(anchor, theta_c, 0.5).unwrap();
            for i in 0..64 {
                // Stay away from the cone's edge, where rounding may pick either side.
                let v = 0.01 + 0.98 * (i as f64 + 0.5) / 64.0;
                let inside = s.sample(from, [0.25, v, v * 0.7]);
                let outside = s.sample(from, [0.75, v, v * 0.3]);
                assert!((inside.length() - 1.0).abs() < 1e-15 && s.inside(from, inside));
                assert!((outside.length() - 1.0).abs() < 1e-15 && !s.inside(from, outside));
            }
        }
    }

    /// `ConeTest` against the reference `inside_cone` on uniform directions and on directions
    /// near the cone's edge, for cones from tiny to nearly the whole sphere and axes of any
    /// length, zero (the +z fallback) and too short or long to square included: they may
    /// differ only within 1e-6 of the cone's smaller angular extent (θc or π − θc) of its
    /// edge. For every cone, a test built for one 0.1 % wider (in its smaller extent) must
    /// differ on directions drawn between the two edges.
    #[test]
    fn cone_test_agrees_with_the_reference_away_from_the_edge() {
        use rand::{Rng as _, SeedableRng};
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        let half_pi = 0.5 * PI;
        let cones = [
            1e-7,
            1e-4,
            0.3,
            1.0,
            half_pi - 1e-9,
            half_pi,
            half_pi + 1e-9,
            2.0,
        ];
        for theta_c in cones.into_iter().chain([PI - 1e-4, PI - 1e-7]) {
            let extent = theta_c.min(PI - theta_c);
            for length in [0.0, 1e-80, 1e-3, 1.0, 1e3, 1e80] {
                // From the origin, an anchor 1e-80 away is not rounded onto `from`.
                let from = match length < 1e-10 {
                    true => DVec3::ZERO,
                    false => DVec3::new(0.3, -0.2, 0.1),
                };
                let towards = DVec3::new(-1.3, 2.0, 0.5).normalize();
                let s = AnchorSampler::new(from + length * towards, theta_c, 0.5).unwrap();
                let axis = s.axis(from);
                assert_eq!(axis == DVec3::Z, length == 0.0);
                let (t, test) = (s.tan2_half(), ConeTest::new(s.tan2_half()));
                let wider = AnchorSampler::new(s.anchor, theta_c + 1e-3 * extent, 0.5).unwrap();
                let wrong = ConeTest::new(wider.tan2_half());
                let d = s.anchor - from;
                let mut wrong_differs = 0;
                for i in 0..4000 {
                    // Uniform directions; directions inside and outside the cone, within a
                    // few θc of its axis (or of its opposite), where a tiny cone's edge lies;
                    // and directions just inside the wider cone's edge.
                    let u = [rng.random::<f64>(), rng.random::<f64>()];
                    let dir = match i % 4 {
                        0 => {
                            let z = 2.0 * u[0] - 1.0;
                            let r = (1.0 - z * z).sqrt();
                            let phi = 2.0 * PI * u[1];
                            DVec3::new(r * phi.cos(), r * phi.sin(), z)
                        }
                        1 => s.sample(from, [0.0, 0.999 * u[0], u[1]]),
                        2 => s.sample(from, [0.9, 0.999 * u[0], u[1]]),
                        // The band between the two edges: inside the wider cone near its
                        // edge or, for a wide cone, outside this one near its edge (there
                        // `sample` measures from the antipode).
                        _ if theta_c <= half_pi => {
                            wider.sample(from, [0.0, 0.9999 + 1e-4 * u[0], u[1]])
                        }
                        _ => s.sample(from, [0.9, 1e-3 * u[0], u[1]]),
                    };
                    let angle = dir.cross(axis).length().atan2(dir.dot(axis));
                    let got = test.inside(d, dir);
                    if (angle - theta_c).abs() > 1e-6 * extent {
                        assert_eq!(got, angle < theta_c, "θc {theta_c}, |d| {length}: {dir}");
                        assert_eq!(got, inside_cone(axis, dir, t), "θc {theta_c}: {dir}");
                    }
                    wrong_differs += usize::from(wrong.inside(d, dir) != got);
                }
                assert!(
                    wrong_differs > 100,
                    "θc {theta_c}, |d| {length}: a 0.1 % wider cone told apart {wrong_differs} times"
                );
            }
        }
    }

    #[test]
    fn coincident_anchor_uses_the_z_axis() {
        let p = DVec3::new(0.5, 0.5, 0.5);
        let s = AnchorSampler::new(p, 0.2, 0.9).unwrap();
        assert_eq!(s.axis(p), DVec3::Z);
        let (p1, p2) = s.densities();
        assert_eq!(s.pdf(p, DVec3::Z), p1);
        assert_eq!(s.pdf(p, -DVec3::Z), p2);
    }
}
