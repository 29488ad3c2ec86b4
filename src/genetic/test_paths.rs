//! The test paths of one pixel (paper §5.4): `M` paths sampled once from a defensive density
//! `q` and reused for every fitness evaluation. Only paths with `F > 0` are stored (`M` still
//! counts the others), each with what any generator needs to evaluate its density without
//! tracing a ray, and `F²/q` for `F² = Σ_c w_c f_c²` ([`ChannelWeights`]: by default
//! relative to the pixel value the paths themselves estimate).
//!
//! The paths and their densities are those of `q`'s estimator ([`Nee`]): with
//! [`Nee::Every`] each stored path is one contribution of a light point or of an emitter
//! hit at any vertex, its last vertex's direction the one to its emitter point, and every
//! generator's density the sum of its two techniques'.
//!
//! Storage is structure-of-arrays: the scattering vertices of all paths are flattened into
//! per-vertex arrays indexed through `offsets`. The BRDF density of each scattering vertex is
//! the same for every generator that uses a BRDF sampler there, so it is computed once here.
//!
//! Paths are traced in waves of up to [`WAVE_SIZE`] ([`TestPaths::sample`]): each path is a
//! [`crate::path::walk::Walk`] with its own random stream, and the walks of a wave
//! advance in lockstep, their pending rays regrouped at every step into packets of 16 (one
//! packet query: Embree's `rtcIntersect16`/`rtcOccluded16`, or the `8` variants twice on a
//! CPU without AVX-512; a loop on obvhs), a last partial one going as a packet when it holds
//! at least [`MIN_INCOHERENT_PACKET`] rays, one by one otherwise. A path's result does not
//! depend on how its rays are traced, so the store
//! equals the one traced ray by ray ([`TestPaths::sample_single`]), but for a camera ray
//! through an edge two triangles share at the same `t`, which the coherent camera packets
//! may answer with the other triangle (a set of measure zero).

use super::ChannelWeights;
use crate::accel::{Coherence, Ray, PACKET_SIZE};
use crate::film::{sample_pixel, sample_stream};
use crate::path::generator::{
    absorbs_at, fixed_light_pdf, Contribution, DirectionSampler, GeneratorDensity, LightEnd, Nee,
    PathGenerator, PathVertices, StepDensity,
};
use crate::path::mixture::Mixture;
use crate::path::walk::{Query, Walk};
use crate::path::{RayCounts, SceneView};
use crate::sampling::light_point::{finest_cell, PointCells};
use crate::sampling::{camera_ray, sample_rng, uniform, Rng};
use crate::scene::material::bsdf;
use crate::scene::Camera;
use crate::scene::SurfacePoint;
use glam::DVec3;
use std::ops::ControlFlow;
use std::sync::OnceLock;

/// Test paths of one pixel.
/// A camera ray through a point uniform over the square of `side` pixels centred on pixel
/// `(x, y)`, clipped to the image ([`footprint_point`]); for `side ≤ 1`, through the pixel
/// itself ([`camera_ray`], the same ray from the same numbers).
pub fn footprint_ray(camera: &Camera, (x, y): (u32, u32), side: f32, rng: &mut Rng) -> Ray {
    if side <= 1.0 {
        return camera_ray(camera, (x, y), rng);
    }
    let (px, py) = footprint_point((camera.width, camera.height), (x, y), side, rng);
    camera.ray(px, py)
}

/// The image position of [`footprint_ray`] for `side > 1`: uniform over the square of
/// `side` pixels centred on the centre of pixel `(x, y)`, each coordinate clamped into the
/// `width × height` image.
pub fn footprint_point(
    (width, height): (u32, u32),
    (x, y): (u32, u32),
    side: f32,
    rng: &mut Rng,
) -> (f32, f32) {
    // The largest f32 below `extent` (`f32::next_down`, past the MSRV): `extent ≥ 1`.
    let below = |extent: u32| f32::from_bits((extent as f32).to_bits() - 1);
    let at =
        |p: u32, extent: u32, u: f32| (p as f32 + 0.5 + (u - 0.5) * side).clamp(0.0, below(extent));
    let px = at(x, width, uniform(rng));
    (px, at(y, height, uniform(rng)))
}

#[derive(Clone, Debug, PartialEq)]
pub struct TestPaths {
    /// Number of sampled paths, zero-contribution ones included (`M` of eq. 10).
    pub sampled: usize,
    pub max_bounces: u32,
    /// The estimator whose contributions and densities the paths are.
    estimator: Nee,
    /// Per stored path: `F²/q`, `F² = Σ_c w_c f_c²` for the contribution `f` and
    /// [`Self::weights`].
    pub f2_over_q: Vec<f64>,
    /// Per stored path: `f_c²/q` per channel.
    f2_rgb_over_q: Vec<DVec3>,
    /// `Σ f/q` over every contribution of every sampled path.
    f_over_q_sum: DVec3,
    weights: ChannelWeights,
    /// Per stored path: number of vertices `x1 … x_len`.
    len: Vec<u32>,
    /// Per stored path: ends with a light point (next-event estimation).
    nee: Vec<bool>,
    /// Per stored path: its end as every generator's light density reads it ([`StoredLight`]).
    light: Vec<StoredLight>,
    /// Per stored path: whether it ends with a light sample or a connection (with
    /// [`Nee::Every`] after a non-delta last vertex), and whether at a delta light (whose
    /// direction technique has density 0).
    connected: Vec<bool>,
    light_delta: Vec<bool>,
    /// Per stored path with [`Nee::Every`]: `d²/cos` at the emitter point, which turns its
    /// area density into solid angle at the last vertex.
    area_to_solid_angle: Vec<f64>,
    /// Per stored path: the point the last stored direction reached, where it is not a
    /// stored vertex, and its triangle (`u32::MAX`: none): with [`Nee::End`] the vertex that
    /// absorbed, with [`Nee::Every`] the emitter point.
    end_point: Vec<DVec3>,
    end_prim: Vec<u32>,
    /// Scattering vertices of path `i` are `offsets[i]..offsets[i + 1]`.
    offsets: Vec<u32>,
    /// Per stored path: how many of its first vertices whose directions' densities multiply
    /// (all but the last of a path that ends with two techniques) equal, bit for bit, those
    /// of the stored path before it. The contributions of one sampled path share their
    /// vertices up to each one's end, so [`Self::generator_pdfs`] multiplies each vertex's
    /// density once per sampled path, not once per contribution.
    shared: Vec<u32>,
    /// Per scattering vertex: position, sampled direction, BRDF density of that direction,
    /// and whether it is a mirror (delta) vertex.
    point: Vec<DVec3>,
    /// Per scattering vertex: its triangle.
    prim: Vec<u32>,
    wi: Vec<DVec3>,
    brdf_pdf: Vec<f64>,
    delta: Vec<bool>,
    /// How [`Self::generator_pdfs_with`] walks the paths; found when first asked for,
    /// forgotten by [`Self::push`].
    walks: WalksOnce,
}

/// [`Walks`], found from the stored paths when first asked for: state derived from them,
/// which the equality of two stores leaves out.
#[derive(Clone, Debug, Default)]
struct WalksOnce(OnceLock<Walks>);

impl PartialEq for WalksOnce {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// How [`TestPaths::generator_pdfs_with`] walks the stored paths, found once from them. A
/// generator's density multiplies, along each path, its step `k`'s density of the direction
/// out of the path's `k`-th non-delta vertex; which step reads a vertex depends on the path
/// alone, so the densities of one sampler at step `k` serve every generator that has it
/// there ([`crate::genetic::fitness::Evaluator`]).
#[derive(Clone, Debug, Default)]
struct Walks {
    /// Per step: the vertices whose direction it reads, in the walk's order: a path's
    /// non-delta vertices that the stored path before does not share, and with
    /// [`Nee::Every`] the last vertex of a path that ends at a light point (its direction
    /// the one to that point).
    of_step: Vec<Vec<u32>>,
    /// Per stored path, in order.
    paths: Vec<PathWalk>,
    /// The stored paths' reads of unshared vertices, path after path.
    reads: Vec<Read>,
}

/// One vertex read by the walk: its place in its step's list of [`Walks::of_step`], and
/// whether every generator's absorption is 1 there ([`absorbs_at`]).
#[derive(Clone, Copy, Debug)]
struct Read {
    place: u32,
    absorbs: bool,
}

/// What the walk does for one stored path.
#[derive(Clone, Copy, Debug)]
struct PathWalk {
    /// Non-delta vertices it shares, bit for bit, with the stored path before.
    shared: u32,
    /// Its reads end at `Walks::reads[reads_end]`; they start where the path before's end.
    reads_end: u32,
    end: WalkEnd,
}

/// How a stored path's density ends, after its last read.
#[derive(Clone, Copy, Debug)]
enum WalkEnd {
    /// Nothing more: an emitter hit with [`Nee::Every`], or a path without a light point.
    Direction,
    /// With [`Nee::Every`], a light point: the sum of the two techniques, `p_dir + p_light`
    /// (`PathGenerator::pdf_techniques`), the direction to it read at `read` (`place`
    /// `u32::MAX` where the light is a delta one, which no direction finds).
    Both {
        read: Read,
        area_to_solid_angle: f64,
    },
    /// With [`Nee::End`], a light point after the absorption at the last vertex (`absorbs`:
    /// 1 for every generator there, [`absorbs_at`]).
    Light { absorbs: bool },
}

/// A stored path's end as every generator's light density reads it
/// ([`GeneratorDensity::light`]), in one place: where it ends at a delta light or the
/// environment, the light technique's density, the same for every generator
/// ([`fixed_light_pdf`]; `None` for an emitter point), else the light point's triangle
/// (`u32::MAX`: none) and its cell of the finest subdivision there ([`finest_cell`]).
#[derive(Clone, Copy, Debug, PartialEq)]
struct StoredLight {
    fixed: Option<f64>,
    prim: u32,
    cell: u32,
}

/// One path of a packet: its random stream, walk, pending query, and buffers reused from
/// packet to packet.
struct Lane {
    rng: Rng,
    /// The component of `q` the walk samples.
    generator: usize,
    walk: Walk,
    query: Option<Query>,
    path: PathVertices,
    contributions: Vec<Contribution>,
}

impl Default for Lane {
    fn default() -> Self {
        Self {
            rng: sample_rng(0, 0, 0),
            generator: 0,
            walk: Walk::default(),
            query: None,
            path: PathVertices::default(),
            contributions: Vec::new(),
        }
    }
}

/// After the camera rays, the last, partial packet of a step's pending rays goes as one
/// packet only if it holds at least this many; fewer go as single rays: past the camera the
/// rays are incoherent, and a packet query costs about as much as a full one however few
/// lanes it holds, while full incoherent packets are barely faster than single rays
/// (reports/README.md, "Measurements formerly in code comments (2026-12-07)").
pub const MIN_INCOHERENT_PACKET: usize = 12;

/// Paths a [`Wave`] advances together at most: the pending rays of this many walks are
/// regrouped after each step into full packets of 16, so that absorption, which thins a
/// lone packet of 16 step by step, leaves the packets full.
pub const WAVE_SIZE: usize = 64;

/// Up to [`WAVE_SIZE`] paths traced together: their lanes and the buffers of their packet
/// queries, reused from wave to wave.
struct Wave {
    lanes: Vec<Lane>,
    /// Count of lanes in use (the first ones).
    n: usize,
    /// The pending rays of one kind, and the lane of each.
    rays: Vec<Ray>,
    owner: Vec<usize>,
    points: Vec<Option<SurfacePoint>>,
    free: Vec<bool>,
}

impl Wave {
    fn new() -> Self {
        Self {
            lanes: std::iter::repeat_with(Lane::default)
                .take(WAVE_SIZE)
                .collect(),
            n: 0,
            rays: Vec::with_capacity(WAVE_SIZE),
            owner: Vec::with_capacity(WAVE_SIZE),
            points: vec![None; WAVE_SIZE],
            free: vec![false; WAVE_SIZE],
        }
    }

    /// Starts paths `js` (at most [`WAVE_SIZE`]) through `pixel`: their camera rays in
    /// packets of 16, then each walk up to its first query.
    #[allow(clippy::too_many_arguments)]
    fn start(
        &mut self,
        view: &SceneView,
        q: &Mixture,
        (pixel, side): ((u32, u32), f32),
        seed: u64,
        js: std::ops::Range<usize>,
        max_bounces: u32,
        counts: &mut RayCounts,
    ) {
        self.n = js.len();
        let lanes = &mut self.lanes[..self.n];
        self.rays.clear();
        for (lane, j) in lanes.iter_mut().zip(js) {
            lane.rng = sample_stream(&view.scene.camera, seed, pixel, j as u64);
            let ray = footprint_ray(&view.scene.camera, pixel, side, &mut lane.rng);
            self.rays.push(ray);
        }
        let (rays, points) = (&self.rays[..], &mut self.points[..self.n]);
        if view.draws_at_hits() {
            // Each lane passes masks and chooses plastics' lobes with its own random numbers.
            for ((lane, ray), point) in lanes.iter_mut().zip(rays).zip(points.iter_mut()) {
                *point = view.trace_through(ray, &mut lane.rng, counts);
            }
        } else {
            // One pixel's camera rays: the coherent case packets are made for.
            for (rays, points) in rays.chunks(PACKET_SIZE).zip(points.chunks_mut(PACKET_SIZE)) {
                view.trace_packet(rays, points, Coherence::Coherent, counts);
            }
        }
        for ((lane, ray), x1) in lanes.iter_mut().zip(rays).zip(points.iter()) {
            lane.contributions.clear();
            lane.query = None;
            if let Some(x1) = *x1 {
                lane.generator = q.choose(uniform(&mut lane.rng) as f64);
                let g = &q.generators[lane.generator];
                let rng = &mut lane.rng;
                let estimator = (max_bounces, q.nee);
                (lane.walk, lane.query) =
                    Walk::start(g, view, ray.origin, x1, estimator, rng, &mut lane.path);
            }
        }
    }

    /// Collects the pending rays of one kind into `rays`, their lanes into `owner`; returns
    /// how many.
    fn gather(&mut self, shadow: bool) -> usize {
        self.rays.clear();
        self.owner.clear();
        for (i, lane) in self.lanes[..self.n].iter().enumerate() {
            let ray = match lane.query {
                Some(Query::Closest(ray)) if !shadow => ray,
                Some(Query::Shadow(ray)) if shadow => ray,
                _ => continue,
            };
            self.rays.push(ray);
            self.owner.push(i);
        }
        self.rays.len()
    }

    /// Traces the pending closest-hit rays in packets of 16 and hands each walk its hit;
    /// returns how many rays.
    fn trace_closest(&mut self, view: &SceneView, q: &Mixture, counts: &mut RayCounts) -> usize {
        let count = self.gather(false);
        let (rays, points) = (&self.rays[..], &mut self.points[..count]);
        if view.draws_at_hits() {
            // Each lane passes masks and chooses plastics' lobes with its own random numbers.
            for ((ray, point), &i) in rays.iter().zip(points.iter_mut()).zip(&self.owner) {
                *point = view.trace_through(ray, &mut self.lanes[i].rng, counts);
            }
        } else {
            let packet = |r: &[Ray], p: &mut [_], c: &mut RayCounts| {
                view.trace_packet(r, p, Coherence::Incoherent, c);
            };
            in_packets(rays, points, counts, packet, |r, c| view.trace(r, c));
        }
        for (&i, y) in self.owner.iter().zip(&self.points) {
            let lane = &mut self.lanes[i];
            let g = &q.generators[lane.generator];
            let (rng, path) = (&mut lane.rng, &mut lane.path);
            lane.query = lane
                .walk
                .hit(g, view, rng, path, &mut lane.contributions, *y);
        }
        count
    }

    /// Traces the pending shadow rays in packets of 16 and hands each walk its answer;
    /// returns how many.
    fn trace_shadows(&mut self, view: &SceneView, counts: &mut RayCounts) -> usize {
        let count = self.gather(true);
        let (rays, free) = (&self.rays[..], &mut self.free[..count]);
        if view.has_masks() {
            for ((ray, free), &i) in rays.iter().zip(free.iter_mut()).zip(&self.owner) {
                *free = view.unblocked_through(ray, &mut self.lanes[i].rng, counts);
            }
        } else {
            let packet = |r: &[Ray], f: &mut [bool], c: &mut RayCounts| {
                view.unblocked_packet(r, f, c);
            };
            in_packets(rays, free, counts, packet, |r, c| view.unblocked(r, c));
        }
        for (&i, &free) in self.owner.iter().zip(&self.free) {
            let lane = &mut self.lanes[i];
            lane.query = lane.walk.shadow(free, &mut lane.contributions);
        }
        count
    }
}

/// Answers `rays` into `out` in packets of [`PACKET_SIZE`]: one packet query (`packet`) per
/// packet of at least [`MIN_INCOHERENT_PACKET`] rays (every packet but perhaps the last),
/// one ray at a time (`single`) below that.
fn in_packets<T>(
    rays: &[Ray],
    out: &mut [T],
    counts: &mut RayCounts,
    packet: impl Fn(&[Ray], &mut [T], &mut RayCounts),
    single: impl Fn(&Ray, &mut RayCounts) -> T,
) {
    for (rays, out) in rays.chunks(PACKET_SIZE).zip(out.chunks_mut(PACKET_SIZE)) {
        if rays.len() >= MIN_INCOHERENT_PACKET {
            packet(rays, out, counts);
        } else {
            for (ray, out) in rays.iter().zip(out.iter_mut()) {
                *out = single(ray, counts);
            }
        }
    }
}

/// How many of the `left` paths still to sample the next wave takes: [`WAVE_SIZE`], or
/// where the light-carrying paths sampled so far say that fewer, in whole packets of 16,
/// reach `max_light`, that many, so that little is traced past where sampling stops.
fn wave_size(paths: &TestPaths, left: usize, max_light: usize) -> usize {
    let stored = paths.len();
    let wanted = if stored == 0 || max_light == usize::MAX {
        WAVE_SIZE
    } else {
        // Paths needed at the rate seen so far (`stored` per `sampled`), rounded up.
        let needed = max_light
            .saturating_sub(stored)
            .saturating_mul(paths.sampled);
        needed.div_ceil(stored).next_multiple_of(PACKET_SIZE)
    };
    wanted.clamp(PACKET_SIZE, WAVE_SIZE).min(left)
}

impl TestPaths {
    /// An empty store (no path sampled yet) of the estimator `nee`'s paths.
    pub fn new(max_bounces: u32, nee: Nee) -> Self {
        Self {
            sampled: 0,
            max_bounces,
            estimator: nee,
            f2_over_q: Vec::new(),
            f2_rgb_over_q: Vec::new(),
            f_over_q_sum: DVec3::ZERO,
            weights: ChannelWeights::EQUAL,
            len: Vec::new(),
            nee: Vec::new(),
            light: Vec::new(),
            connected: Vec::new(),
            light_delta: Vec::new(),
            area_to_solid_angle: Vec::new(),
            end_point: Vec::new(),
            end_prim: Vec::new(),
            offsets: vec![0],
            shared: Vec::new(),
            point: Vec::new(),
            prim: Vec::new(),
            wi: Vec::new(),
            brdf_pdf: Vec::new(),
            delta: Vec::new(),
            walks: WalksOnce::default(),
        }
    }

    /// Samples `m` paths from `q` through pixel `(x, y)` (box filter: a uniformly jittered
    /// camera ray), path `j` with the random stream `sample_rng(seed, pixel, j)`, traced in
    /// waves of paths: their camera rays, then at each step the closest-hit rays of the
    /// paths still going and their shadow rays, each kind in packets of 16. The result is
    /// [`TestPaths::sample_single`]'s.
    pub fn sample(
        view: &SceneView,
        q: &Mixture,
        (x, y): (u32, u32),
        m: usize,
        max_bounces: u32,
        seed: u64,
    ) -> (Self, RayCounts) {
        Self::sample_until(view, q, (x, y), (m, usize::MAX), max_bounces, seed)
    }

    /// [`TestPaths::sample`], stopping early, after the 16 paths (`0..16`, `16..32`, …)
    /// during which the stored light-carrying paths reach `max_light`: where most paths carry light, a few thousand
    /// of them already pin eq. 10 down, and each costs the genetic algorithm `S + 1`
    /// multiply-adds per individual. `sampled` counts the paths actually sampled.
    pub fn sample_until(
        view: &SceneView,
        q: &Mixture,
        (x, y): (u32, u32),
        (m, max_light): (usize, usize),
        max_bounces: u32,
        seed: u64,
    ) -> (Self, RayCounts) {
        Self::sample_around(view, q, ((x, y), 1.0), (m, max_light), max_bounces, seed)
    }

    /// [`TestPaths::sample_until`] with camera rays through a square of `side` pixels
    /// centred on pixel `(x, y)` ([`footprint_ray`]) rather than through the pixel: the paths
    /// of the pixels a GA pixel's mixture will render, not of that pixel alone.
    pub fn sample_around(
        view: &SceneView,
        q: &Mixture,
        ((x, y), side): ((u32, u32), f32),
        (m, max_light): (usize, usize),
        max_bounces: u32,
        seed: u64,
    ) -> (Self, RayCounts) {
        let mut paths = Self::new(max_bounces, q.nee);
        let mut counts = RayCounts::default();
        let mut wave = Wave::new();
        let mut first = 0;
        'waves: while first < m {
            let n = wave_size(&paths, m - first, max_light);
            let js = first..first + n;
            wave.start(view, q, ((x, y), side), seed, js, max_bounces, &mut counts);
            // Until every walk is done. Shadow rays are gathered after the closest-hit
            // answers, so that those just issued go along.
            loop {
                let closest = wave.trace_closest(view, q, &mut counts);
                if closest + wave.trace_shadows(view, &mut counts) == 0 {
                    break;
                }
            }
            // Stored in order, and checked packet by packet of 16 paths: where sampling
            // stops does not depend on the size of the waves.
            for packet in wave.lanes[..n].chunks(PACKET_SIZE) {
                for lane in packet {
                    paths.store(view, q, &lane.path, &lane.contributions);
                }
                if paths.len() >= max_light {
                    break 'waves;
                }
            }
            first += n;
        }
        paths.weigh(ChannelWeights::relative(paths.value()));
        (paths, counts)
    }

    /// [`TestPaths::sample`] with every ray traced on its own
    /// ([`PathGenerator::sample_path`]): the reference the packets must reproduce.
    pub fn sample_single(
        view: &SceneView,
        q: &Mixture,
        (x, y): (u32, u32),
        m: usize,
        max_bounces: u32,
        seed: u64,
    ) -> (Self, RayCounts) {
        let mut paths = Self::new(max_bounces, q.nee);
        let mut counts = RayCounts::default();
        let mut path = PathVertices::default();
        let mut contributions = Vec::new();
        let camera = &view.scene.camera;
        sample_pixel(camera, seed, (x, y), 0..m as u64, |ray, rng| {
            contributions.clear();
            if let Some(x1) = view.trace_through(ray, rng, &mut counts) {
                let g = q.choose(uniform(rng) as f64);
                q.generators[g].sample_path(
                    view,
                    ray.origin,
                    x1,
                    (max_bounces, q.nee),
                    rng,
                    &mut counts,
                    &mut path,
                    &mut contributions,
                );
            }
            paths.store(view, q, &path, &contributions);
            ControlFlow::Continue(())
        });
        paths.weigh(ChannelWeights::relative(paths.value()));
        (paths, counts)
    }

    /// Counts one sampled path and stores its light-carrying sub-paths, `F²/q` with `q`'s
    /// density.
    fn store(
        &mut self,
        view: &SceneView,
        q: &Mixture,
        path: &PathVertices,
        contributions: &[Contribution],
    ) {
        self.sampled += 1;
        for c in contributions {
            let pdf = q.pdf_path(view, path, c, self.max_bounces);
            if pdf > 0.0 && c.f.max_element() > 0.0 {
                self.f_over_q_sum += c.f / pdf;
                self.push(view, path, c, c.f * c.f / pdf);
            }
        }
    }

    /// Stores the part of `path` that contribution `c` uses, with its `f_c²/q` (`sampled`,
    /// the `M` of eq. 10, is the caller's to count; `f2_over_q` is [`Self::weigh`]'s).
    pub fn push(&mut self, view: &SceneView, path: &PathVertices, c: &Contribution, f2q: DVec3) {
        self.walks = WalksOnce::default();
        let every = self.estimator == Nee::Every;
        let scattering = if c.nee && !every { c.len - 1 } else { c.len };
        for (j, v) in path.vertices[..scattering].iter().enumerate() {
            // With an emitter point, the last vertex's direction is the one to it.
            let wi = match c.light {
                Some(l) if j + 1 == c.len => l.wi,
                _ => v.wi,
            };
            let pdf = if v.delta {
                0.0
            } else {
                let m = view.scattering_material(&v.point, v.wo);
                bsdf::pdf(m, bsdf::Frame::facing(&v.point, v.wo), v.wo, wi)
            };
            self.point.push(v.point.p.as_dvec3());
            self.prim.push(v.point.prim);
            self.wi.push(wi.as_dvec3());
            self.brdf_pdf.push(pdf);
            self.delta.push(v.delta);
        }
        self.offsets.push(self.point.len() as u32);
        self.len.push(c.len as u32);
        self.nee.push(c.nee);
        let end = match (c.light, c.nee, path.light) {
            (Some(l), _, _) => Some((l.end, l.wi)),
            (None, true, Some(l)) if !every => Some((l.end, l.wi)),
            _ => None,
        };
        let (point, prim) = match end {
            Some((LightEnd::Area { point, prim }, _)) => (point, prim),
            _ => (DVec3::ZERO, u32::MAX),
        };
        self.light.push(StoredLight {
            fixed: end.and_then(|(e, wi)| fixed_light_pdf(view, &e, wi)),
            prim,
            cell: match prim {
                u32::MAX => 0,
                prim => finest_cell(&view.scene.mesh, prim, point),
            },
        });
        self.connected.push(end.is_some());
        self.light_delta
            .push(matches!(end, Some((LightEnd::Delta, _))));
        self.area_to_solid_angle
            .push(c.light.map_or(0.0, |l| l.area_to_solid_angle));
        let end = match path.vertices.get(scattering) {
            _ if every => (point, prim),
            Some(v) if c.nee => (v.point.p.as_dvec3(), v.point.prim),
            _ => (DVec3::ZERO, u32::MAX),
        };
        self.end_point.push(end.0);
        self.end_prim.push(end.1);
        self.f2_rgb_over_q.push(f2q);
        let i = self.len() - 1;
        let shared = match i.checked_sub(1) {
            Some(before) => {
                let (a, b) = (self.product_vertices(before), self.product_vertices(i));
                a.zip(b)
                    .take_while(|&(a, b)| self.same_vertex(a, b))
                    .count()
            }
            None => 0,
        };
        self.shared.push(shared as u32);
    }

    /// The vertices of stored path `i` whose directions' densities multiply in
    /// [`Self::generator_pdfs`]: all but the last of a path that ends with two techniques.
    fn product_vertices(&self, i: usize) -> std::ops::Range<usize> {
        let (start, end) = (self.offsets[i] as usize, self.offsets[i + 1] as usize);
        let two_techniques = self.estimator == Nee::Every && self.connected[i];
        start..end - usize::from(two_techniques)
    }

    /// Whether vertices `a` and `b` hold the same bits in everything a generator's density
    /// reads of them.
    fn same_vertex(&self, a: usize, b: usize) -> bool {
        let bits = |v: DVec3| v.to_array().map(f64::to_bits);
        bits(self.point[a]) == bits(self.point[b])
            && bits(self.wi[a]) == bits(self.wi[b])
            && self.brdf_pdf[a].to_bits() == self.brdf_pdf[b].to_bits()
            && self.delta[a] == self.delta[b]
    }

    /// Sets the channel weights of `F` and recomputes every `F²/q`.
    pub fn weigh(&mut self, weights: ChannelWeights) {
        self.weights = weights;
        self.f2_over_q.clear();
        self.f2_over_q
            .extend(self.f2_rgb_over_q.iter().map(|&s| weights.weigh(s)));
    }

    /// The channel weights of `F`.
    pub fn weights(&self) -> ChannelWeights {
        self.weights
    }

    /// `(1/M) Σ f/q`: the pixel's scattered light, as the test paths estimate it.
    pub fn value(&self) -> DVec3 {
        if self.sampled == 0 {
            DVec3::ZERO
        } else {
            self.f_over_q_sum / self.sampled as f64
        }
    }

    /// Directional samples that carry all but `share` of the light: the smallest `L` such that
    /// paths of at most `L` sampled directions hold `(1 − share)` of `Σ F²/q`; at least 1.
    /// Generator steps past it would be spent where the test paths saw no light.
    pub fn steps_needed(&self, share: f64) -> usize {
        let total: f64 = self.f2_over_q.iter().sum();
        if total <= 0.0 {
            return 1;
        }
        // A path of `len` vertices sampled `len − 1` directions when it ends with a light
        // point, `len` when it ends on an emitter seen through a mirror.
        let mut by_steps: Vec<(usize, f64)> = (0..self.len())
            .map(|i| {
                let len = self.len[i] as usize;
                (if self.nee[i] { len - 1 } else { len }, self.f2_over_q[i])
            })
            .collect();
        by_steps.sort_by_key(|&(steps, _)| steps);
        let mut acc = 0.0;
        for &(steps, f) in &by_steps {
            acc += f;
            if acc >= (1.0 - share) * total {
                return steps.max(1);
            }
        }
        // Summed in another order than `total`, `acc` may end an ulp short of it: every
        // path is needed then.
        by_steps.last().map_or(1, |&(steps, _)| steps.max(1))
    }

    /// `√(Σ_c w_c I_c²)` for [`Self::value`] `I`: what eq. 10's second moment less its
    /// square is the variance of.
    pub fn mean(&self) -> f64 {
        let i = self.value();
        self.weights.weigh(i * i).sqrt()
    }

    /// Where step `k` of a generator must aim to reproduce stored path `i`: the point its
    /// `k`-th non-delta scattering vertex's direction reached (the next vertex, or: with
    /// [`Nee::End`] the one that absorbed and connected to the light, with [`Nee::Every`] the
    /// emitter point) and its triangle; `None` where the path has no such step or it ended on
    /// an emitter it hit through a mirror.
    pub fn step_target(&self, i: usize, k: usize) -> Option<(DVec3, u32)> {
        let j = self.step_vertex(i, k)?;
        let end = self.offsets[i + 1] as usize;
        if j + 1 < end {
            Some((self.point[j + 1], self.prim[j + 1]))
        } else if self.end_prim[i] != u32::MAX {
            Some((self.end_point[i], self.end_prim[i]))
        } else {
            None
        }
    }

    /// The `k`-th non-delta scattering vertex of stored path `i`, as an index of the vertex
    /// arrays.
    fn step_vertex(&self, i: usize, k: usize) -> Option<usize> {
        let (start, end) = (self.offsets[i] as usize, self.offsets[i + 1] as usize);
        (start..end).filter(|&j| !self.delta[j]).nth(k)
    }

    /// Where step `k` of stored path `i` started and the unit direction it sampled.
    pub fn step_origin(&self, i: usize, k: usize) -> Option<(DVec3, DVec3)> {
        let j = self.step_vertex(i, k)?;
        Some((self.point[j], self.wi[j]))
    }

    /// Number of stored (light-carrying) paths.
    pub fn len(&self) -> usize {
        self.f2_rgb_over_q.len()
    }

    pub fn is_empty(&self) -> bool {
        self.f2_rgb_over_q.is_empty()
    }

    /// The density `p_g` of every stored path, into `out` (`out.len() == self.len()`):
    /// the same value as `PathGenerator::pdf_contribution` on the original path.
    pub fn generator_pdfs(&self, view: &SceneView, g: &PathGenerator, out: &mut [f64]) {
        let steps: Vec<Vec<f64>> = (0..self.step_count().min(g.steps.len()))
            .map(|k| {
                let mut densities = Vec::new();
                self.step_pdfs(k, &g.steps[k].sampler, &mut densities);
                densities
            })
            .collect();
        let steps: Vec<&[f64]> = steps.iter().map(Vec::as_slice).collect();
        let mut lights = Vec::new();
        self.light_pdfs(view, g, &mut lights);
        self.generator_pdfs_with(g, (&steps, &lights), out);
    }

    /// The density with which `g`'s light technique draws each stored path's light point
    /// (`PathGenerator::light_pdf`; 0 for a path without one), into `out`: it depends on
    /// `g`'s light-point sampler alone.
    pub fn light_pdfs(&self, view: &SceneView, g: &PathGenerator, out: &mut Vec<f64>) {
        let density = GeneratorDensity::new(g, view);
        out.clear();
        out.extend(self.walks().paths.iter().zip(&self.light).map(
            |(walk, light)| match walk.end {
                WalkEnd::Direction => 0.0,
                _ => density.light(view, (light.fixed, light.prim), |level| {
                    PointCells::of_finest(light.cell, level)
                }),
            },
        ));
    }

    /// The number of steps whose densities [`Self::generator_pdfs_with`] reads: the most
    /// non-delta vertices of a stored path.
    pub fn step_count(&self) -> usize {
        self.walks().of_step.len()
    }

    /// `sampler`'s densities as step `k` of a generator at the vertices where
    /// [`Self::generator_pdfs_with`] reads them, into `out`.
    pub fn step_pdfs(&self, k: usize, sampler: &DirectionSampler, out: &mut Vec<f64>) {
        let density = StepDensity::new(sampler);
        out.clear();
        out.extend(self.walks().of_step[k].iter().map(|&j| {
            let j = j as usize;
            density.pdf(|| (self.point[j], self.wi[j]), || self.brdf_pdf[j])
        }));
    }

    /// [`Walks`] of the stored paths.
    fn walks(&self) -> &Walks {
        self.walks.0.get_or_init(|| {
            let every = self.estimator == Nee::Every;
            let max = self.max_bounces;
            let mut walks = Walks::default();
            // With next-event estimation at every vertex a direction follows the light
            // point: at `max_bounces` only a path that escaped to the environment stores one
            // (`PathGenerator::pdf_techniques`); before it, both absorptions agree.
            let read = |walks: &mut Walks, j: usize, k: usize, bounce: usize| {
                if walks.of_step.len() <= k {
                    walks.of_step.resize_with(k + 1, Vec::new);
                }
                let place = walks.of_step[k].len() as u32;
                walks.of_step[k].push(j as u32);
                let absorbs = absorbs_at(bounce, max, every);
                Read { place, absorbs }
            };
            for i in 0..self.len() {
                let start = self.offsets[i] as usize;
                let end = self.product_vertices(i).end;
                let unshared = start + self.shared[i] as usize;
                let mut k = (start..unshared).filter(|&j| !self.delta[j]).count();
                let shared = k as u32;
                for j in (unshared..end).filter(|&j| !self.delta[j]) {
                    let r = read(&mut walks, j, k, j - start + 1);
                    walks.reads.push(r);
                    k += 1;
                }
                let len = self.len[i] as usize;
                let end = if every && self.connected[i] {
                    let read = if self.light_delta[i] {
                        Read {
                            place: u32::MAX,
                            absorbs: true,
                        }
                    } else {
                        read(&mut walks, end, k, len)
                    };
                    WalkEnd::Both {
                        read,
                        area_to_solid_angle: self.area_to_solid_angle[i],
                    }
                } else if self.nee[i] && !every {
                    WalkEnd::Light {
                        absorbs: absorbs_at(len, max, false),
                    }
                } else {
                    WalkEnd::Direction
                };
                walks.paths.push(PathWalk {
                    shared,
                    reads_end: walks.reads.len() as u32,
                    end,
                });
            }
            walks
        })
    }

    /// [`Self::generator_pdfs`] with `g`'s direction densities at step `k` given by
    /// `steps[k]` ([`Self::step_pdfs`] of its sampler there; every step below
    /// [`Self::step_count`] that `g` has) and its light technique's by `lights`
    /// ([`Self::light_pdfs`]).
    ///
    /// The product of the direction densities runs along each sampled path once: a stored
    /// path starts from the running product over the vertices it shares with the one before
    /// it, which is the same product of the same factors in the same order.
    pub fn generator_pdfs_with(
        &self,
        g: &PathGenerator,
        (steps, lights): (&[&[f64]], &[f64]),
        out: &mut [f64],
    ) {
        let walks = self.walks();
        // Per step of `g`: its absorption and its densities (none past those the paths
        // read, where only an end-only light point may still follow the absorption).
        let table: Vec<(f64, &[f64])> = (0..g.steps.len())
            .map(|k| {
                (
                    g.absorption_unless(k, false),
                    steps.get(k).copied().unwrap_or_default(),
                )
            })
            .collect();
        // `g`'s absorption at step `k` where a read `absorbs` or not, as
        // [`PathGenerator::absorption_unless`], and its densities.
        let step = |k: usize, absorbs: bool| match table.get(k) {
            Some(&(a, densities)) if !absorbs => (a, densities),
            _ => (1.0, &[][..]),
        };
        // `prefix[t]`: the product over the first `t` reads of the path last evaluated;
        // `absorbed`: its read `prefix.len() − 1` has absorption 1 (its density is 0 from
        // there on).
        let mut prefix: Vec<f64> = vec![1.0];
        let mut absorbed = false;
        let mut first = 0;
        for ((walk, out), &light) in walks.paths.iter().zip(out.iter_mut()).zip(lights) {
            let reads = &walks.reads[first..walk.reads_end as usize];
            first = walk.reads_end as usize;
            let mut k = walk.shared as usize;
            if absorbed && k >= prefix.len() {
                *out = 0.0;
                continue;
            }
            prefix.truncate(k + 1);
            absorbed = false;
            let mut pdf = prefix[k];
            for read in reads {
                let (a, densities) = step(k, read.absorbs);
                if a >= 1.0 {
                    absorbed = true;
                    break;
                }
                pdf *= (1.0 - a) * densities[read.place as usize];
                k += 1;
                prefix.push(pdf);
            }
            if absorbed {
                *out = 0.0;
                continue;
            }
            match walk.end {
                WalkEnd::Both {
                    read,
                    area_to_solid_angle,
                } if pdf > 0.0 => {
                    let (a, densities) = step(k, read.absorbs);
                    let dir = if a >= 1.0 || read.place == u32::MAX {
                        0.0
                    } else {
                        (1.0 - a) * densities[read.place as usize]
                    };
                    let light = light * area_to_solid_angle;
                    pdf = pdf * dir + pdf * light;
                }
                WalkEnd::Light { absorbs } if pdf > 0.0 => {
                    pdf *= step(k, absorbs).0 * light;
                }
                _ => {}
            }
            *out = pdf;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A store of paths with `(sampled directions, F²/q)`, in this order.
    fn store(paths: &[(u32, f64)]) -> TestPaths {
        let mut t = TestPaths::new(5, Nee::End);
        for &(steps, f2q) in paths {
            // A path of `steps + 1` vertices ending with a light point.
            t.len.push(steps + 1);
            t.nee.push(true);
            t.f2_rgb_over_q.push(DVec3::splat(f2q));
        }
        t.weigh(ChannelWeights::EQUAL);
        t
    }

    #[test]
    fn steps_needed_counts_every_path_despite_rounding() {
        // In storage order the sum is 1e16 + 2; in order of steps the two 1s vanish into
        // 1e16 (half an ulp each), so the running sum never reaches the total.
        let paths = store(&[(4, 1.0), (4, 1.0), (1, 1e16)]);
        assert_eq!(paths.steps_needed(0.0), 4);
        // With a share to leave out, the long paths' light is not needed.
        assert_eq!(paths.steps_needed(0.01), 1);
        // Without light, one step.
        assert_eq!(store(&[]).steps_needed(0.0), 1);
        assert_eq!(store(&[(3, 1.0), (2, 1.0)]).steps_needed(0.4), 3);
    }
}
