//! Pinhole camera with the conventions of the design: image right =
//! normalize(cross(target − origin, up)), row 0 at the top, horizontal field of view.

use crate::accel::Ray;
use glam::Vec3;

#[derive(Clone, Debug)]
pub struct Camera {
    pub origin: Vec3,
    /// Horizontal field of view, radians.
    pub fov_x: f32,
    pub width: u32,
    pub height: u32,
    forward: Vec3,
    /// Image-plane vectors at unit distance, scaled so that pixel coordinates map linearly.
    right: Vec3,
    up: Vec3,
    /// Distances along the viewing direction between which camera rays see (Mitsuba's
    /// `near_clip`, `far_clip`); 0 and infinity for TOML scenes.
    near: f32,
    far: f32,
}

impl Camera {
    /// `fov_x` in radians. The caller has validated the inputs (finite, non-degenerate).
    pub fn new(origin: Vec3, target: Vec3, up: Vec3, fov_x: f32, width: u32, height: u32) -> Self {
        let forward = (target - origin).normalize();
        let right = forward.cross(up).normalize();
        let true_up = right.cross(forward);
        let clip = (0.0, f32::INFINITY);
        Self::with_frame(
            origin,
            [forward, right, true_up],
            fov_x,
            (width, height),
            clip,
        )
    }

    /// A camera looking along unit `forward` whose image right is unit `right` and image up
    /// unit `up` (an orthonormal frame, either handedness: Mitsuba's `to_world` may mirror),
    /// with clip distances along `forward`. The caller has validated the inputs.
    pub fn with_frame(
        origin: Vec3,
        [forward, right, up]: [Vec3; 3],
        fov_x: f32,
        (width, height): (u32, u32),
        (near, far): (f32, f32),
    ) -> Self {
        let half_w = (0.5 * fov_x).tan();
        let half_h = half_w * height as f32 / width as f32;
        Self {
            origin,
            fov_x,
            width,
            height,
            forward,
            right: right * half_w,
            up: up * half_h,
            near,
            far,
        }
    }

    /// The same camera with another image size (the horizontal field of view is kept).
    pub fn resized(&self, width: u32, height: u32) -> Self {
        let mut camera = Self::new(
            self.origin,
            self.origin + self.forward,
            self.up,
            self.fov_x,
            width,
            height,
        );
        // A mirrored frame (from Mitsuba's `to_world`) keeps its image right.
        if camera.right.dot(self.right) < 0.0 {
            camera.right = -camera.right;
        }
        camera.near = self.near;
        camera.far = self.far;
        camera
    }

    /// The primary ray through continuous pixel coordinates `(px, py)`, `px ∈ [0, width)`,
    /// `py ∈ [0, height)`, row 0 at the top. The direction is normalised.
    pub fn ray(&self, px: f32, py: f32) -> Ray {
        let sx = 2.0 * px / self.width as f32 - 1.0;
        let sy = 1.0 - 2.0 * py / self.height as f32;
        let dir = (self.forward + sx * self.right + sy * self.up).normalize();
        if self.near == 0.0 && self.far == f32::INFINITY {
            return Ray::new(self.origin, dir, 0.0, f32::INFINITY);
        }
        // Mitsuba's clip planes are at distances along the viewing direction.
        let cos = dir.dot(self.forward);
        Ray::new(self.origin, dir, self.near / cos, self.far / cos)
    }

    /// Continuous pixel coordinates of world point `p` (the inverse of [`Camera::ray`]) and
    /// its depth along the viewing direction; `None` behind the camera.
    pub fn project(&self, p: Vec3) -> Option<(f32, f32, f32)> {
        let d = p - self.origin;
        let depth = d.dot(self.forward);
        if depth.is_nan() || depth <= 0.0 {
            return None;
        }
        let sx = d.dot(self.right) / (depth * self.right.length_squared());
        let sy = d.dot(self.up) / (depth * self.up.length_squared());
        Some((
            0.5 * (sx + 1.0) * self.width as f32,
            0.5 * (1.0 - sy) * self.height as f32,
            depth,
        ))
    }

    /// Pixels per unit length at `depth`, across the image.
    pub fn pixels_per_unit(&self, depth: f32) -> f32 {
        0.5 * self.width as f32 / (self.right.length() * depth)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_inverts_ray() {
        let camera = Camera::new(
            Vec3::new(0.3, 1.0, 4.0),
            Vec3::new(0.0, 0.8, 0.0),
            Vec3::Y,
            0.9,
            64,
            48,
        );
        for (px, py) in [(0.5, 0.5), (31.2, 17.9), (63.9, 47.1)] {
            let ray = camera.ray(px, py);
            let (x, y, depth) = camera.project(ray.origin + 2.5 * ray.dir).unwrap();
            assert!(
                (x - px).abs() < 1e-3 && (y - py).abs() < 1e-3,
                "{x} {y} vs {px} {py}"
            );
            assert!(depth > 0.0 && depth < 2.5);
        }
        assert!(camera.project(camera.origin - camera.forward).is_none());
    }
}
