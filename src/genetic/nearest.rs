//! The `k` nearest of a set of pixel positions, for the interpolation of GA pixels' mixtures
//! at every image pixel.
//!
//! A scan over all points per pixel costs `pixels × points`: on a 1920 × 1080 image with a
//! GA pixel every 32 pixels, 2 million × 2 000 distances. [`PointGrid`] buckets the points in
//! square cells of about one point each and visits rings of cells around the query until no
//! unvisited point can be nearer than the `k`-th found; it returns what the scan returns,
//! ties included.

/// Points bucketed by cell (compressed rows: `start[c]..start[c + 1]` indexes `items`).
#[derive(Clone, Debug, Default)]
pub struct PointGrid {
    points: Vec<(u32, u32)>,
    /// Cell edge in pixels.
    cell: u32,
    cols: u32,
    rows: u32,
    start: Vec<u32>,
    /// Point indices, by cell and, within a cell, ascending.
    items: Vec<u32>,
}

impl PointGrid {
    /// The grid of `points` (pixel positions; they may lie outside the image) for an image
    /// of `width × height`.
    pub fn new(points: Vec<(u32, u32)>, width: u32, height: u32) -> Self {
        let w = points.iter().map(|p| p.0 + 1).fold(width.max(1), u32::max);
        let h = points.iter().map(|p| p.1 + 1).fold(height.max(1), u32::max);
        // About one point per cell.
        let area = w as f64 * h as f64;
        let cell = (area / points.len().max(1) as f64).sqrt().ceil().max(1.0) as u32;
        let (cols, rows) = (w.div_ceil(cell), h.div_ceil(cell));
        let cell_of = |&(x, y): &(u32, u32)| ((y / cell) * cols + x / cell) as usize;
        let mut start = vec![0u32; (cols * rows) as usize + 1];
        for p in &points {
            start[cell_of(p) + 1] += 1;
        }
        for c in 1..start.len() {
            start[c] += start[c - 1];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; points.len()];
        for (i, p) in points.iter().enumerate() {
            let c = cell_of(p);
            items[fill[c] as usize] = i as u32;
            fill[c] += 1;
        }
        Self {
            points,
            cell,
            cols,
            rows,
            start,
            items,
        }
    }

    /// Squared distance of point `i` to `(x, y)`.
    fn distance2(&self, i: usize, x: u32, y: u32) -> f64 {
        let (px, py) = self.points[i];
        (px as f64 - x as f64).powi(2) + (py as f64 - y as f64).powi(2)
    }

    /// The `k` points nearest to `(x, y)` as `(squared distance, index)`, ascending, ties by
    /// index, into `out`: what [`Self::nearest_by_scan`] gives.
    pub fn nearest(&self, x: u32, y: u32, k: usize, out: &mut Vec<(f64, usize)>) {
        self.search(x, y, k, out, 1.0);
    }

    /// [`Self::nearest`], stopping once the `k`-th distance is within `reach` times the
    /// radius searched: 1 is exact; more is a wrong input for the tests.
    fn search(&self, x: u32, y: u32, k: usize, out: &mut Vec<(f64, usize)>, reach: f64) {
        out.clear();
        if self.points.is_empty() || k == 0 {
            return;
        }
        let (cx, cy) = ((x / self.cell) as i64, (y / self.cell) as i64);
        let (cols, rows) = (self.cols as i64, self.rows as i64);
        let visit = |gx: i64, gy: i64, out: &mut Vec<(f64, usize)>| {
            let c = (gy * cols + gx) as usize;
            for &i in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                out.push((self.distance2(i as usize, x, y), i as usize));
            }
        };
        for r in 0i64.. {
            // The cells at Chebyshev distance r from the query's cell, within the grid.
            for gy in (cy - r).max(0)..=(cy + r).min(rows - 1) {
                if (gy - cy).abs() == r {
                    for gx in (cx - r).max(0)..=(cx + r).min(cols - 1) {
                        visit(gx, gy, out);
                    }
                } else {
                    if cx - r >= 0 {
                        visit(cx - r, gy, out);
                    }
                    if cx + r < cols {
                        visit(cx + r, gy, out);
                    }
                }
            }
            let everything = cx - r <= 0 && cy - r <= 0 && cx + r >= cols - 1 && cy + r >= rows - 1;
            if everything {
                break;
            }
            // Every point outside rings 0..=r is more than r cells from the query, which lies
            // inside cell (cx, cy): strictly farther than r · cell.
            let bound = reach * (r as f64 * self.cell as f64);
            if out.len() >= k {
                select(out, k);
                if out[k - 1].0 <= bound * bound {
                    break;
                }
            }
        }
        select(out, k);
    }

    /// The reference: every point's distance, the `k` smallest kept.
    pub fn nearest_by_scan(&self, x: u32, y: u32, k: usize, out: &mut Vec<(f64, usize)>) {
        out.clear();
        out.extend((0..self.points.len()).map(|i| (self.distance2(i, x, y), i)));
        select(out, k);
    }
}

/// Keeps the `k` smallest `(distance, index)` pairs of `v`, sorted.
fn select(v: &mut Vec<(f64, usize)>, k: usize) {
    v.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    v.truncate(k);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_rng, uniform};

    /// Ring search against the scan: random, regular (ties everywhere), clustered,
    /// duplicated and out-of-image points, every pixel of the image queried, several `k`.
    #[test]
    fn ring_search_finds_what_the_scan_finds() {
        let (w, h) = (67, 45);
        let mut rng = sample_rng(3, 0, 0);
        let mut random = |n: u32| (uniform(&mut rng) * n as f32) as u32;
        let regular = || -> Vec<(u32, u32)> {
            (0..9)
                .flat_map(|i| (0..6).map(move |j| (i * 8, j * 8)))
                .collect()
        };
        let sets: Vec<Vec<(u32, u32)>> = vec![
            (0..40).map(|_| (random(w), random(h))).collect(),
            regular(),
            vec![(1, 1), (1, 1), (2, 1), (0, 3), (3, 3), (500, 2)],
            vec![(10, 10)],
        ];
        let (mut fast, mut slow) = (Vec::new(), Vec::new());
        let mut queries = 0;
        for points in sets {
            let grid = PointGrid::new(points, w, h);
            for k in [1, 4, 7] {
                for y in 0..h {
                    for x in 0..w {
                        grid.nearest(x, y, k, &mut fast);
                        grid.nearest_by_scan(x, y, k, &mut slow);
                        assert_eq!(fast, slow, "({x}, {y}), k = {k}");
                        queries += 1;
                    }
                }
            }
        }
        assert_eq!(queries, 4 * 3 * 67 * 45);
        // The comparison is not vacuous: a search that stops at twice the safe radius must
        // disagree with the scan somewhere.
        let grid = PointGrid::new(regular(), w, h);
        let wrong = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                grid.search(x, y, 4, &mut fast, 2.0);
                grid.nearest_by_scan(x, y, 4, &mut slow);
                fast != slow
            })
            .count();
        assert!(wrong > 0, "a search with twice the reach agrees everywhere");
    }
}
