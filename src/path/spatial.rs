//! A spatial guide for the vertices a pixel's mixture does not reach (beyond the paper).
//!
//! The genetic algorithm learns, per pixel, where light arrives from at the first vertices of
//! that pixel's paths. Deeper vertices lie anywhere in the scene, and a per-pixel mixture
//! says little about them. This guide learns incident light per region of space instead,
//! after "practical path guiding" (Müller, Gross and Novák 2017): a spatial-directional tree.
//!
//! * space: per way a surface can face ([`facing`]: the two sides of a thin wall learn
//!   apart), a kd-tree over the scene's bounding box, a node cut in two at the middle of its
//!   longest side while it holds more than [`SPLIT_RECORDS`] training records, down to a
//!   lattice cell ([`LATTICE_LONGEST`] along the longest side): regions are small where
//!   light was recorded often (near what the camera sees) and large elsewhere, and a lookup
//!   is one read of a per-cell table;
//! * directions: per spatial leaf, a quadtree over a square map of the sphere ([`to_square`]:
//!   `u = (cos θ + 1) / 2` about the world `y` axis, `v` the azimuth's "diamond angle"), a quadrant
//!   subdivided while it carries more than [`SPLIT_ENERGY`] of the leaf's recorded light and
//!   holds at least [`MIN_NODE_RECORDS`] records: fine where light comes from a small
//!   solid angle (a slit, a lit band), coarse elsewhere.
//!
//! It is trained on records of path-traced samples: at every non-delta vertex, the
//! cosine-weighted incident radiance along the sampled direction (and along the light sample's
//! direction, with its multiple-importance weight) over that direction's density. At a
//! diffuse vertex, light arriving straight from an emitter is left out of the records (the
//! light sample's record, and the emission the sampled direction finds at once): next-event
//! estimation samples it well there, and a guide that learned it would spend its samples on
//! the light instead of on the indirect light only it can find. fig1, 64 spp, seed 7: `pg`
//! relMSE 0.0187 without direct light in the records, 0.0237 with; glossy 0.0055 against
//! 0.0106; fig5 0.299 / 0.292 / 0.285 against 0.272 / 0.286 / 0.280 (seeds 7 / 11 / 13). The sum of
//! a quadrant's records is proportional to an estimate of `∫ L_i |cos| dω` over its solid
//! angle; a quadrant's probability given its parent is its share of the parent's sum, a
//! leaf's density is uniform over its part of the square (over the sphere, that divided by
//! [`square_jacobian`]), and [`UNIFORM_SHARE`] of the square's uniform density is mixed in. Leaves without a record
//! carrying light are untrained: path tracing samples the BSDF there.
//!
//! A guided vertex draws its direction from `GUIDE_SHARE · p_guide + (1 − GUIDE_SHARE) ·
//! p_bsdf` and multiple importance sampling weighs next-event estimation against that
//! density, so the estimator stays unbiased whatever was learned.
//!
//! The training also learns where light sampling is wasted: per facing and lattice cell, a
//! cell is *dark* once [`DARK_AFTER_TRIES`] light samples in one pass reached no light
//! (fig1's lower room, which sees the light only through its walls). There next-event
//! estimation runs with probability [`DARK_LIGHT_SHARE`] only, and multiple importance
//! sampling weighs it at that share of its density (so emission found by the sampled
//! direction takes nearly all the weight): still unbiased, and the shadow rays that could
//! not arrive are not traced. A dark cell turns lit when one of its light samples reaches
//! a light. fig1, 38 spp, seeds 7 / 11 / 13: 2.03 → 1.79 s, relMSE 0.0341 → 0.0355 (the
//! shifted random streams alone give 0.0352: a share of 0.999); 1 236 of 24 576 cells
//! dark, shadow rays 4.8 → 2.4 million. fig5 (32 spp) 0.66 → 0.54 s, glossy 0.56 → 0.53 s,
//! cbox unchanged, at the same error.

use crate::accel::TriangleMesh;
use glam::Vec3;
use rayon::prelude::*;

/// A spatial node is cut in two while it holds more than this many training records.
pub const SPLIT_RECORDS: usize = 4000;
/// Depth limit of the spatial tree.
const MAX_SPATIAL_DEPTH: u32 = 32;
/// A directional quadrant is subdivided while it carries more than this share of its leaf's
/// recorded light ...
pub const SPLIT_ENERGY: f64 = 0.01;
/// ... and holds at least this many records (fewer say too little about where inside it the
/// light comes from).
pub const MIN_NODE_RECORDS: usize = 16;
/// Depth limit of a directional quadtree: leaves of `4^-5` of the square at the finest
/// (32 × 32, about 0.012 sr on average). Deeper leaves fit the noise of a pass's records
/// more than the light: with 12 levels, `pg` at fixed samples had 4–12 % more error and
/// took 2–8 % longer (fig1 40 spp: relMSE 0.0336 → 0.0322; at 256 spp 0.00395 → 0.00392;
/// glossy 64 spp 0.0056 → 0.0051, 256 spp 0.00119 → 0.00106; fig5 256 spp 0.0590 →
/// 0.0541). Six levels and more gave 12 levels' error on fig1, four 7 % more.
const MAX_DIRECTIONAL_DEPTH: u32 = 5;
/// Share of the sphere's uniform density in a trained leaf's density: directions the training
/// records missed keep some probability.
pub const UNIFORM_SHARE: f64 = 0.1;
/// Lattice cells along the scene box's longest side: the finest spatial regions (see
/// `Lattice`).
pub const LATTICE_LONGEST: u32 = 16;
/// Share of guided direction sampling at a trained vertex; the rest samples the BSDF.
pub const GUIDE_SHARE: f64 = 0.5;
/// Probability of next-event estimation in a dark lattice cell: one where the training's
/// light samples never reached a light (see [`Records::guide`]).
pub const DARK_LIGHT_SHARE: f64 = 0.1;
/// A lattice cell turns dark after this many light samples in one pass, none of which
/// reached a light (had the light been visible to one in ten of them, the chance of that
/// would be 0.9^32 = 3 %).
pub const DARK_AFTER_TRIES: u32 = 32;

/// The position of unit direction `d` on the square: `u = (cos θ + 1) / 2` about the world
/// `y` axis (equal-area in θ), and `v` the "diamond angle" of `(x, z)` over 4: a quarter of
/// the square per quadrant of the azimuth, along which `v` runs as `z / (|x| + |z|)` does
/// (no trigonometry either way: the equal-area `atan2` here and `sin_cos` back cost 4 % of
/// a guided render); the price is a density over the square that varies by up to 2× with
/// the azimuth, [`square_jacobian`].
pub fn to_square(d: Vec3) -> [f32; 2] {
    let u = ((d.y + 1.0) * 0.5).clamp(0.0, 1.0);
    let s = d.x.abs() + d.z.abs();
    let a = if s <= 0.0 {
        0.0
    } else if d.z >= 0.0 {
        if d.x >= 0.0 {
            d.z / s
        } else {
            1.0 - d.x / s
        }
    } else if d.x < 0.0 {
        2.0 - d.z / s
    } else {
        3.0 + d.x / s
    };
    [u, (a * 0.25).clamp(0.0, 1.0)]
}

/// The unit direction at `(u, v)` of the square (inverse of [`to_square`]).
pub fn from_square(u: f64, v: f64) -> Vec3 {
    let y = (2.0 * u - 1.0).clamp(-1.0, 1.0) as f32;
    let a = (4.0 * v).clamp(0.0, 4.0) as f32;
    let quadrant = (a as u32).min(3);
    let t = a - quadrant as f32;
    let (x, z) = match quadrant {
        0 => (1.0 - t, t),
        1 => (-t, 1.0 - t),
        2 => (t - 1.0, -t),
        _ => (t, t - 1.0),
    };
    let r = (1.0 - y * y).max(0.0).sqrt() / (x * x + z * z).sqrt();
    Vec3::new(r * x, y, r * z).normalize()
}

/// Solid angle per unit area of the square at unit direction `d`: `2` per unit of `u` times
/// `dφ / dv = 4 (|cos φ| + |sin φ|)²` (along a quadrant's edge `(1 − t, t)` of the diamond,
/// `dφ / dt = 1 / ((1 − t)² + t²)`). From `8` on the axes to `16` halfway between them; it
/// integrates to `4π` over the square.
pub fn square_jacobian(d: Vec3) -> f64 {
    let (x, z) = (f64::from(d.x), f64::from(d.z));
    let r2 = x * x + z * z;
    if r2 <= 0.0 {
        return 4.0 * std::f64::consts::PI;
    }
    let s = x.abs() + z.abs();
    8.0 * s * s / r2
}

/// The quadrant of `(u, v)` in the unit square, `(u ≥ ½) + 2 (v ≥ ½)`, and `(u, v)` in that
/// quadrant's own unit square (exact in binary floating point).
fn quadrant(u: f32, v: f32) -> (usize, f32, f32) {
    let (hu, hv) = (u >= 0.5, v >= 0.5);
    let q = usize::from(hu) + 2 * usize::from(hv);
    (
        q,
        2.0 * u - f32::from(u8::from(hu)),
        2.0 * v - f32::from(u8::from(hv)),
    )
}

/// Which way a surface normal `n` faces: its largest component's axis and sign, `0 … 5`.
/// Each facing has its own spatial tree, so that the two sides of a thin wall (the divider
/// of fig1: lit from above, dark below, a millimetre apart) learn apart.
pub fn facing(n: Vec3) -> usize {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + usize::from(n[axis] < 0.0)
}

/// Ways a normal can face (see [`facing`]).
pub const FACINGS: usize = 6;

/// One training record: where, which way the surface there faces (see [`facing`]), the
/// direction on the square ([`to_square`]), and the cosine-weighted radiance over the direction's
/// density (luminance).
#[derive(Clone, Copy, Debug)]
pub struct Record {
    pub p: Vec3,
    pub facing: u8,
    pub dir: [f32; 2],
    pub value: f32,
}

/// Records collected along paths: the sampled directions' records wait for the radiance
/// the rest of the path brings back; the light samples' outcomes are kept per lattice cell.
#[derive(Debug)]
pub struct PathRecorder {
    pending: Vec<Pending>,
    pub records: Vec<Record>,
    lattice: Lattice,
    /// Per light sample, its facing and lattice cell's index (as [`SpatialGuide`]'s tables
    /// index them), with the bit `REACHED` set where it reached a light.
    pub light_tries: Vec<u32>,
}

/// The bit of a light try that says it reached a light.
const REACHED: u32 = 1 << 31;
/// The bit of a [`SpatialGuide`]'s region that says its cell is dark.
const DARK: u32 = 1 << 31;

#[derive(Debug)]
struct Pending {
    /// The record, its value still to come.
    record: Record,
    /// `|cos| / pdf` of the sampled direction.
    cos_over_pdf: f32,
    /// The path throughput right after this vertex's sample, and the radiance collected
    /// before the sampled ray was traced.
    beta: Vec3,
    before: Vec3,
}

fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

impl PathRecorder {
    /// No records yet, for `records`' lattice.
    pub fn new(records: &Records) -> Self {
        Self {
            pending: Vec::new(),
            records: Vec::new(),
            lattice: records.lattice.clone(),
            light_tries: Vec::new(),
        }
    }

    /// A light sample taken at `x` (normal `n`), and whether it reached a light (an
    /// unoccluded emitter that the BSDF reflects).
    pub fn light_try(&mut self, x: Vec3, n: Vec3, reached: bool) {
        let i = self.lattice.index_facing(x, n) as u32;
        self.light_tries.push(i | if reached { REACHED } else { 0 });
    }

    /// A light sample's record at `x` (normal `n`): `value` is its MIS-weighted `L_e |cos| /
    /// pdf` (throughput excluded).
    pub fn light(&mut self, x: Vec3, n: Vec3, wi: Vec3, value: Vec3) {
        let value = luminance(value);
        if value > 0.0 && value.is_finite() {
            self.records.push(Record {
                p: x,
                facing: facing(n) as u8,
                dir: to_square(wi),
                value,
            });
        }
    }

    /// The direction sampled at vertex `x` (normal `n`), with `|cos| / pdf`, the throughput
    /// after the sample and the radiance collected so far.
    #[allow(clippy::too_many_arguments)]
    pub fn sampled(
        &mut self,
        x: Vec3,
        n: Vec3,
        wi: Vec3,
        cos_over_pdf: f32,
        beta: Vec3,
        before: Vec3,
    ) {
        self.pending.push(Pending {
            record: Record {
                p: x,
                facing: facing(n) as u8,
                dir: to_square(wi),
                value: 0.0,
            },
            cos_over_pdf,
            beta,
            before,
        });
    }

    /// Leaves the emission that the last sampled direction found at once (now added, the
    /// estimate being `radiance`) out of that direction's record: see the module
    /// documentation on direct light.
    pub fn emission_seen(&mut self, radiance: Vec3) {
        if let Some(p) = self.pending.last_mut() {
            p.before = radiance;
        }
    }

    /// Ends the path whose estimate is `radiance`: each sampled direction's record gets the
    /// radiance collected after it, divided by the throughput that carried it.
    pub fn finish(&mut self, radiance: Vec3) {
        for p in self.pending.drain(..) {
            let after = radiance - p.before;
            let li = Vec3::select(p.beta.cmpgt(Vec3::ZERO), after / p.beta, Vec3::ZERO);
            let value = luminance(li) * p.cos_over_pdf;
            if value > 0.0 && value.is_finite() {
                self.records.push(Record { value, ..p.record });
            }
        }
    }
}

/// Moves the items of `items` for which `left` holds to the front; returns how many they are.
fn partition<T>(items: &mut [T], left: impl Fn(&T) -> bool) -> usize {
    let mut n = 0;
    for i in 0..items.len() {
        if left(&items[i]) {
            items.swap(n, i);
            n += 1;
        }
    }
    n
}

/// Cuts the box `[lo, hi]` holding `records` in two at the middle of its longest side,
/// where that leaves records on both sides: halves without a record are dropped (the box
/// shrinks to the other half), so that a lookup does not descend through cuts that
/// separate nothing (a floor's records, say, cut along its normal). The axis, the cut's
/// position and how many records lie below it; `None` where no cut separates them.
fn cut(
    records: &mut [Record],
    lo: &mut Vec3,
    hi: &mut Vec3,
    finest: Vec3,
) -> Option<(usize, f32, usize)> {
    loop {
        // The longest side that is still more than a lattice cell long.
        let size = (*hi - *lo).to_array();
        let axis = (0..3)
            .filter(|&a| size[a] > 1.5 * finest[a])
            .max_by(|&a, &b| size[a].total_cmp(&size[b]).then(b.cmp(&a)))?;
        let split = 0.5 * (lo[axis] + hi[axis]);
        let below = partition(records, |r| r.p[axis] < split);
        if below == 0 {
            lo[axis] = split;
        } else if below == records.len() {
            hi[axis] = split;
        } else {
            return Some((axis, split, below));
        }
    }
}

/// The regular lattice over the scene's box that spatial lookups go through: the kd-tree's
/// cuts halve boxes down to a lattice cell at the finest, so that every lattice cell lies in
/// one leaf, and a lookup is one table read instead of a descent.
#[derive(Clone, Debug)]
struct Lattice {
    lo: Vec3,
    /// A cell's size along each axis, and its inverse.
    cell: Vec3,
    inv: Vec3,
    res: [u32; 3],
}

impl Lattice {
    /// [`LATTICE_LONGEST`] cells along the box's longest side, and along each other side the
    /// power of two that keeps the cells closest to cubes (the kd-tree halves sides).
    fn new(lo: Vec3, hi: Vec3) -> Self {
        let size = (hi - lo).max(Vec3::splat(1e-6));
        let longest = size.max_element();
        let res = size.to_array().map(|s| {
            let n = (LATTICE_LONGEST as f32 * s / longest).max(1.0);
            let p = n.log2().round().clamp(0.0, 10.0) as u32;
            1u32 << p
        });
        let cell = size / Vec3::from_array(res.map(|r| r as f32));
        Self {
            lo,
            cell,
            inv: cell.recip(),
            res,
        }
    }

    fn cells(&self) -> usize {
        self.res.iter().map(|&r| r as usize).product()
    }

    /// The index of the cell of `p` on a surface of normal `n` in a table of all facings'
    /// cells, facing after facing.
    fn index_facing(&self, p: Vec3, n: Vec3) -> usize {
        facing(n) * self.cells() + self.index(p)
    }

    /// The cell of `p` (points outside the box go to the nearest cell).
    fn index(&self, p: Vec3) -> usize {
        let t = ((p - self.lo) * self.inv).to_array();
        // `as u32` maps NaN and negatives to 0.
        let i: [usize; 3] = std::array::from_fn(|a| (t[a] as u32).min(self.res[a] - 1) as usize);
        (i[2] * self.res[1] as usize + i[1]) * self.res[0] as usize + i[0]
    }

    /// The centre of cell `index`.
    fn centre(&self, index: usize) -> Vec3 {
        let (r0, r1) = (self.res[0] as usize, self.res[1] as usize);
        let i = [index % r0, index / r0 % r1, index / (r0 * r1)];
        self.lo + self.cell * (Vec3::from_array(i.map(|c| c as f32)) + 0.5)
    }
}

/// A node of the spatial kd-tree: cut at `split` along `axis` (0, 1, 2) into the children
/// below and above it, or a leaf (`axis` [`LEAF`]) whose `children[0]` is its directional
/// quadtree's root (0: no record there carried light). Used while building only: the
/// lattice's table answers lookups.
#[derive(Clone, Copy, Debug)]
struct SpaceNode {
    axis: u32,
    split: f32,
    children: [u32; 2],
}

const LEAF: u32 = 3;

/// A node of a directional quadtree: per quadrant of its square (see [`quadrant`]), the
/// quadrant's probability given the node, and its child node (0: the quadrant is a leaf,
/// uniform inside). 32 bytes, two to a cache line: a guide of fig1 at 1024 samples per
/// pixel has 125 000 of them, and lookups wander over all.
#[derive(Clone, Copy, Debug, Default)]
struct QuadNode {
    prob: [f32; 4],
    child: [u32; 4],
}

/// A directional record: position on the node's square and value.
#[derive(Clone, Copy, Debug)]
struct DirRecord {
    u: f32,
    v: f32,
    value: f32,
}

/// Training records over the scene's box, and the guide built from them (`train_spatial`
/// keeps one pass's at a time).
#[derive(Clone, Debug)]
pub struct Records {
    lo: Vec3,
    hi: Vec3,
    lattice: Lattice,
    records: Vec<Record>,
    /// The light tries added (see [`PathRecorder::light_try`]).
    light_tries: Vec<u32>,
    /// Per facing and lattice cell, whether it is dark: kept from guide to guide.
    dark: Vec<bool>,
}

impl Records {
    /// No records yet, for a guide over the box `[lo, hi]`.
    pub fn new(lo: Vec3, hi: Vec3) -> Self {
        let lattice = Lattice::new(lo, hi);
        Self {
            lo,
            hi,
            dark: vec![false; FACINGS * lattice.cells()],
            lattice,
            records: Vec::new(),
            light_tries: Vec::new(),
        }
    }

    /// No records yet, for a guide over the bounding box of `mesh`.
    pub fn around(mesh: &TriangleMesh) -> Self {
        let (lo, hi) = mesh.bounds();
        if lo.cmple(hi).all() {
            Self::new(lo, hi)
        } else {
            Self::new(Vec3::ZERO, Vec3::ONE)
        }
    }

    pub fn add(&mut self, records: impl IntoIterator<Item = Record>) {
        self.records.extend(records);
    }

    /// Adds a recorder's records and light tries.
    pub fn add_recorded(&mut self, recorder: PathRecorder) {
        self.records.extend(recorder.records);
        self.light_tries.extend(recorder.light_tries);
    }

    pub fn len(&self) -> usize {
        self.records.len()
    }

    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// Forgets the records and light tries, keeping the storage (and which cells are dark).
    pub fn clear(&mut self) {
        self.records.clear();
        self.light_tries.clear();
    }

    /// Updates which cells are dark from the light tries added: a cell where a try reached
    /// a light is lit; one without is dark after [`DARK_AFTER_TRIES`] tries, and a dark one
    /// stays dark (its tries now taken at [`DARK_LIGHT_SHARE`]). The tries are used up, so
    /// that a second guide from the same records does not count them again.
    fn update_dark(&mut self) {
        let mut tries = vec![0u32; self.dark.len()];
        let mut reached = vec![false; self.dark.len()];
        for t in self.light_tries.drain(..) {
            let i = (t & !REACHED) as usize;
            tries[i] += 1;
            reached[i] |= t & REACHED != 0;
        }
        for (i, dark) in self.dark.iter_mut().enumerate() {
            *dark = !reached[i] && (*dark || tries[i] >= DARK_AFTER_TRIES);
        }
    }

    /// The guide of the records added so far (see the module documentation). Builds reorder
    /// the records, deterministically.
    pub fn guide(&mut self) -> SpatialGuide {
        self.update_dark();
        let (lo, hi) = (self.lo, self.hi);
        let lattice = self.lattice.clone();
        let cells = lattice.cells();
        let records = self.records.len();
        // One tree per facing, built in parallel, then joined in facing order.
        let mut facings = Vec::with_capacity(FACINGS);
        let mut rest = &mut self.records[..];
        for f in 0..FACINGS {
            let n = partition(rest, |r| usize::from(r.facing) == f);
            let (these, others) = rest.split_at_mut(n);
            facings.push(these);
            rest = others;
        }
        // Per facing: its tree, and per lattice cell the root of the quadtree there.
        let parts: Vec<(FacingTree, Vec<u32>)> = facings
            .into_par_iter()
            .map(|these| {
                let mut part = FacingTree {
                    finest: lattice.cell,
                    space: Vec::new(),
                    quads: vec![QuadNode::default()],
                    cells: 0,
                    trained_cells: 0,
                };
                part.build_space(these, lo, hi, 0);
                let regions = (0..cells).map(|c| part.leaf(lattice.centre(c))).collect();
                (part, regions)
            })
            .collect();
        let mut guide = SpatialGuide {
            stats: SpatialStats {
                records,
                dark_cells: self.dark.iter().filter(|&&d| d).count(),
                ..SpatialStats::default()
            },
            lattice,
            regions: Vec::new(),
            quads: vec![QuadNode::default()],
        };
        for (part, regions) in parts {
            // Node indices move past the nodes before; 0 stays "none".
            let offset = guide.quads.len() as u32 - 1;
            let moved = |i: u32| if i == 0 { 0 } else { i + offset };
            guide.quads.extend(part.quads[1..].iter().map(|q| QuadNode {
                child: q.child.map(moved),
                ..*q
            }));
            guide.regions.extend(regions.into_iter().map(moved));
            guide.stats.cells += part.cells;
            guide.stats.trained_cells += part.trained_cells;
        }
        guide.stats.directional_nodes = guide.quads.len() - 1;
        for (region, &dark) in guide.regions.iter_mut().zip(&self.dark) {
            *region |= if dark { DARK } else { 0 };
        }
        guide
    }
}

/// What training a spatial guide did.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct SpatialStats {
    /// Training passes (pass `i`: `2^i` path-traced samples per pixel), and their samples
    /// per pixel in all (part of the image).
    pub passes: u32,
    pub spp: u32,
    /// Records carrying light, over all passes (each guide learns from its pass's alone).
    pub records: usize,
    /// Leaves of the spatial trees (one tree per facing), and those with a directional
    /// quadtree.
    pub cells: usize,
    pub trained_cells: usize,
    /// Nodes of all directional quadtrees.
    pub directional_nodes: usize,
    /// Lattice cells (per facing) where next-event estimation runs at [`DARK_LIGHT_SHARE`].
    pub dark_cells: usize,
    /// Wall-clock seconds of the training passes.
    pub seconds: f64,
    /// With a GA plan's per-pixel guides: the last training pass's trial of them against
    /// this guide alone, which left them beside it or not.
    pub levels_trial: Option<LevelsTrial>,
}

/// A training pass's trial of a GA plan's per-pixel guides against this guide alone: the
/// mean relative variance of a sample (variance over `mean² + 0.01`, as relMSE weighs
/// errors) over the pixels the plan guides, against that over the control arm, the one
/// pixel in sixteen that the pass leaves to this guide alone.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct LevelsTrial {
    /// The training pass that ran the trial.
    pub pass: u32,
    /// Pixels in each arm.
    pub guided_pixels: usize,
    pub control_pixels: usize,
    /// Mean relative variance of the guided arm over the control arm's.
    pub ratio: f64,
    /// Whether the plan's guides stayed (for the later passes and the render).
    pub kept: bool,
}

/// The trained guide: a spatial kd-tree whose leaves hold directional quadtrees.
#[derive(Clone, Debug)]
pub struct SpatialGuide {
    pub stats: SpatialStats,
    lattice: Lattice,
    /// Per facing and lattice cell, the root of the directional quadtree of the kd-tree leaf
    /// holding the cell (0: none), with [`DARK`] set where the cell is dark (see
    /// [`Records::guide`]): a lookup is one read.
    regions: Vec<u32>,
    /// Every leaf's quadtree nodes; node 0 is unused, so that child 0 can mean "none".
    quads: Vec<QuadNode>,
}

/// One facing's kd-tree and quadtrees while they are built (see [`Records::guide`]).
struct FacingTree {
    /// A lattice cell's size: the finest cut.
    finest: Vec3,
    space: Vec<SpaceNode>,
    /// Quadtree nodes; node 0 is unused, so that child 0 can mean "none".
    quads: Vec<QuadNode>,
    /// Leaves, and leaves with a quadtree.
    cells: usize,
    trained_cells: usize,
}

impl SpatialGuide {
    /// The guide trained on `records` alone, over the box `[lo, hi]`.
    pub fn train(lo: Vec3, hi: Vec3, records: impl IntoIterator<Item = Record>) -> Self {
        let mut all = Records::new(lo, hi);
        all.add(records);
        all.guide()
    }

    /// This guide with every cell dark: next-event estimation at [`DARK_LIGHT_SHARE`]
    /// everywhere, where light arrives too (the estimator must stay unbiased there: a test
    /// of its weights).
    pub fn with_every_cell_dark(mut self) -> Self {
        self.regions.iter_mut().for_each(|r| *r |= DARK);
        self
    }

    /// The trained region at `p` on a surface of normal `n`, if any (its directional
    /// quadtree's root), and the probability of next-event estimation there: 1, or
    /// [`DARK_LIGHT_SHARE`] in a dark cell.
    pub fn at(&self, p: Vec3, n: Vec3) -> (Option<usize>, f64) {
        let region = self.regions[self.lattice.index_facing(p, n)];
        let cell = match region & !DARK {
            0 => None,
            root => Some(root as usize),
        };
        let light_share = if region & DARK != 0 {
            DARK_LIGHT_SHARE
        } else {
            1.0
        };
        (cell, light_share)
    }

    /// The solid-angle density of region `cell`'s guide for unit `wi`.
    pub fn pdf(&self, cell: usize, wi: Vec3) -> f64 {
        self.density(self.square_pdf(cell, to_square(wi)), wi)
    }

    /// The solid-angle density of unit `wi`, whose leaf has the square density `leaf`, with
    /// the uniform share mixed in.
    fn density(&self, leaf: f64, wi: Vec3) -> f64 {
        ((1.0 - UNIFORM_SHARE) * leaf + UNIFORM_SHARE) / square_jacobian(wi)
    }

    /// The density over the square of region `cell`'s quadtree at `(u, v)`.
    fn square_pdf(&self, cell: usize, [mut u, mut v]: [f32; 2]) -> f64 {
        let mut node = cell;
        let mut p = 1.0f64;
        loop {
            let n = &self.quads[node];
            let q;
            (q, u, v) = quadrant(u, v);
            p *= 4.0 * f64::from(n.prob[q]);
            match n.child[q] {
                0 => break,
                c => node = c as usize,
            }
        }
        p
    }

    /// A direction from region `cell`'s density, from three uniform numbers, and its
    /// solid-angle density (the leaf's, found on the way down).
    pub fn sample(&self, cell: usize, u: [f64; 3]) -> (Vec3, f64) {
        if u[0] < UNIFORM_SHARE {
            let wi = from_square(u[1], u[2]);
            return (wi, self.pdf(cell, wi));
        }
        let mut r = ((u[0] - UNIFORM_SHARE) / (1.0 - UNIFORM_SHARE)).clamp(0.0, 1.0);
        let (mut x, mut y, mut size) = (0.0f64, 0.0f64, 1.0f64);
        let mut leaf = 1.0f64;
        let mut node = cell;
        loop {
            let n = &self.quads[node];
            // The quadrant whose cumulative probability passes `r`, without branches
            // (rounding past the end takes the last quadrant with any probability).
            let p = n.prob.map(f64::from);
            let cdf = [0.0, p[0], p[0] + p[1], p[0] + p[1] + p[2]];
            let mut q = cdf[1..].iter().map(|&c| usize::from(r >= c)).sum::<usize>();
            while q > 0 && p[q] <= 0.0 {
                q -= 1;
            }
            r = ((r - cdf[q]) / p[q]).clamp(0.0, 1.0);
            leaf *= 4.0 * p[q];
            size *= 0.5;
            x += size * (q & 1) as f64;
            y += size * (q >> 1) as f64;
            match n.child[q] {
                0 => break,
                c => node = c as usize,
            }
        }
        let wi = from_square(x + size * u[1], y + size * u[2]);
        (wi, self.density(leaf, wi))
    }
}

impl FacingTree {
    /// Builds the spatial node of `records` in the box `[lo, hi]`; returns its index.
    fn build_space(
        &mut self,
        records: &mut [Record],
        mut lo: Vec3,
        mut hi: Vec3,
        depth: u32,
    ) -> u32 {
        let index = self.space.len();
        self.space.push(SpaceNode {
            axis: LEAF,
            split: 0.0,
            children: [0; 2],
        });
        let cut = (records.len() > SPLIT_RECORDS && depth < MAX_SPATIAL_DEPTH)
            .then(|| cut(records, &mut lo, &mut hi, self.finest))
            .flatten();
        if let Some((axis, split, below)) = cut {
            let (a, b) = records.split_at_mut(below);
            let (mut hi_a, mut lo_b) = (hi, lo);
            hi_a[axis] = split;
            lo_b[axis] = split;
            let children = [
                self.build_space(a, lo, hi_a, depth + 1),
                self.build_space(b, lo_b, hi, depth + 1),
            ];
            self.space[index] = SpaceNode {
                axis: axis as u32,
                split,
                children,
            };
        } else {
            self.cells += 1;
            let total: f64 = records.iter().map(|r| f64::from(r.value)).sum();
            if total > 0.0 && total.is_finite() {
                self.trained_cells += 1;
                let mut dirs: Vec<DirRecord> = records
                    .iter()
                    .map(|r| DirRecord {
                        u: r.dir[0],
                        v: r.dir[1],
                        value: r.value,
                    })
                    .collect();
                let root = self.build_quad(&mut dirs, total, total, 0);
                self.space[index].children[0] = root;
            }
        }
        index as u32
    }

    /// Builds the quadtree node of `records` (on the node's own square), whose values sum to
    /// `energy`, in a leaf whose values sum to `total`; returns its index.
    fn build_quad(
        &mut self,
        records: &mut [DirRecord],
        energy: f64,
        total: f64,
        depth: u32,
    ) -> u32 {
        let index = self.quads.len();
        self.quads.push(QuadNode::default());
        // Quadrants 0, 1 (v < ½), then 2, 3, each with `u < ½` first.
        let low_v = partition(records, |r| r.v < 0.5);
        let (bottom, top) = records.split_at_mut(low_v);
        let low_u = [
            partition(bottom, |r| r.u < 0.5),
            partition(top, |r| r.u < 0.5),
        ];
        let (b0, b1) = bottom.split_at_mut(low_u[0]);
        let (t0, t1) = top.split_at_mut(low_u[1]);
        let mut node = QuadNode::default();
        for (q, part) in [b0, b1, t0, t1].into_iter().enumerate() {
            let e: f64 = part.iter().map(|r| f64::from(r.value)).sum();
            node.prob[q] = (e / energy) as f32;
            if e > SPLIT_ENERGY * total
                && part.len() >= MIN_NODE_RECORDS
                && depth + 1 < MAX_DIRECTIONAL_DEPTH
            {
                for r in part.iter_mut() {
                    (_, r.u, r.v) = quadrant(r.u, r.v);
                }
                node.child[q] = self.build_quad(part, e, total, depth + 1);
            }
        }
        self.quads[index] = node;
        index as u32
    }

    /// The root of the directional quadtree of the kd-tree leaf at `p` (0: none).
    fn leaf(&self, p: Vec3) -> u32 {
        let p = p.to_array();
        let mut node = self.space[0];
        while node.axis != LEAF {
            let above = p[node.axis as usize] >= node.split;
            node = self.space[node.children[usize::from(above)] as usize];
        }
        node.children[0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_rng, uniform};
    use std::f64::consts::PI;

    fn uniforms(rng: &mut crate::sampling::Rng) -> [f64; 3] {
        [0; 3].map(|_| f64::from(uniform(rng)))
    }

    #[test]
    fn facings() {
        let normals = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        for (i, n) in normals.into_iter().enumerate() {
            assert_eq!(facing(n), i);
            assert_eq!(facing((n + Vec3::splat(0.3)).normalize()), i);
        }
    }

    #[test]
    fn square_round_trips() {
        let mut rng = sample_rng(9, 0, 0);
        for _ in 0..100_000 {
            let [u, v] = uniforms(&mut rng)[..2].try_into().unwrap();
            let d = from_square(u, v);
            assert!((d.length() - 1.0).abs() < 1e-6, "{d}");
            let [a, b] = to_square(d);
            assert!((f64::from(a) - u).abs() < 1e-5, "u {u} → {a}");
            assert!((f64::from(b) - v).abs() < 1e-5, "v {v} → {b}");
        }
    }

    /// The square's solid angle per unit area integrates to the sphere's `4π` (midpoint rule
    /// on a 512² grid), and a cosine-weighted integral over the square matches the analytic
    /// `π` of the upper hemisphere; its square root misses.
    #[test]
    fn square_jacobian_integrates_to_the_sphere() {
        let n = 512;
        let (mut sphere, mut cosine, mut wrong) = (0.0, 0.0, 0.0);
        for i in 0..n {
            for j in 0..n {
                let (u, v) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                let d = from_square(u, v);
                let area = 1.0 / (n * n) as f64;
                let jacobian = square_jacobian(d);
                sphere += jacobian * area;
                cosine += jacobian * area * f64::from(d.y.max(0.0));
                wrong += jacobian.sqrt() * area;
            }
        }
        assert!((sphere / (4.0 * PI) - 1.0).abs() < 1e-4, "∫ dω = {sphere}");
        assert!((cosine / PI - 1.0).abs() < 1e-4, "∫ cos dω = {cosine}");
        assert!((wrong / (4.0 * PI) - 1.0).abs() > 0.05, "{wrong}");
    }

    /// A guide trained on records bunched around two directions and spread over the rest,
    /// in one region of the box `[0, 1]³`.
    fn trained() -> SpatialGuide {
        let mut rng = sample_rng(4, 0, 0);
        let records = (0..SPLIT_RECORDS).map(|i| {
            let [a, b, c] = uniforms(&mut rng);
            let dir = match i % 4 {
                0 => [0.3 + 0.01 * a as f32, 0.7 + 0.003 * b as f32],
                1 => [0.8 + 0.05 * a as f32, 0.1 + 0.05 * b as f32],
                _ => [a as f32, b as f32],
            };
            Record {
                p: Vec3::splat(0.5),
                facing: 2,
                dir,
                value: 0.5 + c as f32,
            }
        });
        SpatialGuide::train(Vec3::ZERO, Vec3::ONE, records)
    }

    #[test]
    fn quadtree_refines_where_the_light_is() {
        let guide = trained();
        assert_eq!(guide.stats.trained_cells, 1);
        assert!(guide.at(Vec3::splat(0.5), -Vec3::Y).0.is_none());
        let cell = guide.at(Vec3::splat(0.5), Vec3::Y).0.unwrap();
        // A quarter of the light in 3e-5 of the square: the density there is that of the
        // finest leaf (4^-5 of the square), a quarter of 1024 times the mean, and the spread
        // records' quadrants stay coarse.
        let bright = guide.pdf(cell, from_square(0.305, 0.7015)) * 4.0 * PI;
        let dim = guide.pdf(cell, from_square(0.5, 0.3)) * 4.0 * PI;
        assert!(bright > 200.0, "density {bright} at the narrow bunch");
        assert!(
            (0.3..1.0).contains(&dim),
            "density {dim} among the spread records"
        );
        assert!(guide.stats.directional_nodes < 400, "{:?}", guide.stats);
    }

    #[test]
    fn density_integrates_to_one_and_matches_samples() {
        let guide = trained();
        let cell = guide.at(Vec3::splat(0.5), Vec3::Y).0.unwrap();
        // ∫ p dω by sampling directions from the guide itself: E[1 / p] over its samples is
        // the solid angle where p > 0, the whole sphere.
        let mut rng = sample_rng(3, 0, 0);
        let n = 200_000;
        let mut inverse = 0.0;
        // Frequencies of a coarse 16 × 16 histogram of the square against each of its cells'
        // probability, from the quadtree's leaves (and the uniform share).
        let mut hits = vec![0u32; 256];
        // Samples whose density from the descent that drew them differs from `pdf`'s (a
        // rounding at a leaf's edge may move a direction into the neighbouring leaf).
        let mut mismatched = 0;
        for _ in 0..n {
            let (d, pdf) = guide.sample(cell, uniforms(&mut rng));
            inverse += 1.0 / pdf;
            mismatched += usize::from((guide.pdf(cell, d) - pdf).abs() > 1e-6 * pdf);
            let [u, v] = to_square(d);
            hits[((u * 16.0) as usize).min(15) * 16 + ((v * 16.0) as usize).min(15)] += 1;
        }
        assert!(
            mismatched <= n / 1000,
            "{mismatched} densities differ from pdf's"
        );
        let sphere = inverse / n as f64;
        assert!(
            (sphere / (4.0 * PI) - 1.0).abs() < 0.01,
            "∫ 1 dω = {sphere}"
        );
        let mut expected = vec![UNIFORM_SHARE / 256.0; 256];
        for (x, y, size, p) in leaves(&guide, cell) {
            for (c, e) in expected.iter_mut().enumerate() {
                let (cu, cv) = ((c / 16) as f64 / 16.0, (c % 16) as f64 / 16.0);
                let overlap = |a: f64, b: f64| (a + size).min(b + 1.0 / 16.0) - a.max(b);
                let area = overlap(x, cu).max(0.0) * overlap(y, cv).max(0.0);
                *e += (1.0 - UNIFORM_SHARE) * p * area / (size * size);
            }
        }
        let total: f64 = expected.iter().sum();
        assert!((total - 1.0).abs() < 1e-3, "∫ p = {total}");
        let worst = |scale: f64| {
            (0..256)
                .map(|c| {
                    let e = scale * expected[c] * n as f64;
                    (hits[c] as f64 - e).abs() / e.sqrt().max(1.0)
                })
                .fold(0.0, f64::max)
        };
        assert!(worst(1.0) < 5.0, "max |z| {}", worst(1.0));
        // The same check rejects probabilities off by 5 %.
        assert!(worst(1.05) > 5.0, "max |z| {} off by 5 %", worst(1.05));
    }

    /// The leaves of region `cell`'s quadtree: their squares `(u, v, side)` and probabilities.
    fn leaves(guide: &SpatialGuide, cell: usize) -> Vec<(f64, f64, f64, f64)> {
        let mut out = Vec::new();
        let mut stack = vec![(cell, 0.0, 0.0, 1.0, 1.0)];
        while let Some((node, x, y, size, p)) = stack.pop() {
            let n = &guide.quads[node];
            for q in 0..4 {
                let h = size / 2.0;
                let (qx, qy) = (x + h * (q & 1) as f64, y + h * (q >> 1) as f64);
                let pq = p * f64::from(n.prob[q]);
                match n.child[q] {
                    0 => out.push((qx, qy, h, pq)),
                    c => stack.push((c as usize, qx, qy, h, pq)),
                }
            }
        }
        out
    }

    /// A cell turns dark after enough light tries of which none reached a light, stays
    /// dark while no try reaches one, and turns lit when one does; a cell with too few tries
    /// stays lit.
    #[test]
    fn cells_turn_dark_where_light_samples_never_arrive() {
        let mut records = Records::new(Vec3::ZERO, Vec3::ONE);
        let (a, b, c) = (Vec3::splat(0.1), Vec3::splat(0.5), Vec3::splat(0.9));
        let tries = |records: &mut Records, p: Vec3, n: u32, reached: u32| {
            let mut recorder = PathRecorder::new(records);
            for i in 0..n {
                recorder.light_try(p, Vec3::Y, i < reached);
            }
            records.add_recorded(recorder);
        };
        tries(&mut records, a, DARK_AFTER_TRIES, 0);
        tries(&mut records, b, DARK_AFTER_TRIES, 1);
        tries(&mut records, c, DARK_AFTER_TRIES - 1, 0);
        let guide = records.guide();
        let share = |g: &SpatialGuide, p: Vec3, n: Vec3| g.at(p, n).1;
        assert_eq!(share(&guide, a, Vec3::Y), DARK_LIGHT_SHARE);
        // The other side of the same place was not tried.
        assert_eq!(share(&guide, a, -Vec3::Y), 1.0);
        assert_eq!(share(&guide, b, Vec3::Y), 1.0);
        assert_eq!(share(&guide, c, Vec3::Y), 1.0);
        assert_eq!(guide.stats.dark_cells, 1);
        // The next pass tries the dark cell at its share: a few tries keep it dark ...
        records.clear();
        tries(&mut records, a, 3, 0);
        assert_eq!(share(&records.guide(), a, Vec3::Y), DARK_LIGHT_SHARE);
        // ... no try keeps it dark, and one that reaches a light makes it lit.
        records.clear();
        assert_eq!(share(&records.guide(), a, Vec3::Y), DARK_LIGHT_SHARE);
        tries(&mut records, a, 3, 1);
        assert_eq!(share(&records.guide(), a, Vec3::Y), 1.0);
    }

    #[test]
    fn space_splits_where_records_are() {
        // Records at two points far apart, more than one leaf can hold: the regions split
        // and each learns its own direction.
        let records = (0..2 * SPLIT_RECORDS + 2).map(|i| {
            let left = i % 2 == 0;
            Record {
                p: if left {
                    Vec3::splat(0.1)
                } else {
                    Vec3::splat(0.9)
                },
                facing: 0,
                dir: if left { [0.2, 0.2] } else { [0.8, 0.8] },
                value: 1.0,
            }
        });
        let guide = SpatialGuide::train(Vec3::ZERO, Vec3::ONE, records);
        assert!(guide.stats.cells > 1, "{:?}", guide.stats);
        let (a, b) = (
            guide.at(Vec3::splat(0.1), Vec3::X).0.unwrap(),
            guide.at(Vec3::splat(0.9), Vec3::X).0.unwrap(),
        );
        // The same place facing another way has no records.
        assert!(guide.at(Vec3::splat(0.9), -Vec3::X).0.is_none());
        assert_ne!(a, b);
        let (da, db) = (from_square(0.2, 0.2), from_square(0.8, 0.8));
        assert!(guide.pdf(a, da) > 100.0 * guide.pdf(a, db));
        assert!(guide.pdf(b, db) > 100.0 * guide.pdf(b, da));
        // Nothing recorded: untrained.
        let empty = SpatialGuide::train(Vec3::ZERO, Vec3::ONE, []);
        assert!(empty.at(Vec3::splat(0.5), Vec3::Y).0.is_none());
    }
}
