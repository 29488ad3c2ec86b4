//! The patch sampler (beyond the paper): more directions towards a parallelogram in space,
//! the rest uniformly over the sphere.
//!
//! The paper's anchor cones are circular. Light often arrives from a long, thin region: on
//! fig5, a floor point sees the lit top of each side wall as a band a few degrees high and
//! up to 160° wide, which no cone covers without also covering a much larger unlit part.
//! A patch is a parallelogram `c + s·u + r·v`, `s, r ∈ [−1, 1]`; with probability `α` the
//! sampler picks a point on it uniformly by area and returns the direction to it, otherwise
//! a direction uniform over the sphere. In solid angle, with `t` the distance to the
//! patch's plane along `ω` and `n = u × v`:
//!
//! ```text
//! p(ω) = α · [ω meets the patch] · t² / (4 |n · ω|) + (1 − α) / 4π
//! ```
//!
//! (area density `1/A`, `A = 4|n|`, times `t²/|cos θ|`, `cos θ = n·ω / |n|`). The uniform
//! part keeps every direction possible, so the estimator stays unbiased, as the cone's
//! outside density does.

use glam::DVec3;
use std::f64::consts::PI;

/// Invalid parameters of a [`PatchSampler`].
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum PatchError {
    #[error("patch centre {0} is not finite")]
    Center(DVec3),
    #[error("patch edges {0} and {1} are not finite, or span no area")]
    Edges(DVec3, DVec3),
    #[error("probability on the patch {0} is not in (0, 1)")]
    Alpha(f64),
}

/// A parallelogram `center + s·half_u + r·half_v` (`s, r ∈ [−1, 1]`) holding probability
/// `alpha`; the rest of the sphere holds `1 − alpha` uniformly.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PatchSampler {
    pub center: DVec3,
    /// Half of one pair of edges.
    pub half_u: DVec3,
    /// Half of the other pair; not parallel to `half_u`.
    pub half_v: DVec3,
    /// Probability mass on the patch, in (0, 1).
    pub alpha: f64,
}

/// The uniform density over the sphere, `1/4π`.
const UNIFORM: f64 = 0.25 / PI;

/// A unit direction uniform over the sphere from two uniform numbers.
fn uniform_sphere(u1: f64, u2: f64) -> DVec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * u2).sin_cos();
    DVec3::new(r * c, r * s, z)
}

impl PatchSampler {
    pub fn new(
        center: DVec3,
        half_u: DVec3,
        half_v: DVec3,
        alpha: f64,
    ) -> Result<Self, PatchError> {
        if !center.is_finite() {
            return Err(PatchError::Center(center));
        }
        let n = half_u.cross(half_v);
        // Edges much more nearly parallel than this leave the in-plane coordinates
        // ill-conditioned.
        let spans = n.length() > 1e-9 * half_u.length() * half_v.length();
        if !(half_u.is_finite() && half_v.is_finite() && n.is_finite() && spans) {
            return Err(PatchError::Edges(half_u, half_v));
        }
        if !(alpha > 0.0 && alpha < 1.0) {
            return Err(PatchError::Alpha(alpha));
        }
        Ok(Self {
            center,
            half_u,
            half_v,
            alpha,
        })
    }

    /// The patch's area, `4 |half_u × half_v|`.
    pub fn area(&self) -> f64 {
        4.0 * self.half_u.cross(self.half_v).length()
    }

    /// A unit direction from three uniform numbers in [0, 1): `u[0]` picks the patch with
    /// probability α, `u[1]`, `u[2]` the point on it (or the uniform direction).
    pub fn sample(&self, from: DVec3, u: [f64; 3]) -> DVec3 {
        if u[0] < self.alpha {
            let p =
                self.center + (2.0 * u[1] - 1.0) * self.half_u + (2.0 * u[2] - 1.0) * self.half_v;
            // `from` on the sampled point itself (probability 0): any direction will do.
            if let Some(d) = (p - from).try_normalize() {
                return d;
            }
        }
        uniform_sphere(u[1], u[2])
    }

    /// Solid-angle density of [`sample`](Self::sample) for the unit direction `dir`.
    pub fn pdf(&self, from: DVec3, dir: DVec3) -> f64 {
        PatchShape::new(self).pdf(from, dir)
    }
}

/// A patch with the constants of its density, for repeated evaluations: the guide evaluates
/// each of its patches twice per vertex.
#[derive(Clone, Copy, Debug)]
pub struct PatchShape {
    pub sampler: PatchSampler,
    /// `half_u × half_v`, not normalised.
    n: DVec3,
    /// Rows of the inverse Gram matrix of the edges, mapping `(q·u, q·v)` to `(s, r)`.
    to_s: (f64, f64),
    to_r: (f64, f64),
    /// The uniform part `(1 − α)/4π`.
    outside: f64,
}

impl PatchShape {
    pub fn new(p: &PatchSampler) -> Self {
        let (u, v) = (p.half_u, p.half_v);
        let (uu, uv, vv) = (u.dot(u), u.dot(v), v.dot(v));
        // det = |u × v|², positive for a valid patch.
        let det = uu * vv - uv * uv;
        Self {
            sampler: *p,
            n: u.cross(v),
            to_s: (vv / det, -uv / det),
            to_r: (-uv / det, uu / det),
            outside: (1.0 - p.alpha) * UNIFORM,
        }
    }

    /// The patch part's density `t²/(4|n·ω|)` where the ray from `from` along unit `dir`
    /// meets the patch, 0 where it does not.
    #[inline]
    pub fn patch_density(&self, from: DVec3, dir: DVec3) -> f64 {
        let p = &self.sampler;
        let dn = self.n.dot(dir);
        let t = self.n.dot(p.center - from) / dn;
        // A ray in the plane (dn = 0) gives ±∞ or NaN: not a hit.
        if !(t > 0.0 && t.is_finite()) {
            return 0.0;
        }
        let q = from + t * dir - p.center;
        let (qu, qv) = (q.dot(p.half_u), q.dot(p.half_v));
        let s = self.to_s.0 * qu + self.to_s.1 * qv;
        let r = self.to_r.0 * qu + self.to_r.1 * qv;
        if s.abs() <= 1.0 && r.abs() <= 1.0 {
            t * t / (4.0 * dn.abs())
        } else {
            0.0
        }
    }

    /// [`PatchSampler::pdf`].
    #[inline]
    pub fn pdf(&self, from: DVec3, dir: DVec3) -> f64 {
        self.sampler.alpha * self.patch_density(from, dir) + self.outside
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_invalid_parameters() {
        let (c, u, v) = (DVec3::ZERO, DVec3::X, DVec3::Z);
        assert!(PatchSampler::new(c, u, v, 0.5).is_ok());
        assert!(matches!(
            PatchSampler::new(DVec3::NAN, u, v, 0.5),
            Err(PatchError::Center(_))
        ));
        assert!(matches!(
            PatchSampler::new(c, u, 2.0 * u, 0.5),
            Err(PatchError::Edges(..))
        ));
        assert!(matches!(
            PatchSampler::new(c, u, DVec3::ZERO, 0.5),
            Err(PatchError::Edges(..))
        ));
        assert!(matches!(
            PatchSampler::new(c, DVec3::splat(f64::INFINITY), v, 0.5),
            Err(PatchError::Edges(..))
        ));
        for alpha in [0.0, 1.0, f64::NAN] {
            assert!(matches!(
                PatchSampler::new(c, u, v, alpha),
                Err(PatchError::Alpha(_))
            ));
        }
    }

    #[test]
    fn sampled_directions_meet_the_patch() {
        // A skewed parallelogram; every patch-part sample must get the patch density.
        let p = PatchSampler::new(
            DVec3::new(0.0, 2.0, 0.0),
            DVec3::new(1.0, 0.0, 0.2),
            DVec3::new(0.3, 0.1, 0.5),
            0.9,
        )
        .unwrap();
        let shape = PatchShape::new(&p);
        let from = DVec3::new(0.2, 0.0, -0.1);
        let mut hits = 0;
        for i in 0..1000 {
            // Points on a grid inside the patch, edges excluded (they hold no area).
            let u = [
                0.5 * (i % 10) as f64 / 10.0,
                (0.5 + (i / 10 % 10) as f64) / 10.0,
                (0.5 + (i / 100) as f64) / 10.0,
            ];
            let d = p.sample(from, u);
            assert!((d.length() - 1.0).abs() < 1e-12);
            hits += usize::from(shape.patch_density(from, d) > 0.0);
        }
        assert_eq!(hits, 1000);
    }
}
