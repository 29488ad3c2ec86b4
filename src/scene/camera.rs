//! Pinhole camera with the conventions of the design: image right =
//! normalize(cross(target − origin, up)), row 0 at the top, horizontal field of view; and
//! its importance for paths that reach it from the lights ([`Camera::connect`]).

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

/// What joins a point of the scene to the pinhole (pbrt-v4's `PerspectiveCamera::SampleWi`
/// for a pinhole): the pixel that sees it, the camera's importance and its density.
#[derive(Clone, Copy, Debug)]
pub struct CameraConnection {
    /// The pixel the point is seen in, and its index (row by row).
    pub pixel: (u32, u32),
    pub index: u32,
    /// Unit direction from the point towards the pinhole, and their distance.
    pub wi: Vec3,
    pub dist: f32,
    /// `cos θ` of the ray from the pinhole against the viewing direction.
    pub cos: f64,
    /// The importance `W_e` of that ray ([`Camera::importance`]).
    pub importance: f64,
    /// The density of the pinhole (a delta position) in solid angle at the point:
    /// `dist² / cos θ`.
    pub pdf: f64,
    /// Where the segment to the camera ends for a visibility test: the pinhole, or the near
    /// clip plane along the ray (nothing nearer is seen).
    pub end: Vec3,
}

impl Camera {
    /// The area of one pixel on the image plane at unit distance from the pinhole.
    pub fn pixel_area(&self) -> f64 {
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        4.0 * f64::from(self.right.length()) * f64::from(self.up.length()) / (w * h)
    }

    /// The pixel that continuous pixel coordinates `(px, py)` fall in; `None` outside the
    /// image.
    fn pixel_at(&self, px: f32, py: f32) -> Option<(u32, u32)> {
        let inside = px >= 0.0 && py >= 0.0;
        let (x, y) = (px as u32, py as u32);
        (inside && x < self.width && y < self.height).then_some((x, y))
    }

    /// The importance `W_e` of a ray leaving the pinhole along unit `dir` (pbrt-v4's
    /// `PerspectiveCamera::We`), normalised over the pixel it passes through rather than the
    /// whole film, so that `∫_pixel W_e cos θ dω = 1`: `1 / (A_pixel cos⁴ θ)`, where
    /// `A_pixel` is a pixel's area at unit distance ([`Self::pixel_area`]) and `θ` the
    /// angle to the viewing direction; with that pixel. `None` outside the image.
    pub fn importance(&self, dir: Vec3) -> Option<((u32, u32), f64)> {
        let cos = f64::from(dir.dot(self.forward));
        if cos <= 0.0 {
            return None;
        }
        let (px, py, _) = self.project(self.origin + dir)?;
        let pixel = self.pixel_at(px, py)?;
        Some((pixel, 1.0 / (self.pixel_area() * cos.powi(4))))
    }

    /// The solid-angle density with which a camera ray of the pixel that `dir` passes through
    /// (uniform over the pixel) leaves along unit `dir`: `1 / (A_pixel cos³ θ)` (pbrt-v4's
    /// `PerspectiveCamera::PDF_We`, direction part, per pixel); zero outside the image.
    pub fn pdf_direction(&self, dir: Vec3) -> f64 {
        match self.importance(dir) {
            Some((_, we)) => we * f64::from(dir.dot(self.forward)),
            None => 0.0,
        }
    }

    /// The camera as seen from world point `p`: the pixel it lands in, the importance and
    /// the density of the pinhole ([`CameraConnection`]); `None` behind the camera, outside
    /// the image or outside the clip distances.
    pub fn connect(&self, p: Vec3) -> Option<CameraConnection> {
        let d = p - self.origin;
        let depth = d.dot(self.forward);
        if !(depth > self.near && depth < self.far) {
            return None;
        }
        let dist = d.length();
        let dir = d / dist;
        let (pixel, importance) = self.importance(dir)?;
        let cos = f64::from(depth / dist);
        let end = match self.near > 0.0 {
            true => self.origin + dir * (self.near / dir.dot(self.forward)),
            false => self.origin,
        };
        Some(CameraConnection {
            pixel,
            index: pixel.1 * self.width + pixel.0,
            wi: -dir,
            dist,
            cos,
            importance,
            pdf: f64::from(dist) * f64::from(dist) / cos,
            end,
        })
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

    /// `∫ W_e cos θ dω` over the sphere, by uniform directions: 1 for each pixel the
    /// directions fall in, so the image's pixel count in all; and `W_e cos / pdf = 1`
    /// for camera rays (the density is the one the rays are drawn with). The twin: the
    /// importance without its `cos⁴ θ` integrates to something else.
    #[test]
    fn importance_integrates_to_one_per_pixel() {
        let camera = Camera::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 1.3, 8, 6);
        // A midpoint grid over the square that `uniform_sphere` maps onto the sphere.
        let (rows, cols) = (2000u32, 1000u32);
        let n = rows * cols;
        let (mut with, mut without) = (0.0, 0.0);
        let mut per_pixel = vec![0.0; 48];
        for k in 0..n {
            let u = (
                ((k / cols) as f32 + 0.5) / rows as f32,
                ((k % cols) as f32 + 0.5) / cols as f32,
            );
            let dir = crate::math::uniform_sphere(u.0, u.1);
            if let Some(((x, y), we)) = camera.importance(dir) {
                let cos = f64::from(dir.dot(camera.forward));
                let value = we * cos * 4.0 * std::f64::consts::PI / f64::from(n);
                with += value;
                without += value * cos.powi(4);
                per_pixel[(y * 8 + x) as usize] += value;
            }
        }
        assert!((with / 48.0 - 1.0).abs() < 0.01, "{with}");
        assert!((without / 48.0 - 1.0).abs() > 0.1, "{without}");
        let worst = per_pixel
            .iter()
            .map(|v| (v - 1.0f64).abs())
            .fold(0.0, f64::max);
        assert!(worst < 0.08, "{per_pixel:?}");
        for (px, py) in [(0.3, 0.2), (7.9, 5.9), (4.5, 3.1)] {
            let dir = camera.ray(px, py).dir;
            let (pixel, we) = camera.importance(dir).unwrap();
            assert_eq!(pixel, (px as u32, py as u32));
            let cos = f64::from(dir.dot(camera.forward));
            assert!((we * cos / camera.pdf_direction(dir) - 1.0).abs() < 1e-9);
        }
    }

    /// A point the camera ray through a pixel meets is connected back to that pixel, along
    /// the ray, with the pinhole's density `dist² / cos θ`.
    #[test]
    fn connect_inverts_ray() {
        let camera = Camera::new(Vec3::new(0.3, 1.0, 4.0), Vec3::ZERO, Vec3::Y, 0.9, 64, 48);
        let ray = camera.ray(40.3, 12.7);
        let c = camera.connect(ray.origin + 3.0 * ray.dir).unwrap();
        assert_eq!((c.pixel, c.index), ((40, 12), 12 * 64 + 40));
        assert!((c.wi + ray.dir).length() < 1e-5 && (c.dist - 3.0).abs() < 1e-5);
        let cos = f64::from(ray.dir.dot(camera.forward));
        assert!((c.pdf - 9.0 / cos).abs() < 1e-3 * c.pdf);
        assert!(camera.connect(ray.origin - ray.dir).is_none());
    }
}
