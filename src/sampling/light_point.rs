//! The light-point sampler (the paper's §6 optimises "the sample point on the light
//! surface" too): the density over emitter area of the shadow ray's end point. Mass `β`
//! lies uniformly on an anchor region — an emitter triangle or one cell of its fixed 4^k
//! midpoint subdivision, whose area is exactly the triangle's over 4^k — and `1 − β`
//! uniformly over all emitters by area.
//!
//! Subdivision: each level splits a triangle `(v0, v1, v2)` at its edge midpoints `m01, m12,
//! m20` into four congruent children, numbered 0..3: child `i < 3` is the corner triangle at
//! `vi` (its vertices keep their positions: `(v0, m01, m20)`, `(m01, v1, m12)`,
//! `(m20, m12, v2)`) and child 3 is the middle one `(m12, m20, m01)`, whose vertex `i` faces
//! `vi`. A cell index at level `k` is `k` base-4 digits, the coarsest level most significant.
//! A point on an edge shared by children belongs to the middle child (a corner takes only the
//! points with barycentric coordinate strictly above 1/2 at its vertex).
//!
//! An analytic emitter (a sphere or a disk) is one region of level 0, sampled uniformly by
//! area like the rest: the density is the same simple one, and unbiased, though on a sphere
//! half the points land on the side the shading point does not see.

use crate::accel::TriangleMesh;
use crate::math::uniform_in_triangle;
use crate::scene::Emitters;
use glam::DVec3;

/// Finest subdivision level: 4^16 cells still have `u32` indices.
pub const MAX_LEVEL: u8 = 16;

/// Invalid parameters of a [`LightPointSampler`].
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum LightPointError {
    #[error("triangle {0} is not an emitter")]
    NotEmitter(u32),
    #[error("subdivision level {0} is above {MAX_LEVEL}")]
    Level(u8),
    #[error("cell {cell} does not exist at level {level} (4^level cells)")]
    Cell { level: u8, cell: u32 },
    #[error("primitive {0} is an analytic shape: its only region is level 0")]
    AnalyticLevel(u32),
    #[error("probability on the region {0} is not in [0, 1)")]
    Beta(f64),
}

/// One cell of the 4^`level` subdivision of emitter triangle `prim`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightRegion {
    pub prim: u32,
    pub level: u8,
    /// Index in `0..4^level` (module docs).
    pub cell: u32,
}

impl LightRegion {
    /// The region of `level` on triangle `prim` that contains `point` (a point on it); on an
    /// analytic shape, the shape (level 0).
    pub fn containing(mesh: &TriangleMesh, prim: u32, level: u8, point: DVec3) -> Self {
        if mesh.analytic(prim).is_some() {
            return Self {
                prim,
                level: 0,
                cell: 0,
            };
        }
        Self {
            prim,
            level,
            cell: cell_of(barycentric(vertices(mesh, prim), point), level),
        }
    }

    /// Area of the region: the triangle's area over 4^level, exactly.
    pub fn area(&self, mesh: &TriangleMesh) -> f64 {
        // 4^-level is a power of two: the division is exact.
        mesh.area(self.prim) / cells_at(self.level) as f64
    }

    /// A point uniform by area in the region.
    fn sample(&self, mesh: &TriangleMesh, u1: f64, u2: f64) -> DVec3 {
        match mesh.analytic(self.prim) {
            Some(shape) => shape.sample_area(u1, u2),
            None => uniform_in_triangle(self.vertices(mesh), u1, u2),
        }
    }

    /// The region's three vertices in space (of a triangle's region).
    pub fn vertices(&self, mesh: &TriangleMesh) -> [DVec3; 3] {
        let [a, b, c] = vertices(mesh, self.prim);
        cell_barycentrics(self.cell, self.level).map(|w| a * w.x + b * w.y + c * w.z)
    }

    /// Whether the region names an analytic shape below level 0 (there is no such cell).
    pub fn is_invalid_on(&self, mesh: &TriangleMesh) -> bool {
        self.level > 0 && mesh.analytic(self.prim).is_some()
    }

    /// Whether `point`, a point on primitive `prim`, lies in the region.
    pub fn contains(&self, mesh: &TriangleMesh, prim: u32, point: DVec3) -> bool {
        prim == self.prim
            && (mesh.analytic(prim).is_some()
                || cell_of(barycentric(vertices(mesh, prim), point), self.level) == self.cell)
    }

    /// Whether a point on the region's triangle lies in the region, given `cell_at(level)`,
    /// the point's cell of a level ([`PointCells::at`]): asked only below level 0, where
    /// the region is not the whole triangle.
    fn holds(&self, cell_at: impl FnOnce(u8) -> u32) -> bool {
        self.level == 0 || cell_at(self.level) == self.cell
    }
}

/// The cell of level [`MAX_LEVEL`] that holds `point` on primitive `prim` (0 on an analytic
/// shape, which has none): every coarser level's cell is its leading digits
/// ([`PointCells::of_finest`]).
pub fn finest_cell(mesh: &TriangleMesh, prim: u32, point: DVec3) -> u32 {
    match mesh.analytic(prim) {
        Some(_) => 0,
        None => PointCells::new(mesh, prim, point).at(MAX_LEVEL),
    }
}

/// The cells that hold one point on a triangle, found digit by digit, coarsest first, and
/// only as deep as asked: a light region of level 2 needs two digits of its point, not
/// [`MAX_LEVEL`]'s sixteen.
#[derive(Clone, Copy, Debug)]
pub struct PointCells {
    /// The point's barycentric coordinates within the cell of `level`.
    w: DVec3,
    level: u8,
    /// The cell of `level`.
    cell: u32,
}

impl PointCells {
    /// The cells of `point` on triangle `prim` (whose analytic shapes have no cells below
    /// level 0, which [`LightRegion::holds`] never asks of).
    pub fn new(mesh: &TriangleMesh, prim: u32, point: DVec3) -> Self {
        Self::of(match mesh.analytic(prim) {
            Some(_) => DVec3::ONE / 3.0,
            None => barycentric(vertices(mesh, prim), point),
        })
    }

    /// The cells of the point of barycentric coordinates `w`.
    fn of(w: DVec3) -> Self {
        Self {
            w,
            level: 0,
            cell: 0,
        }
    }

    /// The cell of `level` (at most [`MAX_LEVEL`]), finding the digits not found yet.
    pub fn at(&mut self, level: u8) -> u32 {
        while self.level < level {
            let (digit, w) = child(self.w);
            (self.w, self.cell, self.level) = (w, self.cell * 4 + digit, self.level + 1);
        }
        // A u64 shift: all sixteen levels' digits are 32 bits, which a u32 cannot shift out.
        (u64::from(self.cell) >> (2 * u32::from(self.level - level))) as u32
    }

    /// The cell of `level` of the point whose [`finest_cell`] is `finest`: its leading digits.
    pub fn of_finest(finest: u32, level: u8) -> u32 {
        (u64::from(finest) >> (2 * u32::from(MAX_LEVEL - level))) as u32
    }
}

/// [`LightPointSampler::pdf_area`] with its constants computed once, for the many points
/// whose density the fitness evaluates: the region's area and whether it is an analytic
/// shape, and the two values the density takes.
#[derive(Clone, Copy, Debug)]
pub struct LightDensity {
    region: LightRegion,
    analytic: bool,
    /// `(1 − β)/total_area`, and that plus `β/area(region)` (`None` where `β = 0`).
    everywhere: f64,
    in_region: Option<f64>,
}

impl LightDensity {
    /// [`LightPointSampler::pdf_area`] at a point on primitive `prim` whose cell of a level
    /// is `cell_at(level)` ([`PointCells::at`]; asked for only where the region is a cell
    /// below level 0 of a triangle and `prim` that triangle); the same value.
    #[inline]
    pub fn pdf_area(&self, emitters: &Emitters, prim: u32, cell_at: impl FnOnce(u8) -> u32) -> f64 {
        if !emitters.contains(prim) {
            return 0.0;
        }
        match self.in_region {
            Some(density)
                if prim == self.region.prim && (self.analytic || self.region.holds(cell_at)) =>
            {
                density
            }
            _ => self.everywhere,
        }
    }
}

/// Mass `beta` uniformly on `region`, `1 − beta` uniformly over all emitter area.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightPointSampler {
    pub region: LightRegion,
    /// Probability of the region, in [0, 1): below 1 so that every emitter point keeps a
    /// positive density and the estimator stays unbiased.
    pub beta: f64,
}

impl LightPointSampler {
    /// Light points uniform over all emitter area (`β = 0`), the region named by emitter
    /// triangle `prim` unused.
    pub fn uniform(prim: u32) -> Self {
        Self {
            region: LightRegion {
                prim,
                level: 0,
                cell: 0,
            },
            beta: 0.0,
        }
    }

    pub fn new(
        region: LightRegion,
        beta: f64,
        emitters: &Emitters,
    ) -> Result<Self, LightPointError> {
        if !emitters.contains(region.prim) {
            return Err(LightPointError::NotEmitter(region.prim));
        }
        if region.level > MAX_LEVEL {
            return Err(LightPointError::Level(region.level));
        }
        if u64::from(region.cell) >= cells_at(region.level) {
            return Err(LightPointError::Cell {
                level: region.level,
                cell: region.cell,
            });
        }
        if !(0.0..1.0).contains(&beta) {
            return Err(LightPointError::Beta(beta));
        }
        Ok(Self { region, beta })
    }

    /// A point on an emitter and its primitive, from three uniform numbers in [0, 1): `u[0]`
    /// picks the region (probability β) or, rescaled, an emitter by area; `u[1..]` place the
    /// point uniformly in the chosen triangle.
    pub fn sample(&self, mesh: &TriangleMesh, emitters: &Emitters, u: [f64; 3]) -> (DVec3, u32) {
        if u[0] < self.beta {
            (self.region.sample(mesh, u[1], u[2]), self.region.prim)
        } else {
            // `pick` clamps a rescaled number that rounds up to 1.
            let prim = emitters.pick((u[0] - self.beta) / (1.0 - self.beta));
            let point = match mesh.analytic(prim) {
                Some(shape) => shape.sample_area(u[1], u[2]),
                None => uniform_in_triangle(vertices(mesh, prim), u[1], u[2]),
            };
            (point, prim)
        }
    }

    /// The constants of [`Self::pdf_area`], for evaluating it at many points.
    pub fn density(&self, mesh: &TriangleMesh, emitters: &Emitters) -> LightDensity {
        let everywhere = (1.0 - self.beta) / emitters.total_area;
        LightDensity {
            region: self.region,
            analytic: mesh.analytic(self.region.prim).is_some(),
            everywhere,
            in_region: (self.beta > 0.0).then(|| everywhere + self.beta / self.region.area(mesh)),
        }
    }

    /// Area density of [`sample`](Self::sample) at `point`, a point on primitive `prim`:
    /// `β·[point in region]/area(region) + (1−β)/total_area`, and 0 off the emitters.
    pub fn pdf_area(
        &self,
        mesh: &TriangleMesh,
        emitters: &Emitters,
        point: DVec3,
        prim: u32,
    ) -> f64 {
        if !emitters.contains(prim) {
            return 0.0;
        }
        let everywhere = (1.0 - self.beta) / emitters.total_area;
        if self.beta > 0.0 && self.region.contains(mesh, prim, point) {
            everywhere + self.beta / self.region.area(mesh)
        } else {
            everywhere
        }
    }
}

/// Converts an area density at `point` (unit normal `light_normal`, emitting on its side) to
/// a solid-angle density seen from `from`: `pdf_area · d² / cos`, and 0 where `from` is behind
/// the light or on it.
pub fn solid_angle_pdf(pdf_area: f64, from: DVec3, point: DVec3, light_normal: DVec3) -> f64 {
    let to_from = from - point;
    let d2 = to_from.length_squared();
    let cos = light_normal.dot(to_from) / d2.sqrt();
    if cos > 0.0 && d2 > 0.0 {
        pdf_area * d2 / cos
    } else {
        0.0
    }
}

fn cells_at(level: u8) -> u64 {
    1u64 << (2 * u32::from(level))
}

fn vertices(mesh: &TriangleMesh, prim: u32) -> [DVec3; 3] {
    mesh.vertices(prim).map(|v| v.as_dvec3())
}

/// Barycentric coordinates `(b0, b1, b2)` of `p` with respect to `[a, b, c]`, of its
/// projection onto the triangle's plane.
pub fn barycentric([a, b, c]: [DVec3; 3], p: DVec3) -> DVec3 {
    let (e1, e2, d) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (dp1, dp2) = (d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    let b1 = (d22 * dp1 - d12 * dp2) / det;
    let b2 = (d11 * dp2 - d12 * dp1) / det;
    DVec3::new(1.0 - b1 - b2, b1, b2)
}

/// The cell of `level` holding the point of barycentric coordinates `w` (module docs).
fn cell_of(w: DVec3, level: u8) -> u32 {
    PointCells::of(w).at(level)
}

/// The child cell (module docs) that holds the point of barycentric coordinates `w` in its
/// parent, and the point's coordinates in it.
fn child(w: DVec3) -> (u32, DVec3) {
    // Doubling and subtracting 1 from a value in [1/2, 1] are exact.
    if w.x > 0.5 {
        (0, DVec3::new(2.0 * w.x - 1.0, 2.0 * w.y, 2.0 * w.z))
    } else if w.y > 0.5 {
        (1, DVec3::new(2.0 * w.x, 2.0 * w.y - 1.0, 2.0 * w.z))
    } else if w.z > 0.5 {
        (2, DVec3::new(2.0 * w.x, 2.0 * w.y, 2.0 * w.z - 1.0))
    } else {
        (3, DVec3::ONE - 2.0 * w)
    }
}

/// Barycentric coordinates of the three vertices of `cell` at `level` (module docs); they are
/// dyadic rationals, exact in `f64`.
fn cell_barycentrics(cell: u32, level: u8) -> [DVec3; 3] {
    let mut v = [DVec3::X, DVec3::Y, DVec3::Z];
    for l in (0..level).rev() {
        let mid = |i: usize, j: usize| 0.5 * (v[i] + v[j]);
        let (m01, m12, m20) = (mid(0, 1), mid(1, 2), mid(2, 0));
        v = match (cell >> (2 * u32::from(l))) & 3 {
            0 => [v[0], m01, m20],
            1 => [m01, v[1], m12],
            2 => [m20, m12, v[2]],
            _ => [m12, m20, m01],
        };
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_partition_the_triangle_and_map_back_to_themselves() {
        for level in 0..=4u8 {
            let mut area = 0.0;
            for cell in 0..cells_at(level) as u32 {
                let [p, q, r] = cell_barycentrics(cell, level);
                let a = 0.5 * (q - p).cross(r - p).length();
                // Unit barycentric simplex has area √3/2; every cell is 1/4^level of it.
                let expected = 0.75f64.sqrt() / cells_at(level) as f64;
                assert!((a - expected).abs() < 1e-14, "level {level} cell {cell}");
                area += a;
                assert_eq!(cell_of((p + q + r) / 3.0, level), cell);
                // Points just inside each corner belong to the cell too.
                for (x, y, z) in [(p, q, r), (q, r, p), (r, p, q)] {
                    assert_eq!(cell_of(x * 0.98 + y * 0.01 + z * 0.01, level), cell);
                }
            }
            assert!((area - 0.75f64.sqrt()).abs() < 1e-12);
        }
    }

    #[test]
    fn the_finest_cell_names_the_cell_of_every_level() {
        for i in 0..500 {
            // Points spread over the triangle, some on the cells' shared edges.
            let (a, b) = ((i as f64 * 0.618_034) % 1.0, (i as f64 * 0.414_214) % 1.0);
            let (a, b) = if i % 7 == 0 {
                (0.25 * (i % 4) as f64, 0.5)
            } else {
                (a, b)
            };
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let w = DVec3::new(1.0 - a - b, a, b);
            let finest = cell_of(w, MAX_LEVEL);
            // One asked coarsest first (a digit more each time), one deepest first.
            let (mut rising, mut cells) = (PointCells::of(w), PointCells::of(w));
            for level in 0..=MAX_LEVEL {
                let region = |cell| LightRegion {
                    prim: 0,
                    level,
                    cell,
                };
                let cell = cell_of(w, level);
                // The finest cell's leading digits, and the digits found as deep as asked
                // (deepest first, then coarser from them), name the same cell.
                let of_finest = |l| PointCells::of_finest(finest, l);
                assert!(region(cell).holds(of_finest), "{w} at level {level}");
                assert_eq!(cells.at(MAX_LEVEL - level), cell_of(w, MAX_LEVEL - level));
                assert_eq!(cells.at(level), cell, "{w} at level {level}");
                assert_eq!(rising.at(level), cell, "{w} at level {level}");
                // Another cell of the level does not hold it: the check can fail.
                if level > 0 {
                    assert!(!region(cell ^ 1).holds(of_finest), "{w} at level {level}");
                }
            }
        }
    }

    #[test]
    fn shared_edges_go_to_the_middle_child() {
        // The midpoint of v0–v1 lies on corner children 0 and 1 and the middle one.
        assert_eq!(cell_of(DVec3::new(0.5, 0.5, 0.0), 1), 3);
        assert_eq!(cell_of(DVec3::new(0.5, 0.25, 0.25), 1), 3);
        assert_eq!(cell_of(DVec3::new(0.5 + 1e-12, 0.25, 0.25 - 1e-12), 1), 0);
    }

    #[test]
    fn barycentrics_recover_a_point() {
        let t = [
            DVec3::new(0.1, 2.0, -1.0),
            DVec3::new(1.7, 2.2, -0.5),
            DVec3::new(-0.4, 1.1, 0.9),
        ];
        let w = DVec3::new(0.2, 0.3, 0.5);
        let p = t[0] * w.x + t[1] * w.y + t[2] * w.z;
        assert!((barycentric(t, p) - w).abs().max_element() < 1e-14);
    }

    #[test]
    fn solid_angle_conversion() {
        let n = DVec3::new(0.0, -1.0, 0.0);
        let light = DVec3::new(0.0, 2.0, 0.0);
        // Straight below at distance 2: d²/cos = 4.
        assert_eq!(solid_angle_pdf(0.5, DVec3::ZERO, light, n), 2.0);
        // At 60° from the normal, distance 4: d²/cos = 32.
        let from = light + 4.0 * DVec3::new(60f64.to_radians().sin(), -0.5, 0.0);
        assert!((solid_angle_pdf(1.0, from, light, n) - 32.0).abs() < 1e-12);
        // Behind the one-sided light, or on it: no density.
        assert_eq!(
            solid_angle_pdf(1.0, DVec3::new(0.0, 3.0, 0.0), light, n),
            0.0
        );
        assert_eq!(solid_angle_pdf(1.0, light, light, n), 0.0);
    }
}
