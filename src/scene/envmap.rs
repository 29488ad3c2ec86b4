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
//! Sampling (Mitsuba warps a piecewise-bilinear density; genpath's is piecewise constant,
//! simpler to keep exact): the `W × (H − 1)` patches between neighbouring texel centres (`u`
//! between two centres, `θ` between two rows) are cut into `sub × sub` cells each
//! ([`subdivision`]); a cell is picked with probability proportional to the luminance of the
//! bilinear lookup at its centre (the mean of the bilinear radiance over the cell in `(u, v)`)
//! times its solid angle (`Ω = (2π / (W·sub))(cos θ₀ − cos θ₁)`: the `sin θ` weighting), and a
//! direction uniformly in solid angle inside it (`u` uniform, `cos θ` uniform), so the density
//! is `P(cell) / Ω` there. Inside a patch the bilinear radiance is zero at a cell's centre
//! only where all four corners are, so the density covers every direction the map lights.
//! Both inversions of the running sums (the row, then the cell in it) start from a guide
//! table and land in the cells a binary search would; the direction mapping's trigonometry
//! is [`crate::math::trig`]'s, within 2e-15 of libm's.

use crate::math::trig;
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
    /// Cells per texel along each axis ([`subdivision`]).
    sub: usize,
    /// Cells across (`W·sub`) and down (`(H − 1)·sub`).
    cols: usize,
    rows: usize,
    /// Per row of cells, the running sum of its cells' weights; and the running sum of the
    /// rows' totals.
    cell_cdf: Vec<f64>,
    row_cdf: Vec<f64>,
    /// Guide tables of the two inversions ([`Guided`]): per row of cells, one entry per
    /// cell; for the rows, one per row.
    cell_guide: Vec<u32>,
    row_guide: Vec<u32>,
    /// Per row of cells, `1 / (total weight · Ω)`: a cell's weight times it is its density.
    row_density: Vec<f64>,
    /// `cos θ` at the edges of the rows of cells.
    cos_rows: Vec<f64>,
}

/// A direction drawn by [`EnvMap::sample`], with what [`EnvMap::eval`] and [`EnvMap::pdf`]
/// give there (computed from the cell and the place in it, not from the direction again).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvSample {
    /// Unit, in world space.
    pub dir: DVec3,
    pub radiance: Vec3,
    pub pdf: f64,
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

/// A running sum and its guide table (the cutpoint method, Chen and Asau 1974): entry `b`
/// of the guide is the first step whose running sum exceeds (a hair below) `b / n` of the
/// total, for `n` the number of steps, so that inverting the sum starts there and scans a
/// step or two forward instead of searching the whole sum. The inversion is a binary
/// search's, step for step.
struct Guided<'a> {
    cdf: &'a [f64],
    guide: &'a [u32],
}

impl Guided<'_> {
    /// The guide table of `cdf` (non-decreasing, not empty).
    fn table(cdf: &[f64]) -> impl Iterator<Item = u32> + '_ {
        let n = cdf.len();
        let total = cdf[n - 1];
        (0..n).map(move |b| {
            // Below the least target of bucket `b` by far more than its rounding.
            let lower = b as f64 / n as f64 * total * (1.0 - 1e-9);
            cdf.partition_point(|&c| c <= lower).min(n - 1) as u32
        })
    }

    /// The index of the first running sum above `u` times the total (clamped to the last),
    /// and where that falls inside its step, in [0, 1); `u` in [0, 1).
    fn invert(&self, u: f64) -> (usize, f64) {
        let cdf = self.cdf;
        let n = cdf.len();
        let target = u * cdf[n - 1];
        let b = ((u * n as f64) as usize).min(n - 1);
        let mut i = self.guide[b] as usize;
        while i < n - 1 && cdf[i] <= target {
            i += 1;
        }
        let before = if i == 0 { 0.0 } else { cdf[i - 1] };
        let step = cdf[i] - before;
        let t = if step > 0.0 {
            ((target - before) / step).clamp(0.0, 1.0 - f64::EPSILON)
        } else {
            0.5
        };
        (i, t)
    }
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
        let sub = subdivision(width, height);
        let (cols, rows) = (width * sub, (height - 1) * sub);
        let cos_rows: Vec<f64> = (0..=rows)
            .map(|i| (PI * i as f64 / rows as f64).cos())
            .collect();
        let lum: Vec<f64> = texels.iter().map(|&c| luminance(c)).collect();
        let mut cell_cdf = Vec::with_capacity(cols * rows);
        let mut row_cdf = Vec::with_capacity(rows);
        let mut total = 0.0;
        for i in 0..rows {
            let solid_angle = 2.0 * PI / cols as f64 * (cos_rows[i] - cos_rows[i + 1]);
            let y = (i as f64 + 0.5) / sub as f64;
            let mut row = 0.0;
            for j in 0..cols {
                let x = (j as f64 + 0.5) / sub as f64;
                row += bilinear(&lum, width, (x, y)) * solid_angle;
                cell_cdf.push(row);
            }
            total += row;
            row_cdf.push(total);
        }
        if total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(EnvMapError::Black);
        }
        let cell_guide = cell_cdf.chunks(cols).flat_map(Guided::table).collect();
        let row_guide = Guided::table(&row_cdf).collect();
        let row_density = (0..rows)
            .map(|i| 1.0 / (total * 2.0 * PI / cols as f64 * (cos_rows[i] - cos_rows[i + 1])))
            .collect();
        Ok(Self {
            width,
            height,
            texels,
            to_world,
            from_world: to_world.transpose(),
            sub,
            cols,
            rows,
            cell_cdf,
            row_cdf,
            cell_guide,
            row_guide,
            row_density,
            cos_rows,
        })
    }

    /// The mean of the map's channels over the sphere (texels weighted by the solid angle of
    /// their row, `sin θ`): what emission sampling weighs the environment's power by.
    pub fn mean_radiance(&self) -> f64 {
        let (mut sum, mut weight) = (0.0, 0.0);
        for (row, texels) in self.texels.chunks(self.width).enumerate() {
            let theta = PI * (row as f64 + 0.5) / self.height as f64;
            let w = theta.sin();
            let mean: f64 = texels
                .iter()
                .map(|t| f64::from(t.x + t.y + t.z) / 3.0)
                .sum();
            sum += w * mean / self.width as f64;
            weight += w;
        }
        if weight > 0.0 {
            sum / weight
        } else {
            0.0
        }
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
        let u = trig::atan2(d.x, -d.z) / (2.0 * PI);
        let v = trig::acos(d.y) / PI;
        (if u < 0.0 { u + 1.0 } else { u }, v)
    }

    /// The map's radiance (without `scale`) arriving along `−dir`, i.e. gathered by a ray
    /// leaving along unit `dir`: Mitsuba's bilinear lookup.
    pub fn eval(&self, dir: DVec3) -> Vec3 {
        self.lookup(self.uv(dir))
    }

    /// The bilinear lookup at texture coordinates `(u, v)`.
    fn lookup(&self, (u, v): (f64, f64)) -> Vec3 {
        let x = u * self.width as f64 - 0.5;
        let y = v * (self.height - 1) as f64;
        bilinear(&self.texels, self.width, (x, y))
    }

    /// [`Self::eval`] and [`Self::pdf`] at once.
    pub fn eval_pdf(&self, dir: DVec3) -> (Vec3, f64) {
        let uv = self.uv(dir);
        (self.lookup(uv), self.density(uv))
    }

    /// The density at texture coordinates `(u, v)`: that of the cell holding them.
    fn density(&self, (u, v): (f64, f64)) -> f64 {
        let (cols, rows) = (self.cols, self.rows);
        let j = trig::floor((u * self.width as f64 - 0.5) * self.sub as f64);
        let i = trig::floor(v * rows as f64).clamp(0, rows as i64 - 1) as usize;
        let k = i * cols + j.rem_euclid(cols as i64) as usize;
        let before = if k % cols == 0 {
            0.0
        } else {
            self.cell_cdf[k - 1]
        };
        (self.cell_cdf[k] - before) * self.row_density[i]
    }

    /// A unit direction (world) drawn from two uniform numbers in [0, 1): `u[1]` picks the
    /// cell row, `u[0]` the cell in it, each then rescaled to place the direction uniformly
    /// in solid angle inside the cell; with the radiance and the density there.
    pub fn sample(&self, u: [f64; 2]) -> EnvSample {
        let cols = self.cols;
        let rows = Guided {
            cdf: &self.row_cdf,
            guide: &self.row_guide,
        };
        let (i, t_v) = rows.invert(u[1]);
        let span = i * cols..(i + 1) * cols;
        let row = Guided {
            cdf: &self.cell_cdf[span.clone()],
            guide: &self.cell_guide[span],
        };
        let (j, t_u) = row.invert(u[0]);
        // `φ / 2π`, and Mitsuba's `u`: `φ` wrapped into one turn.
        let turns = ((j as f64 + t_u) / self.sub as f64 + 0.5) / self.width as f64;
        let tex_u = if turns >= 1.0 { turns - 1.0 } else { turns };
        let (sin_phi, cos_phi) = trig::sin_cos_turns(turns);
        let cos_theta = self.cos_rows[i] + t_v * (self.cos_rows[i + 1] - self.cos_rows[i]);
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let local = DVec3::new(sin_phi * sin_theta, cos_theta, -cos_phi * sin_theta);
        let before = if j == 0 {
            0.0
        } else {
            self.cell_cdf[i * cols + j - 1]
        };
        EnvSample {
            dir: (self.to_world * local).normalize(),
            radiance: self.lookup((tex_u, trig::atan2(sin_theta, cos_theta) / PI)),
            pdf: (self.cell_cdf[i * cols + j] - before) * self.row_density[i],
        }
    }

    /// The solid-angle density of [`Self::sample`] at unit `dir` (world).
    pub fn pdf(&self, dir: DVec3) -> f64 {
        self.density(self.uv(dir))
    }
}

/// Mitsuba's bilinear lookup of `grid` (rows of `width`, periodic across columns, clamped
/// across rows) at `(x, y)` in texel units, texel centres at integers: in `f64`, rounded once.
fn bilinear<T>(grid: &[T], width: usize, (x, y): (f64, f64)) -> T
where
    T: Copy + Texel,
{
    let height = grid.len() / width;
    let y = y.clamp(0.0, (height - 1) as f64);
    let (x0, y0) = (trig::floor(x), trig::floor(y).min(height as i64 - 2));
    let (fx, fy) = (x - x0 as f64, y - y0 as f64);
    let c0 = x0.rem_euclid(width as i64) as usize;
    let c1 = (c0 + 1) % width;
    let r0 = y0 as usize;
    let at = |c: usize, r: usize| grid[r * width + c].widen();
    let top = at(c0, r0) * (1.0 - fx) + at(c1, r0) * fx;
    let bottom = at(c0, r0 + 1) * (1.0 - fx) + at(c1, r0 + 1) * fx;
    T::narrow(top * (1.0 - fy) + bottom * fy)
}

/// A value [`bilinear`] interpolates: an RGB texel or a luminance, in `f64` meanwhile.
trait Texel {
    fn widen(self) -> DVec3;
    fn narrow(v: DVec3) -> Self;
}

impl Texel for Vec3 {
    fn widen(self) -> DVec3 {
        self.as_dvec3()
    }
    fn narrow(v: DVec3) -> Self {
        v.as_vec3()
    }
}

impl Texel for f64 {
    fn widen(self) -> DVec3 {
        DVec3::splat(self)
    }
    fn narrow(v: DVec3) -> Self {
        v.x
    }
}

/// Cells per texel along each axis of the sampling distribution: 4 (16 cells between four
/// texel centres, each weighted by the bilinear radiance at its centre, which follows the
/// lookup closely) for maps of up to 2^18 pixels, 2 up to 2^20, else 1.
fn subdivision(width: usize, height: usize) -> usize {
    match width * height {
        n if n <= 1 << 18 => 4,
        n if n <= 1 << 20 => 2,
        _ => 1,
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

    /// What a sample carries is what the direction evaluates to: the same cell's density,
    /// and the radiance to rounding; and the guided inversions land in the cells a binary
    /// search finds.
    #[test]
    fn samples_carry_their_radiance_and_density() {
        let (w, h) = (16, 9);
        let mut texels: Vec<Vec3> = (0..w * h)
            .map(|i| Vec3::new(0.1 + (i % 7) as f32, 0.5, 0.2 * (i % 3) as f32))
            .collect();
        texels[2 * w + 5] = Vec3::splat(500.0);
        let to_world = DMat3::from_axis_angle(DVec3::new(0.3, 1.0, -0.2).normalize(), 0.7);
        let m = EnvMap::new(w, h, texels, to_world).unwrap();
        let n = 4000;
        for k in 0..n {
            let u = [
                (k as f64 + 0.5) / n as f64,
                (((k * 7919) % n) as f64 + 0.5) / n as f64,
            ];
            let s = m.sample(u);
            let (radiance, pdf) = m.eval_pdf(s.dir);
            assert!((pdf - s.pdf).abs() <= 1e-9 * pdf, "{u:?}: {pdf} {}", s.pdf);
            assert!((radiance - s.radiance).abs().max_element() <= 1e-4 * radiance.max_element());
            let row = m
                .row_cdf
                .partition_point(|&c| c <= u[1] * m.row_cdf[m.rows - 1]);
            let local = m.from_world * s.dir;
            assert_eq!(
                trig::floor(trig::acos(local.y) / PI * m.rows as f64) as usize,
                row
            );
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
