//! Where a ray meets a surface: the point, its frames and the per-hit numbers every BSDF
//! reads. Declared with the scene, below the samplers and the path layer that make and read
//! it, so that the BSDF code in `sampling` can take it without importing the path layer.

use glam::{Vec2, Vec3};

/// A surface point reached by a ray.
#[derive(Clone, Copy, Debug, Default)]
pub struct SurfacePoint {
    pub p: Vec3,
    /// Unit geometric normal as stored (`cross(v1 − v0, v2 − v0)`): emission leaves on its
    /// side, and rays leave off it.
    pub ng: Vec3,
    /// Unit shading normal (Mitsuba's `sh_frame.n`): the interpolated vertex normals, or
    /// `ng`. BSDFs scatter in its frame, and one-sided ones on its side.
    pub ns: Vec3,
    /// Unit shading tangent (Mitsuba's `sh_frame.s`, orthogonal to `ns`) where the material
    /// has an anisotropic lobe, which alone reads it; zero elsewhere.
    pub ts: Vec3,
    /// Texture coordinates (Mitsuba's `si.uv`) where the material is textured, which alone
    /// reads them; zero elsewhere.
    pub uv: Vec2,
    /// The unit shading normal of a normal or bump map (Mitsuba's `normalmap`, `bumpmap`),
    /// before it is turned towards any `wo` ([`super::normals`]); zero where the
    /// material has none (the BSDF then scatters about `ns`).
    pub np: Vec3,
    /// Whether a `twosided` wraps that map (see [`super::normals::resolve`]).
    pub np_twosided_outside: bool,
    /// On a smooth plastic, the uniform number that chooses its lobe at this hit
    /// ([`super::SmoothPlastic`]; drawn by the path layer's `SceneView::trace_through`, 0
    /// where its `SceneView::trace` made the point); 0 elsewhere.
    pub lobe_u: f32,
    pub prim: u32,
}

impl SurfacePoint {
    /// A point on a surface that shades flat (a light point: emitters shade flat).
    pub fn flat(p: Vec3, ng: Vec3, prim: u32) -> Self {
        Self {
            p,
            ng,
            ns: ng,
            ts: Vec3::ZERO,
            uv: Vec2::ZERO,
            np: Vec3::ZERO,
            np_twosided_outside: false,
            lobe_u: 0.0,
            prim,
        }
    }
}
