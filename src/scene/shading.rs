//! What shading reads at a surface point beyond its triangle: Mitsuba's per-vertex shading
//! normals and texture coordinates, interpolated with a hit's barycentrics.

use glam::{DVec3, Vec2, Vec3};

/// Per-vertex shading attributes, indexed like [`crate::accel::TriangleMesh::positions`].
/// Empty for a scene without any (every TOML scene): its triangles shade with their
/// geometric normals.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Shading {
    /// Unit shading normal of each vertex, world space; empty when no shape has any, zero
    /// for the vertices of shapes that shade flat (a triangle with a zero one shades flat).
    pub normals: Vec<Vec3>,
    /// Texture coordinates of each vertex; empty when no shape has any, `None` for the
    /// vertices of shapes without.
    pub uvs: Vec<Option<Vec2>>,
}

impl Shading {
    /// Appends a shape's `count` vertices with their attributes (where the shape has them),
    /// after the `before` vertices of the shapes appended so far.
    pub fn push_shape(
        &mut self,
        before: usize,
        count: usize,
        normals: Option<&[Vec3]>,
        uvs: Option<&[Option<Vec2>]>,
    ) {
        if let Some(n) = normals {
            self.normals.resize(before, Vec3::ZERO);
            self.normals.extend_from_slice(&n[..count]);
        } else if !self.normals.is_empty() {
            self.normals.resize(before + count, Vec3::ZERO);
        }
        if let Some(uv) = uvs {
            self.uvs.resize(before, None);
            self.uvs.extend_from_slice(&uv[..count]);
        } else if !self.uvs.is_empty() {
            self.uvs.resize(before + count, None);
        }
    }

    /// The shading normal of triangle `t` at barycentrics `(u, v)` (Embree's convention:
    /// `p = (1−u−v)·v0 + u·v1 + v·v2`): its vertex normals interpolated and normalised, as
    /// Mitsuba's `sh_frame.n`; `None` where the triangle shades flat.
    pub fn normal(&self, t: [u32; 3], u: f32, v: f32) -> Option<Vec3> {
        if self.normals.is_empty() {
            return None;
        }
        let [n0, n1, n2] = t.map(|i| self.normals[i as usize]);
        if n0 == Vec3::ZERO || n1 == Vec3::ZERO || n2 == Vec3::ZERO {
            return None;
        }
        let n = n0 + (n1 - n0) * u + (n2 - n0) * v;
        Some(n.normalize_or_zero()).filter(|n| *n != Vec3::ZERO)
    }

    /// The texture coordinates of triangle `t` at barycentrics `(u, v)`: its vertices'
    /// interpolated, or Mitsuba's default for a mesh without any, `(u, v)` itself.
    pub fn uv(&self, t: [u32; 3], u: f32, v: f32) -> Vec2 {
        match self.corner_uvs(t) {
            Some([a, b, c]) => a + (b - a) * u + (c - a) * v,
            None => Vec2::new(u, v),
        }
    }
}

/// Mitsuba's `dp_du` of a triangle with corners `p` (world space) and texture coordinates
/// `uvs` (`None` for a mesh without): from the texture coordinates, or, where they are
/// degenerate, the first axis of `coordinate_system(ng)`; `p1 − p0` without texture
/// coordinates (the barycentric parameterisation).
pub fn dp_du(p: [Vec3; 3], uvs: Option<[Vec2; 3]>, ng: Vec3) -> DVec3 {
    dp_duv(p, uvs, ng).0
}

/// Mitsuba's `dp_du` and `dp_dv` of a triangle (see [`dp_du`]): `p2 − p0` for `dp_dv`
/// without texture coordinates, the second axis of `coordinate_system(ng)` where they are
/// degenerate.
pub fn dp_duv(p: [Vec3; 3], uvs: Option<[Vec2; 3]>, ng: Vec3) -> (DVec3, DVec3) {
    let [p0, p1, p2] = p.map(|x| x.as_dvec3());
    let (dp0, dp1) = (p1 - p0, p2 - p0);
    let Some([uv0, uv1, uv2]) = uvs.map(|u| u.map(|x| x.as_dvec2())) else {
        return (dp0, dp1);
    };
    let (duv0, duv1) = (uv1 - uv0, uv2 - uv0);
    let det = duv0.x * duv1.y - duv0.y * duv1.x;
    if det == 0.0 {
        crate::math::basis(ng.as_dvec3())
    } else {
        (
            (duv1.y * dp0 - duv0.y * dp1) / det,
            (duv0.x * dp1 - duv1.x * dp0) / det,
        )
    }
}

/// Mitsuba's shading tangent `sh_frame.s`: `dp_du` made orthogonal to the unit shading
/// normal `ns` (Gram–Schmidt), or the first axis of `coordinate_system(ns)` where that
/// leaves nothing.
pub fn tangent(dp_du: DVec3, ns: Vec3) -> Vec3 {
    let n = ns.as_dvec3();
    let s = dp_du - n * n.dot(dp_du);
    let s = s.normalize_or_zero();
    if s == DVec3::ZERO {
        crate::math::basis(n).0.as_vec3()
    } else {
        s.as_vec3()
    }
}

impl Shading {
    /// The texture coordinates of triangle `t`'s corners, where its mesh has them.
    pub fn corner_uvs(&self, t: [u32; 3]) -> Option<[Vec2; 3]> {
        if self.uvs.is_empty() {
            return None;
        }
        let [a, b, c] = t.map(|i| self.uvs[i as usize]);
        Some([a?, b?, c?])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shading() -> Shading {
        let mut s = Shading::default();
        // A flat shape first, then one with normals and texture coordinates.
        s.push_shape(0, 3, None, None);
        assert!(s.normals.is_empty() && s.uvs.is_empty());
        let n = [Vec3::X, Vec3::Y, Vec3::Z];
        let uv = [Some(Vec2::ZERO), Some(Vec2::X), Some(Vec2::Y)];
        s.push_shape(3, 3, Some(&n), Some(&uv));
        s.push_shape(6, 3, None, None);
        assert_eq!((s.normals.len(), s.uvs.len()), (9, 9));
        s
    }

    #[test]
    fn normals_are_the_vertices_at_the_corners_and_interpolated_between() {
        let s = shading();
        let t = [3, 4, 5];
        assert_eq!(s.normal(t, 0.0, 0.0), Some(Vec3::X));
        assert_eq!(s.normal(t, 1.0, 0.0), Some(Vec3::Y));
        assert_eq!(s.normal(t, 0.0, 1.0), Some(Vec3::Z));
        let centre = s.normal(t, 1.0 / 3.0, 1.0 / 3.0).unwrap();
        assert!((centre - Vec3::ONE.normalize()).length() < 1e-6, "{centre}");
        let edge = s.normal(t, 0.5, 0.0).unwrap();
        assert!((edge - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
        // Flat shapes, before and after, and a triangle that mixes them.
        assert_eq!(s.normal([0, 1, 2], 0.2, 0.2), None);
        assert_eq!(s.normal([6, 7, 8], 0.2, 0.2), None);
        assert_eq!(s.normal([3, 4, 6], 0.2, 0.2), None);
        assert_eq!(Shading::default().normal([0, 1, 2], 0.2, 0.2), None);
    }

    #[test]
    fn opposite_normals_that_cancel_shade_flat() {
        let mut s = Shading::default();
        s.push_shape(0, 3, Some(&[Vec3::X, -Vec3::X, Vec3::X]), None);
        assert_eq!(s.normal([0, 1, 2], 0.5, 0.0), None);
    }

    #[test]
    fn texture_coordinates_are_interpolated_or_the_barycentrics() {
        let s = shading();
        let uv = s.uv([3, 4, 5], 0.25, 0.5);
        assert!((uv - Vec2::new(0.25, 0.5)).length() < 1e-7);
        let uv = s.uv([4, 5, 3], 0.25, 0.5);
        assert!((uv - Vec2::new(0.25, 0.25)).length() < 1e-7, "{uv}");
        assert_eq!(s.uv([0, 1, 2], 0.25, 0.5), Vec2::new(0.25, 0.5));
    }

    #[test]
    fn the_tangent_follows_u_and_is_orthogonal_to_the_normal() {
        // A triangle in the x–y plane whose u runs along y: dp/du = +y whatever the order.
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let uvs = [Vec2::ZERO, Vec2::Y, Vec2::X];
        let rotated = [1, 2, 0];
        for order in [[0, 1, 2], [0, 2, 1], rotated] {
            let d = dp_du(order.map(|i| p[i]), Some(order.map(|i| uvs[i])), Vec3::Z);
            assert!((d - DVec3::Y).length() < 1e-12, "{d}");
        }
        // Without texture coordinates: p1 − p0 and p2 − p0.
        assert_eq!(dp_du(p, None, Vec3::Z), DVec3::X);
        assert_eq!(dp_duv(p, None, Vec3::Z).1, DVec3::Y);
        // dp/dv: v runs along x here.
        let d = dp_duv(p, Some(uvs), Vec3::Z).1;
        assert!((d - DVec3::X).length() < 1e-12, "{d}");
        // A tilted shading normal: s is orthogonal to it, in the plane of n and dp/du.
        let ns = Vec3::new(0.0, 0.6, 0.8);
        let s = tangent(DVec3::Y, ns);
        assert!(s.dot(ns).abs() < 1e-6 && (s - Vec3::new(0.0, 0.8, -0.6)).length() < 1e-6);
        // Degenerate texture coordinates: Mitsuba's coordinate_system(ng).
        let flat = [Vec2::ZERO; 3];
        let d = dp_du(p, Some(flat), Vec3::Z);
        assert_eq!(d, crate::math::basis(DVec3::Z).0);
    }
}
