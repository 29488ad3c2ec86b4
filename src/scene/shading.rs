//! What shading reads at a surface point beyond its triangle: Mitsuba's per-vertex shading
//! normals and texture coordinates, interpolated with a hit's barycentrics.

use glam::{Vec2, Vec3};

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
        let corners = match self.uvs.is_empty() {
            true => None,
            false => t
                .map(|i| self.uvs[i as usize])
                .into_iter()
                .collect::<Option<Vec<_>>>(),
        };
        match corners.as_deref() {
            Some(&[a, b, c]) => a + (b - a) * u + (c - a) * v,
            _ => Vec2::new(u, v),
        }
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
}
