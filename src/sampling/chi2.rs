//! χ² goodness-of-fit harness shared by the sampler tests (after Mitsuba 3's `chi2` and
//! pbrt-v4's sampling tests): draw many samples, histogram them over a binning, integrate the
//! claimed density over every bin by quadrature to get the expected counts, pool the bins
//! expected to hold fewer than 5 samples, and compute Pearson's statistic and its p-value.
//!
//! Test support only: it depends on the dev-dependency `statrs`, so it is not part of the
//! library; test crates include it with `#[path = "../src/sampling/chi2.rs"] mod chi2;`. It
//! uses nothing of the crate, only `glam`, `rand`, `rand_pcg` and `statrs`.

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::f64::consts::PI;
use std::fmt;

/// Šidák-corrected significance of each of `tests` tests, for an overall level `alpha`.
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests as f64)
}

/// A test file's family of χ² tests that must accept, `0.01` overall: each accepts above the
/// Šidák-corrected significance, and each must-reject twin must fall at or below it.
pub struct Family {
    /// The tests that must accept (keep it in step with the file).
    pub tests: usize,
}

impl Family {
    pub fn significance(&self) -> f64 {
        sidak(0.01, self.tests)
    }

    /// Asserts that `c` (of `hist`, every sample with a finite positive density) accepts.
    pub fn accept(&self, name: &str, hist: &Histogram, c: &Chi2) {
        println!("accept {name}: {c}");
        assert_eq!(
            hist.bad_pdf, 0,
            "{name}: samples without finite positive pdf"
        );
        assert!(
            c.impossible.is_none() && c.p_value > self.significance(),
            "{name}: {c}, significance {:.2e}",
            self.significance()
        );
    }

    /// Asserts that `c` (a deliberately wrong density) rejects.
    pub fn reject(&self, name: &str, c: &Chi2) {
        println!("reject {name}: {c}");
        assert!(
            c.p_value <= self.significance(),
            "{name} was not rejected: {c}, significance {:.2e}",
            self.significance()
        );
    }
}

/// A partition of a sampler's domain into bins that can be integrated over.
pub trait Binning {
    /// A sample: a direction, or a point with its triangle.
    type Point;
    fn bins(&self) -> usize;
    /// The bin of `x`, or `None` if `x` is outside the domain (a sampler bug).
    fn bin_of(&self, x: &Self::Point) -> Option<usize>;
    /// `∫ pdf` over `bin`, by quadrature.
    fn integrate(&self, bin: usize, pdf: &dyn Fn(&Self::Point) -> f64) -> f64;
}

/// Sample counts per bin.
pub struct Histogram {
    pub counts: Vec<u64>,
    pub samples: u64,
    /// Samples that fell in no bin (non-finite, off the domain).
    pub unbinned: u64,
    /// Samples whose own density was not finite and positive.
    pub bad_pdf: u64,
}

/// Draws `samples` samples from `sample` (three uniform numbers each, from a generator seeded
/// with `seed`) and bins them; `pdf` is evaluated at each one to count those it gives no
/// finite positive density.
pub fn histogram<B: Binning>(
    binning: &B,
    samples: u64,
    seed: u64,
    mut sample: impl FnMut([f64; 3]) -> B::Point,
    pdf: impl Fn(&B::Point) -> f64,
) -> Histogram {
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut h = Histogram {
        counts: vec![0; binning.bins()],
        samples,
        unbinned: 0,
        bad_pdf: 0,
    };
    for _ in 0..samples {
        let x = sample([rng.random(), rng.random(), rng.random()]);
        let p = pdf(&x);
        if !(p.is_finite() && p > 0.0) {
            h.bad_pdf += 1;
        }
        match binning.bin_of(&x) {
            Some(bin) => h.counts[bin] += 1,
            None => h.unbinned += 1,
        }
    }
    h
}

/// The outcome of one χ² test.
#[derive(Clone, Debug)]
pub struct Chi2 {
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// `∫ pdf` over all bins: 1 for a normalised density, up to quadrature error.
    pub pdf_total: f64,
    /// Why the test failed before any statistic, if it did.
    pub impossible: Option<String>,
}

impl fmt::Display for Chi2 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "chi2 = {:.1}, dof = {}, p = {:.3e}, integral of pdf = {:.9}",
            self.statistic, self.dof, self.p_value, self.pdf_total
        )?;
        if let Some(why) = &self.impossible {
            write!(f, " ({why})")?;
        }
        Ok(())
    }
}

/// Bins expected to hold fewer samples than this are pooled (the usual rule of thumb).
const MIN_EXPECTED: f64 = 5.0;

/// Pearson's χ² of `hist` against the counts that `pdf` predicts over `binning`.
pub fn chi2<B: Binning>(binning: &B, hist: &Histogram, pdf: impl Fn(&B::Point) -> f64) -> Chi2 {
    let mass: Vec<f64> = (0..binning.bins())
        .map(|bin| binning.integrate(bin, &pdf))
        .collect();
    let pdf_total = mass.iter().sum();
    let fail = |why: String| Chi2 {
        statistic: f64::INFINITY,
        dof: 0,
        p_value: 0.0,
        pdf_total,
        impossible: Some(why),
    };
    if hist.unbinned > 0 {
        return fail(format!("{} samples fell in no bin", hist.unbinned));
    }
    let n = hist.samples as f64;
    let mut pairs = Vec::new();
    for (bin, (&m, &observed)) in mass.iter().zip(&hist.counts).enumerate() {
        if !(m.is_finite() && m >= 0.0) {
            return fail(format!("bin {bin} has probability {m}"));
        }
        if m == 0.0 && observed > 0 {
            return fail(format!("{observed} samples in bin {bin} of probability 0"));
        }
        if m > 0.0 {
            pairs.push((n * m, observed as f64));
        }
    }
    // Pool the sparse bins, smallest first, until each pool expects enough samples; a
    // remainder that still expects too few joins the last cell.
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut cells: Vec<(f64, f64)> = Vec::new();
    let mut pool = (0.0, 0.0);
    for (expected, observed) in pairs {
        pool = (pool.0 + expected, pool.1 + observed);
        if pool.0 >= MIN_EXPECTED {
            cells.push(pool);
            pool = (0.0, 0.0);
        }
    }
    if pool.0 > 0.0 {
        match cells.last_mut() {
            Some(last) => *last = (last.0 + pool.0, last.1 + pool.1),
            None => cells.push(pool),
        }
    }
    assert!(
        cells.len() >= 2,
        "binning too coarse for a χ² test ({} cells)",
        cells.len()
    );
    let statistic = cells.iter().map(|(e, o)| (o - e) * (o - e) / e).sum();
    let dof = cells.len() - 1;
    let p_value = ChiSquared::new(dof as f64)
        .expect("positive degrees of freedom")
        .sf(statistic);
    Chi2 {
        statistic,
        dof,
        p_value,
        pdf_total,
        impossible: None,
    }
}

/// Draws a histogram and tests it against `pdf` (the usual single-pdf case).
pub fn chi2_test<B: Binning>(
    binning: &B,
    samples: u64,
    seed: u64,
    sample: impl FnMut([f64; 3]) -> B::Point,
    pdf: impl Fn(&B::Point) -> f64 + Copy,
) -> (Histogram, Chi2) {
    let hist = histogram(binning, samples, seed, sample, pdf);
    let result = chi2(binning, &hist, pdf);
    (hist, result)
}

/// The sphere of directions binned in `(h, φ)` about an axis, `h = 1 − cos θ`. Solid angle
/// is `dh dφ`, so bins of equal `Δh·Δφ` have equal area. Edges in `h` may be placed where the
/// density jumps (a cone's edge), finely enough that a tiny cap spans several bins.
pub struct SphereBins {
    axis: DVec3,
    t: DVec3,
    b: DVec3,
    /// Increasing, from 0 to 2.
    h_edges: Vec<f64>,
    n_phi: usize,
    /// Depth at which the quadrature first checks convergence ([`Self::resolving`]).
    min_depth: u32,
}

/// Adaptive quadrature: depth at which convergence is first checked (so that a small
/// feature cannot hide between the nodes of a whole bin), and the deepest split.
const MIN_DEPTH: u32 = 2;
const MAX_DEPTH: u32 = 10;
/// Absolute tolerance on one bin's probability; halved at each split.
const TOLERANCE: f64 = 1e-9;
/// How far, relative to a cell, Simpson's edge nodes are pulled inside it.
const EDGE_PULL: f64 = 1e-6;

impl SphereBins {
    pub fn new(axis: DVec3, h_edges: Vec<f64>, n_phi: usize) -> Self {
        assert!(h_edges.first() == Some(&0.0) && h_edges.last() == Some(&2.0));
        assert!(h_edges.windows(2).all(|w| w[0] < w[1]) && n_phi > 0);
        let axis = axis.normalize();
        // Any orthonormal frame will do: the harness must not share the samplers' code.
        let helper = if axis.x.abs() < 0.9 {
            DVec3::X
        } else {
            DVec3::Y
        };
        let t = helper.cross(axis).normalize();
        Self {
            axis,
            t,
            b: axis.cross(t),
            h_edges,
            min_depth: MIN_DEPTH,
            n_phi,
        }
    }

    /// `n_h × n_phi` bins of equal solid angle.
    pub fn equal_area(axis: DVec3, n_h: usize, n_phi: usize) -> Self {
        let edges = (0..=n_h).map(|i| 2.0 * i as f64 / n_h as f64).collect();
        Self::new(axis, edges, n_phi)
    }

    /// These bins with the quadrature checking convergence only from `min_depth` splits on
    /// (`4^min_depth` cells per bin): densities whose discontinuities enclose small or thin
    /// regions (a patch's corner, a sliver seen edge-on) that could hide between the nodes of
    /// a coarser start.
    pub fn resolving(mut self, min_depth: u32) -> Self {
        self.min_depth = min_depth.min(MAX_DEPTH);
        self
    }

    /// `n_in` bins of equal area in the cap `h ≤ h_split` and `n_out` over the rest, each
    /// ring cut into `n_phi` sectors.
    pub fn split_at(axis: DVec3, h_split: f64, n_in: usize, n_out: usize, n_phi: usize) -> Self {
        assert!(h_split > 0.0 && h_split < 2.0);
        let mut edges: Vec<f64> = (0..n_in)
            .map(|i| h_split * i as f64 / n_in as f64)
            .collect();
        edges.extend((0..n_out).map(|i| h_split + (2.0 - h_split) * i as f64 / n_out as f64));
        edges.push(2.0);
        Self::new(axis, edges, n_phi)
    }

    /// `(h, φ)` of unit `d`; `h` from the chord to the nearer pole so it keeps its relative
    /// precision for directions within 1e-7 rad of either pole.
    fn coords(&self, d: DVec3) -> (f64, f64) {
        let h = if d.dot(self.axis) >= 0.0 {
            0.5 * (d - self.axis).length_squared()
        } else {
            2.0 - 0.5 * (d + self.axis).length_squared()
        };
        let phi = d.dot(self.b).atan2(d.dot(self.t));
        (h, if phi < 0.0 { phi + 2.0 * PI } else { phi })
    }

    fn direction(&self, h: f64, phi: f64) -> DVec3 {
        let sin_t = (h * (2.0 - h)).max(0.0).sqrt();
        let (sp, cp) = phi.sin_cos();
        (self.t * (sin_t * cp) + self.b * (sin_t * sp) + self.axis * (1.0 - h)).normalize()
    }
}

/// `∫∫ f` over a rectangle by the tensor Simpson rule with its edge nodes pulled inside by
/// [`EDGE_PULL`]: a jump anywhere in the cell separates two nodes, so the adaptive split
/// notices it (Gauss nodes leave a blind strip along the edges), yet a jump lying exactly on
/// the cell's edge (a bin edge placed on a cone's edge) is never straddled by rounding.
fn simpson(f: &dyn Fn(f64, f64) -> f64, [x0, x1, y0, y1]: [f64; 4]) -> f64 {
    let nodes = |a: f64, b: f64| {
        [
            a + EDGE_PULL * (b - a),
            0.5 * (a + b),
            b - EDGE_PULL * (b - a),
        ]
    };
    const W: [f64; 3] = [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0];
    let (xs, ys) = (nodes(x0, x1), nodes(y0, y1));
    let mut sum = 0.0;
    for (x, wx) in xs.iter().zip(W) {
        for (y, wy) in ys.iter().zip(W) {
            sum += wx * wy * f(*x, *y);
        }
    }
    (x1 - x0) * (y1 - y0) * sum
}

/// Adaptive quadrature: split in four until the split changes the estimate by at most `tol`.
fn adaptive(
    f: &dyn Fn(f64, f64) -> f64,
    r: [f64; 4],
    coarse: f64,
    (tol, min_depth): (f64, u32),
    depth: u32,
) -> f64 {
    let [x0, x1, y0, y1] = r;
    let (xm, ym) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let kids = [
        [x0, xm, y0, ym],
        [xm, x1, y0, ym],
        [x0, xm, ym, y1],
        [xm, x1, ym, y1],
    ];
    let parts = kids.map(|k| simpson(f, k));
    let fine: f64 = parts.iter().sum();
    // An infinite or NaN density cannot converge; χ² rejects it anyway.
    if !fine.is_finite()
        || depth >= MAX_DEPTH
        || (depth >= min_depth && (fine - coarse).abs() <= tol)
    {
        return fine;
    }
    kids.iter()
        .zip(parts)
        .map(|(&k, part)| adaptive(f, k, part, (0.5 * tol, min_depth), depth + 1))
        .sum()
}

impl Binning for SphereBins {
    type Point = DVec3;

    fn bins(&self) -> usize {
        (self.h_edges.len() - 1) * self.n_phi
    }

    fn bin_of(&self, d: &DVec3) -> Option<usize> {
        if !(d.is_finite() && (d.length() - 1.0).abs() < 1e-9) {
            return None;
        }
        let (h, phi) = self.coords(*d);
        let ring = self
            .h_edges
            .partition_point(|&e| e <= h)
            .clamp(1, self.h_edges.len() - 1)
            - 1;
        let sector = ((phi / (2.0 * PI) * self.n_phi as f64) as usize).min(self.n_phi - 1);
        Some(ring * self.n_phi + sector)
    }

    fn integrate(&self, bin: usize, pdf: &dyn Fn(&DVec3) -> f64) -> f64 {
        let (ring, sector) = (bin / self.n_phi, bin % self.n_phi);
        let dphi = 2.0 * PI / self.n_phi as f64;
        let rect = [
            self.h_edges[ring],
            self.h_edges[ring + 1],
            sector as f64 * dphi,
            (sector + 1) as f64 * dphi,
        ];
        let f = |h: f64, phi: f64| pdf(&self.direction(h, phi));
        adaptive(&f, rect, simpson(&f, rect), (TOLERANCE, self.min_depth), 0)
    }
}

/// Points on triangles, binned by triangle and by the cells of a regular grid of `n`
/// divisions per edge in barycentric coordinates (`n²` congruent cells per triangle). For
/// `n = 2^m` the cells are those of the m-fold midpoint subdivision, so a density constant on
/// such cells is integrated exactly.
pub struct TriangleBins {
    /// `(prim, vertices)` of each triangle of the domain.
    tris: Vec<(u32, [DVec3; 3])>,
    n: usize,
}

/// Levels of midpoint subdivision of a cell for its quadrature (4^this centroids).
const CELL_QUADRATURE_LEVELS: u32 = 2;

impl TriangleBins {
    pub fn new(tris: Vec<(u32, [DVec3; 3])>, n: usize) -> Self {
        assert!(n > 0 && !tris.is_empty());
        Self { tris, n }
    }

    /// Every cell `(triangle, i, j, flipped)` as a dense index; cells with `i + j ≥ n` (or
    /// `n − 1` when flipped) do not exist and keep probability 0.
    fn index(&self, tri: usize, i: usize, j: usize, flipped: bool) -> usize {
        ((tri * self.n + i) * self.n + j) * 2 + usize::from(flipped)
    }

    /// Barycentric coordinates `(b1, b2)` of the cell's vertices, or `None` if it does not exist.
    fn cell(&self, bin: usize) -> Option<(usize, [(f64, f64); 3])> {
        let flipped = bin % 2 == 1;
        let j = (bin / 2) % self.n;
        let i = (bin / 2 / self.n) % self.n;
        let tri = bin / 2 / self.n / self.n;
        let k = self.n as f64;
        let (x, y) = (i as f64 / k, j as f64 / k);
        let s = 1.0 / k;
        if flipped && i + j + 2 <= self.n {
            Some((tri, [(x + s, y), (x + s, y + s), (x, y + s)]))
        } else if !flipped && i + j < self.n {
            Some((tri, [(x, y), (x + s, y), (x, y + s)]))
        } else {
            None
        }
    }
}

/// `Σ pdf(centroid) · area` over the `4^levels` midpoint sub-triangles of `[a, b, c]`.
fn centroid_rule(f: &dyn Fn(DVec3) -> f64, [a, b, c]: [DVec3; 3], levels: u32) -> f64 {
    if levels == 0 {
        return f((a + b + c) / 3.0) * 0.5 * (b - a).cross(c - a).length();
    }
    let (ab, bc, ca) = (0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a));
    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [bc, ca, ab]]
        .into_iter()
        .map(|t| centroid_rule(f, t, levels - 1))
        .sum()
}

impl Binning for TriangleBins {
    type Point = (u32, DVec3);

    fn bins(&self) -> usize {
        self.tris.len() * self.n * self.n * 2
    }

    fn bin_of(&self, &(prim, p): &(u32, DVec3)) -> Option<usize> {
        let tri = self.tris.iter().position(|&(q, _)| q == prim)?;
        let [a, b, c] = self.tris[tri].1;
        let (e1, e2, d) = (b - a, c - a, p - a);
        // The point must lie on the triangle's plane, within rounding.
        let normal = e1.cross(e2).normalize();
        if !(p.is_finite() && d.dot(normal).abs() <= 1e-9 * (1.0 + d.length())) {
            return None;
        }
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let det = d11 * d22 - d12 * d12;
        let b1 = (d22 * d.dot(e1) - d12 * d.dot(e2)) / det;
        let b2 = (d11 * d.dot(e2) - d12 * d.dot(e1)) / det;
        const SLACK: f64 = 1e-9;
        if b1 < -SLACK || b2 < -SLACK || b1 + b2 > 1.0 + SLACK {
            return None;
        }
        let k = self.n as f64;
        let (x, y) = (b1.max(0.0) * k, b2.max(0.0) * k);
        let i = (x as usize).min(self.n - 1);
        let j = (y as usize).min(self.n - 1 - i);
        let flipped = (x - i as f64) + (y - j as f64) > 1.0 && i + j + 2 <= self.n;
        Some(self.index(tri, i, j, flipped))
    }

    fn integrate(&self, bin: usize, pdf: &dyn Fn(&(u32, DVec3)) -> f64) -> f64 {
        let Some((tri, corners)) = self.cell(bin) else {
            return 0.0;
        };
        let (prim, [a, b, c]) = self.tris[tri];
        let at = |(b1, b2): (f64, f64)| a + (b - a) * b1 + (c - a) * b2;
        centroid_rule(
            &|p| pdf(&(prim, p)),
            corners.map(at),
            CELL_QUADRATURE_LEVELS,
        )
    }
}
