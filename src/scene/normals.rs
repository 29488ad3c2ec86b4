//! Shading normals from a texture: Mitsuba 3's `normalmap` and `bumpmap` BSDF adapters
//! (`src/bsdfs/normalmap.cpp`, `bumpmap.cpp`, `normalmap_helpers.h` of Mitsuba 3.9.1).
//!
//! # How every method sees them
//!
//! A perturbed shading normal `np` is computed once per hit, where the hit becomes a
//! [`super::SurfacePoint`], from the material's [`Perturbation`] (kept beside its
//! textures, [`super::MaterialTextures::perturbation`]) and the hit's unperturbed shading
//! frame. Mitsuba then turns it per direction `wo` towards `wo` (its
//! `flip_invalid_normals`: the normal rotated by π about the unperturbed one where `wo` lies
//! on the other side of it), and a `twosided` around the map mirrors a `wo` behind the
//! surface first ([`resolve`]). The BSDF's `sampling::bsdf::Frame` carries the
//! result as its normal and the unperturbed normal beside it (`base`), and
//! `scene::material::bsdf` applies Mitsuba's two rules: nothing scatters into a `wi` on
//! different sides of the two normals, and what scatters is attenuated by the microfacet
//! shadowing term of Estévez et al., "A Microfacet-Based Shadowing Function to Solve the
//! Bump Terminator Problem" (Ray Tracing Gems, 2019; [`shadow_terminator`]). Every method
//! builds its frames through `Frame::facing` and looks materials up through
//! `SceneView::scattering_material`, so all of them (their own sampling, the densities of
//! other generators' paths, the guides' records) see the same perturbed BSDF.
//!
//! The densities stay those of the nested BSDF in the perturbed frame, where Mitsuba zeroes
//! them for the directions it refuses: those directions carry nothing, so both estimate the
//! same image, and genpath's densities stay the densities its samplers draw with.

use super::texture::{Bitmap, Texture};
use glam::{Vec2, Vec3};
use std::sync::Arc;

/// Where a perturbed shading normal comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum NormalSource {
    /// Mitsuba's `normalmap`: the texture's colour `c` gives the normal `2c − 1` in the
    /// unperturbed shading frame.
    NormalMap(Texture),
    /// Mitsuba's `bumpmap`: a height field, the luminance of a bitmap times `scale`, whose
    /// gradient in texture space tilts the surface.
    BumpMap { height: Arc<Bitmap>, scale: f32 },
}

/// A material's perturbed shading normals.
#[derive(Clone, Debug, PartialEq)]
pub struct Perturbation {
    pub source: NormalSource,
    /// Whether a `twosided` wraps the adapter (it then mirrors a `wo` behind the surface
    /// before the adapter reads it), rather than the adapter wrapping the BSDF, two-sided
    /// or not.
    pub twosided_outside: bool,
}

/// The differential geometry a perturbation reads at a hit (Mitsuba's `si`): the
/// unperturbed shading frame, the geometric normal and the texture parameterisation.
#[derive(Clone, Copy, Debug)]
pub struct HitFrame {
    /// Unit shading normal and tangent (`sh_frame.n`, `sh_frame.s`).
    pub ns: Vec3,
    pub ts: Vec3,
    /// Unit geometric normal (`si.n`).
    pub ng: Vec3,
    /// `dp/du` and `dp/dv` (world space).
    pub dp_du: Vec3,
    pub dp_dv: Vec3,
    pub uv: Vec2,
}

impl Perturbation {
    /// The perturbed unit shading normal at a hit (world space), before it is turned towards
    /// any `wo`. Zero where it is undefined (a zero normal-map colour `2c − 1`, or a bump
    /// whose tangents are parallel): callers then keep the unperturbed frame.
    pub fn normal(&self, h: &HitFrame) -> Vec3 {
        match &self.source {
            NormalSource::NormalMap(t) => {
                let n = t.eval(h.uv) * 2.0 - 1.0;
                let tt = h.ns.cross(h.ts);
                (h.ts * n.x + tt * n.y + h.ns * n.z).normalize_or_zero()
            }
            NormalSource::BumpMap { height, scale } => {
                let g = height.gradient(h.uv) * *scale;
                let du = h.dp_du + h.ns * (g.x - h.ns.dot(h.dp_du));
                let dv = h.dp_dv + h.ns * (g.y - h.ns.dot(h.dp_dv));
                let n = du.cross(dv).normalize_or_zero();
                // Turned to the geometric normal's side.
                if h.ng.dot(n) < 0.0 {
                    -n
                } else {
                    n
                }
            }
        }
    }
}

/// The perturbed normal `np` (unit, from [`Perturbation::normal`]) at a point whose
/// unperturbed shading normal is `ns`, as the BSDF seen from `wo` uses it: `(n, base)`, the
/// perturbed normal and the unperturbed one as the adapter's nested BSDF sees them. A
/// `twosided` outside the adapter mirrors both in the surface where `wo` is behind `ns`
/// (Mitsuba's twosided mirrors `wo`); then `n` is rotated by π about `base` where `wo` lies
/// on different sides of the two (Mitsuba's `flip_invalid_normals`).
pub fn resolve(ns: Vec3, np: Vec3, twosided_outside: bool, wo: Vec3) -> (Vec3, Vec3) {
    let (mut base, mut n) = (ns, np);
    if twosided_outside && ns.dot(wo) <= 0.0 {
        base = -ns;
        n = np - ns * (2.0 * ns.dot(np));
    }
    if base.dot(wo) * n.dot(wo) <= 0.0 {
        n = (base * (2.0 * base.dot(n)) - n).normalize();
    }
    (n, base)
}

/// `tan² θ` of unit `w` against unit `n` (Mitsuba's `Frame3f::tan_theta_2`).
fn tan2(n: Vec3, w: Vec3) -> f32 {
    let c = n.dot(w);
    (1.0 - c * c).max(0.0) / (c * c)
}

/// Mitsuba's `eval_shadow_terminator`: the shadowing of the perturbed normal `n` against the
/// unperturbed `base` for the light's direction `wi` (all unit), `2 / (1 + √(1 + α² tan² θ_i))`
/// with `α² = min(tan² θ_n / 8, 1)`.
pub fn shadow_terminator(n: Vec3, base: Vec3, wi: Vec3) -> f32 {
    let alpha2 = (0.125 * tan2(base, n)).min(1.0);
    2.0 / (1.0 + (1.0 + alpha2 * tan2(base, wi)).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flip_rotates_about_the_unperturbed_normal_and_the_mirror_reflects_in_the_surface() {
        let ns = Vec3::Z;
        let np = Vec3::new(0.6, 0.0, 0.8);
        // wo on the same side of both: unchanged.
        let wo = Vec3::new(0.0, 0.6, 0.8);
        assert_eq!(resolve(ns, np, false, wo), (np, ns));
        // wo above ns but below np: rotated by π about ns.
        let wo = Vec3::new(-0.9, 0.0, 0.1).normalize();
        let (n, base) = resolve(ns, np, false, wo);
        assert!((n - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6 && base == ns);
        // A twosided outside, wo behind: both mirrored, then the flip if needed.
        let wo = Vec3::new(0.0, 0.6, -0.8);
        let (n, base) = resolve(ns, np, true, wo);
        assert!((n - Vec3::new(0.6, 0.0, -0.8)).length() < 1e-6 && base == -ns);
        // Inside (or one-sided), wo behind ns and np: nothing changes.
        assert_eq!(resolve(ns, np, false, wo), (np, ns));
    }

    #[test]
    fn the_shadow_terminator_is_one_for_an_unperturbed_normal_and_falls_towards_grazing() {
        let n = Vec3::Z;
        assert_eq!(shadow_terminator(n, n, Vec3::new(0.6, 0.0, 0.8)), 1.0);
        let tilted = Vec3::new(0.6, 0.0, 0.8);
        let g = |wi: Vec3| shadow_terminator(tilted, n, wi.normalize());
        assert_eq!(g(Vec3::Z), 1.0);
        assert!(g(Vec3::new(1.0, 0.0, 1.0)) < 1.0);
        assert!(g(Vec3::new(1.0, 0.0, 0.1)) < g(Vec3::new(1.0, 0.0, 1.0)));
        // α² = tan²θ_n / 8 = (0.36 / 0.64) / 8; tan²θ_i = 1 at 45°.
        let alpha2 = 0.5625f32 / 8.0;
        let expected = 2.0 / (1.0 + (1.0 + alpha2).sqrt());
        assert!((g(Vec3::new(1.0, 0.0, 1.0)) - expected).abs() < 1e-6);
    }
}
