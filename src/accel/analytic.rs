//! Analytic shapes (Mitsuba's `sphere` and `disk`): their ray intersection, area and uniform
//! area sampling, in `f64`. Both back-ends answer them with the same routine
//! ([`AnalyticShapes`]), after their triangle traversal, so their answers on them are
//! identical by construction. They are tested one after another, not inside a BVH: scenes
//! hold a handful of them (thousands would want a BVH of their own).

use super::{Hit, Ray};
use glam::{DAffine3, DMat3, DVec3};
use std::f64::consts::PI;

/// A sphere or a disk, placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub enum Analytic {
    /// The sphere of `radius` around `center`; its normal points outwards, or inwards where
    /// `flip` (Mitsuba's `flip_normals`).
    Sphere {
        center: DVec3,
        radius: f64,
        flip: bool,
        /// The inverse of `to_world`'s linear part (identity for an unturned sphere): the
        /// texture coordinates are the local direction's spherical angles, as Mitsuba's.
        to_local: DMat3,
    },
    /// The unit disk `x² + y² ≤ 1, z = 0` placed by an affine `to_world` (an ellipse in
    /// general): `frame` maps local `(x, y, z)` to `center + x·axis_u + y·axis_v + z·normal`,
    /// `to_local` is its inverse, `normal` the unit world normal (Mitsuba's: the inverse
    /// transpose of `to_world` applied to `+z`, negated for `flip_normals`).
    Disk {
        frame: DAffine3,
        to_local: DAffine3,
        normal: DVec3,
    },
}

/// Why an analytic shape cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AnalyticError {
    #[error("radius {0} is not a positive finite number")]
    Radius(f64),
    #[error("center {0} is not finite")]
    Center(DVec3),
    #[error(
        "`to_world` maps the disk to a point or a segment (its x and y axes are parallel or zero)"
    )]
    DegenerateDisk,
    #[error("`to_world` is not finite")]
    NotFinite,
}

impl Analytic {
    pub fn sphere(center: DVec3, radius: f64, flip: bool) -> Result<Self, AnalyticError> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(AnalyticError::Radius(radius));
        }
        if !center.is_finite() {
            return Err(AnalyticError::Center(center));
        }
        Ok(Analytic::Sphere {
            center,
            radius,
            flip,
            to_local: DMat3::IDENTITY,
        })
    }

    /// A sphere turned by the linear part `linear` of its `to_world` (whose texture
    /// coordinates it turns; the shape itself is the same); a disk as it is.
    pub fn turned(self, linear: DMat3) -> Result<Self, AnalyticError> {
        match self {
            Analytic::Sphere {
                center,
                radius,
                flip,
                ..
            } => {
                let to_local = linear.inverse();
                if !(to_local.is_finite() && linear.determinant() != 0.0) {
                    return Err(AnalyticError::NotFinite);
                }
                Ok(Analytic::Sphere {
                    center,
                    radius,
                    flip,
                    to_local,
                })
            }
            disk => Ok(disk),
        }
    }

    /// Mitsuba's disk placed by `to_world` (only its action on the `z = 0` plane and on
    /// normals matters).
    pub fn disk(to_world: DAffine3, flip: bool) -> Result<Self, AnalyticError> {
        let m = to_world.matrix3;
        if !(m.is_finite() && to_world.translation.is_finite()) {
            return Err(AnalyticError::NotFinite);
        }
        let (u, v) = (m.x_axis, m.y_axis);
        let cross = u.cross(v);
        let scale = u.length() * v.length();
        if !(cross.length() > 1e-12 * scale && scale > 0.0 && cross.is_finite()) {
            return Err(AnalyticError::DegenerateDisk);
        }
        // Mitsuba's normal: the inverse transpose applied to +z, which is along u × v
        // (both are orthogonal to it) with the sign of the z column's side.
        let mut normal = cross.normalize();
        if m.determinant() < 0.0 {
            normal = -normal;
        }
        if flip {
            normal = -normal;
        }
        // Local z along the normal: invertible whatever the z column of `to_world` is.
        let frame =
            DAffine3::from_mat3_translation(DMat3::from_cols(u, v, normal), to_world.translation);
        Ok(Analytic::Disk {
            frame,
            to_local: frame.inverse(),
            normal,
        })
    }

    /// Surface area.
    pub fn area(&self) -> f64 {
        match self {
            Analytic::Sphere { radius, .. } => 4.0 * PI * radius * radius,
            Analytic::Disk { frame, .. } => {
                PI * frame.matrix3.x_axis.cross(frame.matrix3.y_axis).length()
            }
        }
    }

    /// The unit geometric normal at `p`, a point on the shape.
    pub fn normal_at(&self, p: DVec3) -> DVec3 {
        match self {
            Analytic::Sphere { center, flip, .. } => {
                let n = (p - *center).normalize_or_zero();
                if *flip {
                    -n
                } else {
                    n
                }
            }
            Analytic::Disk { normal, .. } => *normal,
        }
    }

    /// The point of the shape nearest to `p` (for a disk, in its local coordinates).
    pub fn project(&self, p: DVec3) -> DVec3 {
        match self {
            Analytic::Sphere { center, radius, .. } => {
                let d = (p - *center).try_normalize().unwrap_or(DVec3::Z);
                *center + d * *radius
            }
            Analytic::Disk {
                frame, to_local, ..
            } => {
                let l = to_local.transform_point3(p);
                let (x, y) = (l.x, l.y);
                let r = (x * x + y * y).sqrt();
                let s = if r > 1.0 { 1.0 / r } else { 1.0 };
                frame.transform_point3(DVec3::new(x * s, y * s, 0.0))
            }
        }
    }

    /// Two unit tangents at `p`, a point on the shape.
    pub fn tangents(&self, p: DVec3) -> (DVec3, DVec3) {
        orthonormal_basis(self.normal_at(p))
    }

    /// A point uniform by area from two uniform numbers in [0, 1).
    pub fn sample_area(&self, u1: f64, u2: f64) -> DVec3 {
        match self {
            Analytic::Sphere { center, radius, .. } => *center + uniform_sphere(u1, u2) * *radius,
            Analytic::Disk { frame, .. } => {
                // An affine map keeps a uniform density uniform.
                let (x, y) = concentric_disk(u1, u2);
                frame.transform_point3(DVec3::new(x, y, 0.0))
            }
        }
    }

    /// The cone of directions in which a sphere is seen from `x`, where `x` lies clearly
    /// outside it (by 1e-3 of its radius: from a point on the sphere the cone degenerates
    /// to a half-space, and area sampling serves as well); `None` otherwise, and for a disk.
    pub fn visible_cone(&self, x: DVec3) -> Option<SphereCone> {
        let Analytic::Sphere { center, radius, .. } = *self else {
            return None;
        };
        let to_center = center - x;
        let dist2 = to_center.length_squared();
        // Also `None` for a NaN.
        if dist2.partial_cmp(&(radius * (1.0 + 1e-3)).powi(2)) != Some(std::cmp::Ordering::Greater)
        {
            return None;
        }
        let dist = dist2.sqrt();
        let sin2_max = radius * radius / dist2;
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        Some(SphereCone {
            center,
            radius,
            axis: to_center / dist,
            sin_max: radius / dist,
            // 1 − cos θmax without cancellation for small cones.
            one_minus_cos_max: sin2_max / (1.0 + cos_max),
        })
    }

    /// Axis-aligned bounds.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        match self {
            Analytic::Sphere { center, radius, .. } => (
                *center - DVec3::splat(*radius),
                *center + DVec3::splat(*radius),
            ),
            Analytic::Disk { frame, .. } => {
                let (u, v) = (frame.matrix3.x_axis, frame.matrix3.y_axis);
                let half = (u * u + v * v).map(f64::sqrt);
                (frame.translation - half, frame.translation + half)
            }
        }
    }

    /// The closest crossing of `ray` with the shape in `(tmin, tmax)`: `t`, the unit
    /// geometric normal and a surface parameterisation `(u, v)` (Mitsuba's: the sphere's
    /// `(φ/2π, θ/π)` of the local direction (`to_local` applied), the disk's `(r, φ/2π)`).
    pub fn intersect(&self, ray: &Ray, tmax: f64) -> Option<(f64, DVec3, f64, f64)> {
        let t = self.crossing(ray, tmax)?;
        let (n, u, v) = self.surface(ray, t);
        Some((t, n, u, v))
    }

    /// The `t` of [`Self::intersect`] alone: what shadow rays and the search for the
    /// closest shape need, without the normal and the `atan2`/`acos` of the
    /// parameterisation, which [`Self::surface`] computes for the one crossing kept.
    pub fn crossing(&self, ray: &Ray, tmax: f64) -> Option<f64> {
        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        let tmin = f64::from(ray.tmin);
        match self {
            Analytic::Sphere { center, radius, .. } => {
                sphere_crossing(o - *center, d, *radius, tmin, tmax)
            }
            Analytic::Disk { to_local, .. } => {
                let (lo, ld) = (to_local.transform_point3(o), to_local.transform_vector3(d));
                if ld.z == 0.0 {
                    return None;
                }
                let t = -lo.z / ld.z;
                if !(t > tmin && t < tmax) {
                    return None;
                }
                let (x, y) = (lo.x + t * ld.x, lo.y + t * ld.y);
                if x * x + y * y > 1.0 {
                    return None;
                }
                Some(t)
            }
        }
    }

    /// The unit geometric normal and `(u, v)` of [`Self::intersect`] where `ray` crosses
    /// the shape at `t` (a [`Self::crossing`]).
    pub fn surface(&self, ray: &Ray, t: f64) -> (DVec3, f64, f64) {
        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        match self {
            Analytic::Sphere {
                center,
                radius,
                flip,
                to_local,
            } => {
                let local = o - *center + d * t;
                let n = local / *radius;
                let n = n.normalize_or_zero();
                let l = (*to_local * n).normalize_or_zero();
                let phi = l.y.atan2(l.x);
                let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
                let (u, v) = (phi / (2.0 * PI), l.z.clamp(-1.0, 1.0).acos() / PI);
                (if *flip { -n } else { n }, u, v)
            }
            Analytic::Disk {
                to_local, normal, ..
            } => {
                let (lo, ld) = (to_local.transform_point3(o), to_local.transform_vector3(d));
                let (x, y) = (lo.x + t * ld.x, lo.y + t * ld.y);
                let phi = y.atan2(x);
                let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
                (*normal, (x * x + y * y).sqrt(), phi / (2.0 * PI))
            }
        }
    }
}

/// The directions towards a sphere from a point outside it (Mitsuba's
/// `Sphere::sample_direction`, after Akalin's "Sampling the visible sphere"), sampled
/// uniformly in solid angle as points on the visible cap.
#[derive(Clone, Copy, Debug)]
pub struct SphereCone {
    center: DVec3,
    radius: f64,
    /// Unit direction from the reference point to the centre.
    axis: DVec3,
    sin_max: f64,
    one_minus_cos_max: f64,
}

impl SphereCone {
    /// The point of the sphere first met in a direction uniform in the cone.
    pub fn sample(&self, u1: f64, u2: f64) -> DVec3 {
        // cos θ uniform in [cos θmax, 1], as 1 − cos θ = h·u1.
        let h = self.one_minus_cos_max * u1;
        let cos_theta = 1.0 - h;
        let sin2_theta = h * (2.0 - h);
        // The angle α at the centre between the axis (towards the reference point) and the
        // point where that direction meets the sphere.
        let ratio = sin2_theta / (self.sin_max * self.sin_max);
        let cos_alpha = sin2_theta / self.sin_max + cos_theta * (1.0 - ratio).max(0.0).sqrt();
        let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
        let phi = 2.0 * PI * u2;
        let (t, b) = orthonormal_basis(-self.axis);
        let n = t * (phi.cos() * sin_alpha) + b * (phi.sin() * sin_alpha) - self.axis * cos_alpha;
        self.center + n * self.radius
    }

    /// The solid-angle density of [`Self::sample`]'s directions: `1 / (2π (1 − cos θmax))`.
    pub fn pdf_solid_angle(&self) -> f64 {
        1.0 / (2.0 * PI * self.one_minus_cos_max)
    }
}

/// Two unit vectors completing unit `n` to an orthonormal basis (Duff et al. 2017).
fn orthonormal_basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The smallest root in `(tmin, tmax)` of `|o + t·d|² = r²`, `o` relative to the centre. The
/// discriminant is computed as pbrt-v4 and Mitsuba do (`r² − |o − (o·d/d·d)·d|²`, free of the
/// cancellation of `b² − 4ac`) and the roots without subtracting nearly equal numbers.
fn sphere_crossing(o: DVec3, d: DVec3, r: f64, tmin: f64, tmax: f64) -> Option<f64> {
    let a = d.length_squared();
    if a.is_nan() || a <= 0.0 {
        return None;
    }
    let b = o.dot(d);
    let c = o.length_squared() - r * r;
    let perp = o - d * (b / a);
    let disc = a * (r * r - perp.length_squared());
    if disc < 0.0 {
        return None;
    }
    let q = -(b + disc.sqrt().copysign(b));
    let (mut t0, mut t1) = if q == 0.0 { (0.0, 0.0) } else { (q / a, c / q) };
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    [t0, t1].into_iter().find(|&t| t > tmin && t < tmax)
}

/// A direction uniform over the unit sphere.
pub fn uniform_sphere(u1: f64, u2: f64) -> DVec3 {
    let z = 1.0 - 2.0 * u1;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Shirley–Chiu's concentric map of the unit square onto the unit disk (Mitsuba's
/// `square_to_uniform_disk_concentric`).
pub fn concentric_disk(u1: f64, u2: f64) -> (f64, f64) {
    let (x, y) = (2.0 * u1 - 1.0, 2.0 * u2 - 1.0);
    if x == 0.0 && y == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) = if x.abs() > y.abs() {
        (x, PI / 4.0 * (y / x))
    } else {
        (y, PI / 2.0 - PI / 4.0 * (x / y))
    };
    (r * phi.cos(), r * phi.sin())
}

/// The analytic shapes of a scene as a back-end answers them: primitive ids from `first`
/// on, after the triangles.
#[derive(Clone, Debug, Default)]
pub struct AnalyticShapes {
    pub shapes: Vec<Analytic>,
    pub first: u32,
}

impl AnalyticShapes {
    /// `hit` (the triangles' closest hit, if any) replaced by a strictly closer crossing of
    /// an analytic shape. `ray` must be valid.
    pub fn closest(&self, ray: &Ray, hit: Option<Hit>) -> Option<Hit> {
        let mut best_t = hit.map(|h| h.t);
        let mut tmax = best_t.map_or(f64::from(ray.tmax), f64::from);
        let mut nearest = None;
        for (i, shape) in self.shapes.iter().enumerate() {
            if let Some(t) = shape.crossing(ray, tmax) {
                let t32 = t as f32;
                // A crossing that rounds to the triangle's t leaves the triangle's hit.
                if best_t.is_some_and(|b| t32 >= b) {
                    continue;
                }
                tmax = t;
                best_t = Some(t32);
                nearest = Some((i, t));
            }
        }
        let Some((i, t)) = nearest else {
            return hit;
        };
        let (n, u, v) = self.shapes[i].surface(ray, t);
        Some(Hit {
            t: t as f32,
            prim: self.first + i as u32,
            u: u as f32,
            v: v as f32,
            ng: n.as_vec3(),
        })
    }

    /// Whether an analytic shape crosses `ray` within its segment. `ray` must be valid.
    pub fn occludes(&self, ray: &Ray) -> bool {
        let tmax = f64::from(ray.tmax);
        self.shapes.iter().any(|s| s.crossing(ray, tmax).is_some())
    }

    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn ray(o: [f32; 3], d: [f32; 3]) -> Ray {
        Ray::new(Vec3::from(o), Vec3::from(d), 0.0, f32::INFINITY)
    }

    #[test]
    fn sphere_hits_from_outside_inside_tangent_and_behind() {
        let s = Analytic::sphere(DVec3::new(1.0, 0.0, 0.0), 0.5, false).unwrap();
        let inf = f64::INFINITY;
        // From outside: the near side, normal towards the ray.
        let (t, n, _, _) = s
            .intersect(&ray([-2.0, 0.0, 0.0], [2.0, 0.0, 0.0]), inf)
            .unwrap();
        assert!((t - 1.25).abs() < 1e-12 && n == DVec3::NEG_X, "{t} {n}");
        // From inside: the far side, normal along the ray.
        let (t, n, _, _) = s
            .intersect(&ray([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), inf)
            .unwrap();
        assert!((t - 0.5).abs() < 1e-12 && n == DVec3::Y, "{t} {n}");
        // Behind, and cut short by tmax.
        assert!(s
            .intersect(&ray([2.0, 0.0, 0.0], [1.0, 0.0, 0.0]), inf)
            .is_none());
        assert!(s
            .intersect(&ray([-2.0, 0.0, 0.0], [1.0, 0.0, 0.0]), 2.0)
            .is_none());
        // Tangent: grazing just inside hits, just outside misses, exactly is finite.
        assert!(s
            .intersect(&ray([0.0, 0.4999, 0.0], [1.0, 0.0, 0.0]), inf)
            .is_some());
        assert!(s
            .intersect(&ray([0.0, 0.5001, 0.0], [1.0, 0.0, 0.0]), inf)
            .is_none());
        if let Some((t, n, u, v)) = s.intersect(&ray([0.0, 0.5, 0.0], [1.0, 0.0, 0.0]), inf) {
            assert!(t.is_finite() && n.is_finite() && u.is_finite() && v.is_finite());
        }
        // Flipped normals point inwards.
        let f = Analytic::sphere(DVec3::new(1.0, 0.0, 0.0), 0.5, true).unwrap();
        let (_, n, _, _) = f
            .intersect(&ray([-2.0, 0.0, 0.0], [1.0, 0.0, 0.0]), inf)
            .unwrap();
        assert_eq!(n, DVec3::X);
        // Far away and small: t keeps its relative precision.
        let far = Analytic::sphere(DVec3::new(0.0, 0.0, -1e4), 1e-2, false).unwrap();
        let (t, _, _, _) = far
            .intersect(&ray([0.0, 0.0, 0.0], [0.0, 0.0, -1.0]), inf)
            .unwrap();
        assert!((t - (1e4 - 1e-2)).abs() < 1e-9, "{t}");
    }

    #[test]
    fn disk_hits_inside_its_ellipse_only() {
        let to_world = DAffine3::from_scale_rotation_translation(
            DVec3::new(2.0, 1.0, 1.0),
            glam::DQuat::IDENTITY,
            DVec3::new(0.0, 0.0, 1.0),
        );
        let d = Analytic::disk(to_world, false).unwrap();
        assert!((d.area() - 2.0 * PI).abs() < 1e-12);
        let inf = f64::INFINITY;
        let (t, n, r, _) = d
            .intersect(&ray([1.9, 0.0, 3.0], [0.0, 0.0, -1.0]), inf)
            .unwrap();
        assert!((t - 2.0).abs() < 1e-12 && n == DVec3::Z && (r - 0.95).abs() < 1e-6);
        // Outside the ellipse (inside its bounding box), parallel, behind.
        assert!(d
            .intersect(&ray([1.5, 0.8, 3.0], [0.0, 0.0, -1.0]), inf)
            .is_none());
        assert!(d
            .intersect(&ray([0.0, 0.0, 3.0], [1.0, 0.0, 0.0]), inf)
            .is_none());
        assert!(d
            .intersect(&ray([0.0, 0.0, 3.0], [0.0, 0.0, 1.0]), inf)
            .is_none());
        // Flipped, and as Mitsuba orients it under a mirroring transform (inverse transpose).
        let f = Analytic::disk(to_world, true).unwrap();
        assert_eq!(f.normal_at(DVec3::ZERO), DVec3::NEG_Z);
        let mirror = Analytic::disk(DAffine3::from_scale(DVec3::new(-1.0, 1.0, 1.0)), false);
        assert_eq!(mirror.unwrap().normal_at(DVec3::ZERO), DVec3::Z);
        let down = Analytic::disk(DAffine3::from_scale(DVec3::new(1.0, 1.0, -1.0)), false);
        assert_eq!(down.unwrap().normal_at(DVec3::ZERO), DVec3::NEG_Z);
        assert!(Analytic::disk(DAffine3::from_scale(DVec3::new(1.0, 0.0, 1.0)), false).is_err());
    }

    #[test]
    fn cone_samples_are_visible_points_of_the_sphere() {
        let (c, r) = (DVec3::new(0.0, 3.0, 0.0), 0.7);
        let s = Analytic::sphere(c, r, false).unwrap();
        let x = DVec3::new(0.2, -1.0, 0.4);
        let cone = s.visible_cone(x).unwrap();
        for i in 0..1000 {
            let (u1, u2) = ((i as f64 + 0.5) / 1000.0, (i * 37 % 1000) as f64 / 1000.0);
            let y = cone.sample(u1, u2);
            assert!(((y - c).length() - r).abs() < 1e-12);
            assert!((y - c).dot(x - y) >= -1e-9);
        }
        // Ω = 2π (1 − cos θmax).
        let sin2 = r * r / (c - x).length_squared();
        let omega = 2.0 * PI * (1.0 - (1.0 - sin2).sqrt());
        assert!((cone.pdf_solid_angle() * omega - 1.0).abs() < 1e-12);
        assert!(s.visible_cone(c + DVec3::X * r).is_none());
        assert!(s.visible_cone(c).is_none());
    }
}
