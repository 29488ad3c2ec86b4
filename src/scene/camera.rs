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
}

impl Camera {
    /// `fov_x` in radians. The caller has validated the inputs (finite, non-degenerate).
    pub fn new(origin: Vec3, target: Vec3, up: Vec3, fov_x: f32, width: u32, height: u32) -> Self {
        let forward = (target - origin).normalize();
        let right = forward.cross(up).normalize();
        let true_up = right.cross(forward);
        let half_w = (0.5 * fov_x).tan();
        let half_h = half_w * height as f32 / width as f32;
        Self { origin, fov_x, width, height, forward, right: right * half_w, up: true_up * half_h }
    }

    /// The same camera with another image size (the horizontal field of view is kept).
    pub fn resized(&self, width: u32, height: u32) -> Self {
        Self::new(self.origin, self.origin + self.forward, self.up, self.fov_x, width, height)
    }

    /// The primary ray through continuous pixel coordinates `(px, py)`, `px ∈ [0, width)`,
    /// `py ∈ [0, height)`, row 0 at the top. The direction is normalised.
    pub fn ray(&self, px: f32, py: f32) -> Ray {
        let sx = 2.0 * px / self.width as f32 - 1.0;
        let sy = 1.0 - 2.0 * py / self.height as f32;
        let dir = (self.forward + sx * self.right + sy * self.up).normalize();
        Ray::new(self.origin, dir, 0.0, f32::INFINITY)
    }
}
