//! Mitsuba 3's `envmap` emitter (`src/emitters/envmap.cpp`): an equirectangular image of
//! the radiance arriving from every direction, looked up as Mitsuba looks it up, and a
//! light-sampling density proportional to it, exact in solid angle.
//!
//! Directions (in the map's frame, after `to_world`'s inverse): texture coordinates
//! `u = atan2(d.x, −d.z) / 2π` (wrapped into [0, 1)) and `v = acos(d.y) / π`, so the image's
//! top row looks along +y and its middle row's left edge along −z; inversely
//! `d = (sin φ sin θ, cos θ, −cos φ sin θ)` for `φ = 2π u`, `θ = π v`.
//!
//! Radiance is Mitsuba's bilinear lookup: periodic in `u` with texel centres at
//! `u = (x + ½) / W`, clamped in `v` with the rows at `v = y / (H − 1)` (the first row at the
//! pole `θ = 0`, the last at `θ = π`), times `scale`.
//!
//! Sampling (Mitsuba warps a piecewise-bilinear density; genpath's is piecewise constant, which
//! is as good for light sampling and simpler to keep exact): the sphere is cut into the
//! `W × (H − 1)` patches between neighbouring texel centres (`u` between two centres, `θ`
//! between two rows); a patch is picked with probability proportional to the mean of its four
//! corners' luminance times its solid angle (`Ω = (2π / W)(cos θ₀ − cos θ₁)`: the `sin θ`
//! weighting), and a direction uniformly in solid angle inside it (`u` uniform, `cos θ`
//! uniform), so the density is `P(patch) / Ω` there. The bilinear radiance inside a patch
//! is positive only where one of its corners is, so the density covers every direction the
//! map lights.

use glam::{DMat3, DVec3, Vec3};
use std::f64::consts::PI;

/// An environment map, its frame and its sampling distribution.
#[derive(Clone, Debug)]
pub struct EnvMap {
    width: usize,
    height: usize,
    /// Linear RGB, row after row, row 0 at the top (`θ = 0`).
    texels: Vec<Vec3>,
    /// `to_world`'s linear part (orthogonal) and its inverse.
    to_world: DMat3,
    from_world: DMat3,
    /// Per patch row (`H − 1`), the running sum of its patches' weights; and the running
    /// sum of the rows' totals.
    patch_cdf: Vec<f64>,
    row_cdf: Vec<f64>,
    /// `cos θ` at each row of texels (the patches' edges).
    cos_rows: Vec<f64>,
}

/// Mitsuba's luminance of linear sRGB.
fn luminance(c: Vec3) -> f64 {
    0.212671 * f64::from(c.x) + 0.715160 * f64::from(c.y) + 0.072169 * f64::from(c.z)
}

/// Why a map cannot be an environment.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EnvMapError {
    #[error("the map is {0}×{1}; an environment map needs at least 2×3 pixels")]
    TooSmall(usize, usize),
    #[error("pixel ({x}, {y}) is {value:?}: negative, not a number or infinite")]
    BadPixel { x: usize, y: usize, value: [f32; 3] },
    #[error("the map is black: it emits nothing")]
    Black,
    #[error("`to_world` must rotate (or mirror) without scaling or shearing")]
    NotRigid,
}

/// The index of the first running sum above `target` (clamped to the last), and where
/// `target` falls inside that step, in [0, 1).
fn invert(cdf: &[f64], target: f64) -> (usize, f64) {
    let i = cdf.partition_point(|&c| c <= target).min(cdf.len() - 1);
    let before = if i == 0 { 0.0 } else { cdf[i - 1] };
    let step = cdf[i] - before;
    let t = if step > 0.0 {
        ((target - before) / step).clamp(0.0, 1.0 - f64::EPSILON)
    } else {
        0.5
    };
    (i, t)
}

impl EnvMap {
    /// The map of `width × height` linear RGB `texels` (row 0 at the top), placed by the
    /// linear part of `to_world`.
    pub fn new(
        width: usize,
        height: usize,
        texels: Vec<Vec3>,
        to_world: DMat3,
    ) -> Result<Self, EnvMapError> {
        if width < 2 || height < 3 {
            return Err(EnvMapError::TooSmall(width, height));
        }
        assert_eq!(texels.len(), width * height);
        if let Some(i) = texels
            .iter()
            .position(|c| !(c.is_finite() && c.min_element() >= 0.0))
        {
            return Err(EnvMapError::BadPixel {
                x: i % width,
                y: i / width,
                value: texels[i].to_array(),
            });
        }
        let orthogonal = (to_world.transpose() * to_world - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .all(|e| e.abs() < 1e-6);
        if !orthogonal {
            return Err(EnvMapError::NotRigid);
        }
        let cos_rows: Vec<f64> = (0..height)
            .map(|y| (PI * y as f64 / (height - 1) as f64).cos())
            .collect();
        let lum = |x: usize, y: usize| luminance(texels[y * width + x % width]);
        let mut patch_cdf = Vec::with_capacity(width * (height - 1));
        let mut row_cdf = Vec::with_capacity(height - 1);
        let mut total = 0.0;
        for r in 0..height - 1 {
            let solid_angle = 2.0 * PI / width as f64 * (cos_rows[r] - cos_rows[r + 1]);
            let mut row = 0.0;
            for c in 0..width {
                let mean = 0.25 * (lum(c, r) + lum(c + 1, r) + lum(c, r + 1) + lum(c + 1, r + 1));
                row += mean * solid_angle;
                patch_cdf.push(row);
            }
            total += row;
            row_cdf.push(total);
        }
        if !(total > 0.0) {
            return Err(EnvMapError::Black);
        }
        Ok(Self {
            width,
            height,
            texels,
            to_world,
            from_world: to_world.transpose(),
            patch_cdf,
            row_cdf,
            cos_rows,
        })
    }

    pub fn width(&self) -> usize {
        self.width
    }

    pub fn height(&self) -> usize {
        self.height
    }

    /// Mitsuba's texture coordinates of unit `dir` (world), in the map's frame.
    fn uv(&self, dir: DVec3) -> (f64, f64) {
        let d = self.from_world * dir;
        let u = d.x.atan2(-d.z) / (2.0 * PI);
        let v = d.y.clamp(-1.0, 1.0).acos() / PI;
        (u - u.floor(), v)
    }

    /// The map's radiance (without `scale`) arriving along `−dir`, i.e. gathered by a ray
    /// leaving along unit `dir`: Mitsuba's bilinear lookup.
    pub fn eval(&self, dir: DVec3) -> Vec3 {
        let (u, v) = self.uv(dir);
        let x = u * self.width as f64 - 0.5;
        let y = (v * (self.height - 1) as f64).clamp(0.0, (self.height - 1) as f64);
        let (x0, y0) = (x.floor(), y.floor().min((self.height - 2) as f64));
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let w = self.width as i64;
        let c0 = (x0 as i64).rem_euclid(w) as usize;
        let c1 = (c0 + 1) % self.width;
        let r0 = y0 as usize;
        let at = |c: usize, r: usize| self.texels[r * self.width + c];
        let top = at(c0, r0) * (1.0 - fx) + at(c1, r0) * fx;
        let bottom = at(c0, r0 + 1) * (1.0 - fx) + at(c1, r0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The patch holding `(u, v)`: its column and row.
    fn patch(&self, u: f64, v: f64) -> (usize, usize) {
        let c = ((u * self.width as f64 - 0.5).floor() as i64).rem_euclid(self.width as i64);
        let r = ((v * (self.height - 1) as f64).floor() as i64).clamp(0, self.height as i64 - 2);
        (c as usize, r as usize)
    }

    /// The probability of patch `(c, r)` and its solid angle.
    fn patch_mass(&self, c: usize, r: usize) -> (f64, f64) {
        let i = r * self.width + c;
        let before = if c == 0 { 0.0 } else { self.patch_cdf[i - 1] };
        let total = self.row_cdf[self.row_cdf.len() - 1];
        let solid_angle = 2.0 * PI / self.width as f64 * (self.cos_rows[r] - self.cos_rows[r + 1]);
        ((self.patch_cdf[i] - before) / total, solid_angle)
    }

    /// A unit direction (world) drawn from two uniform numbers in [0, 1): `u[1]` picks the
    /// patch row, `u[0]` the patch in it, each then rescaled to place the direction
    /// uniformly in solid angle inside the patch.
    pub fn sample(&self, u: [f64; 2]) -> DVec3 {
        let total = self.row_cdf[self.row_cdf.len() - 1];
        let (r, t_v) = invert(&self.row_cdf, u[1] * total);
        let row = &self.patch_cdf[r * self.width..(r + 1) * self.width];
        let (c, t_u) = invert(row, u[0] * row[self.width - 1]);
        let phi = 2.0 * PI * (c as f64 + 0.5 + t_u) / self.width as f64;
        let cos_theta = self.cos_rows[r] + t_v * (self.cos_rows[r + 1] - self.cos_rows[r]);
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let local = DVec3::new(phi.sin() * sin_theta, cos_theta, -phi.cos() * sin_theta);
        (self.to_world * local).normalize()
    }

    /// The solid-angle density of [`Self::sample`] at unit `dir` (world).
    pub fn pdf(&self, dir: DVec3) -> f64 {
        let (u, v) = self.uv(dir);
        let (c, r) = self.patch(u, v);
        let (mass, solid_angle) = self.patch_mass(c, r);
        mass / solid_angle
    }

    /// The density of [`Self::sample`] per unit of `(u, v)` without the `sin θ` Jacobian
    /// (`du dv · 2π²` taken for the solid angle): a deliberately wrong density that the χ²
    /// test must reject.
    #[cfg(any(test, feature = "testing"))]
    pub fn pdf_without_jacobian(&self, dir: DVec3) -> f64 {
        let (u, v) = self.uv(dir);
        let (c, r) = self.patch(u, v);
        let (mass, _) = self.patch_mass(c, r);
        let uv_area = 1.0 / (self.width * (self.height - 1)) as f64;
        mass / (uv_area * 2.0 * PI * PI)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(texels: Vec<Vec3>, w: usize, h: usize) -> EnvMap {
        EnvMap::new(w, h, texels, DMat3::IDENTITY).unwrap()
    }

    #[test]
    fn directions_map_as_mitsubas() {
        // A map whose texel (x, y) holds (x, y, 1).
        let (w, h) = (8, 5);
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |x| Vec3::new(x as f32, y as f32, 1.0)))
            .collect();
        let m = map(texels, w, h);
        // +y is the top row; −y the bottom one.
        assert_eq!(m.eval(DVec3::Y).y, 0.0);
        assert_eq!(m.eval(-DVec3::Y).y, 4.0);
        // Along −z (u = 0), half-way between the last and the first column; along +x
        // (u = 1/4) the centre of column 1.5, at the horizon (row 2).
        let e = m.eval(-DVec3::Z);
        assert!((e.x - 3.5).abs() < 1e-5 && (e.y - 2.0).abs() < 1e-5, "{e}");
        let e = m.eval(DVec3::X);
        assert!((e.x - 1.5).abs() < 1e-5, "{e}");
        // Texture coordinates invert the sampler's mapping.
        for &(u, v) in &[(0.1, 0.3), (0.7, 0.9), (0.5, 0.5)] {
            let (phi, theta) = (2.0 * PI * u, PI * v);
            let d = DVec3::new(
                phi.sin() * theta.sin(),
                theta.cos(),
                -phi.cos() * theta.sin(),
            );
            let (uu, vv) = m.uv(d);
            assert!((uu - u).abs() < 1e-12 && (vv - v).abs() < 1e-12);
        }
    }

    #[test]
    fn a_uniform_map_samples_uniformly() {
        let m = map(vec![Vec3::ONE; 16 * 9], 16, 9);
        for &d in &[DVec3::Y, DVec3::X, DVec3::new(0.3, -0.8, 0.52).normalize()] {
            assert!((m.pdf(d) - 1.0 / (4.0 * PI)).abs() < 1e-12);
        }
    }

    #[test]
    fn bad_maps_are_refused() {
        let mut texels = vec![Vec3::ONE; 12];
        texels[5] = Vec3::new(1.0, f32::NAN, 0.0);
        let e = EnvMap::new(4, 3, texels, DMat3::IDENTITY).unwrap_err();
        assert!(matches!(e, EnvMapError::BadPixel { x: 1, y: 1, .. }));
        assert_eq!(
            EnvMap::new(4, 3, vec![Vec3::ZERO; 12], DMat3::IDENTITY).unwrap_err(),
            EnvMapError::Black
        );
        assert_eq!(
            EnvMap::new(2, 2, vec![Vec3::ONE; 4], DMat3::IDENTITY).unwrap_err(),
            EnvMapError::TooSmall(2, 2)
        );
        let scaled = DMat3::from_diagonal(DVec3::splat(2.0));
        assert_eq!(
            EnvMap::new(4, 3, vec![Vec3::ONE; 12], scaled).unwrap_err(),
            EnvMapError::NotRigid
        );
    }
}
