//! Building a [`SpatialField`] from training records (Open PGL's `Field::Update`): per
//! facing, a kd-tree over the scene's box cut where records are dense, and in each of its
//! leaves a directional quadtree over the square map refined where the recorded light is
//! (see [`super::field`] for the structure and what it learns). The trees of all facings
//! are built in parallel and joined, in facing order, into the field's lookup tables.

use super::field::{QuadNode, SpatialField, DARK};
use super::lattice::{Lattice, FACINGS};
use super::square::quadrant;
use super::stats::FieldStats;
use super::storage::Record;
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
/// more than the light, and cost time as well as error; shallower ones lose the light's
/// detail (reports/README.md, "Measurements formerly in code comments (2026-12-07)").
const MAX_DIRECTIONAL_DEPTH: u32 = 5;

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

/// A directional record: position on the node's square and value.
#[derive(Clone, Copy, Debug)]
struct DirRecord {
    u: f32,
    v: f32,
    value: f32,
}

/// One facing's kd-tree and quadtrees while they are built (see [`SpatialField::build`]).
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

impl SpatialField {
    /// The field of `records` over the box `lo_hi` on `lattice`, with the cells `dark`
    /// marks (per facing and lattice cell) dark. Reorders the records, deterministically.
    pub(super) fn build(
        lattice: &Lattice,
        (lo, hi): (Vec3, Vec3),
        records: &mut [Record],
        dark: &[bool],
    ) -> Self {
        let lattice = lattice.clone();
        let cells = lattice.cells();
        let count = records.len();
        // One tree per facing, built in parallel, then joined in facing order.
        let mut facings = Vec::with_capacity(FACINGS);
        let mut rest = records;
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
        let mut field = SpatialField {
            stats: FieldStats {
                records: count,
                dark_cells: dark.iter().filter(|&&d| d).count(),
                ..FieldStats::default()
            },
            lattice,
            regions: Vec::new(),
            quads: vec![QuadNode::default()],
            shares: Vec::new(),
            fixed_share_density: false,
        };
        for (part, regions) in parts {
            // Node indices move past the nodes before; 0 stays "none".
            let offset = field.quads.len() as u32 - 1;
            let moved = |i: u32| if i == 0 { 0 } else { i + offset };
            field.quads.extend(part.quads[1..].iter().map(|q| QuadNode {
                child: q.child.map(moved),
                ..*q
            }));
            field.regions.extend(regions.into_iter().map(moved));
            field.stats.cells += part.cells;
            field.stats.trained_cells += part.trained_cells;
        }
        field.stats.directional_nodes = field.quads.len() - 1;
        for (region, &dark) in field.regions.iter_mut().zip(dark) {
            *region |= if dark { DARK } else { 0 };
        }
        field
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
