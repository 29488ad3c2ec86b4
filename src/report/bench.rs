//! Throughput measurements for `genpath bench` and `cargo bench --bench rays`: rays per
//! second per back-end (coherent camera rays against incoherent random rays, single rays
//! against 16-wide packets, closest hit and any hit), fitness evaluations per second, and
//! render time against the number of threads.
//!
//! Every figure is the best of a few passes: the machines are shared, and the best pass is
//! the one least disturbed.

use crate::accel::{Accel, Coherence, Hit, Ray, PACKET_SIZE};
use crate::scene::Camera;
use glam::Vec3;
use rand::{Rng as _, SeedableRng};
use rand_pcg::Pcg64Mcg;
use std::hint::black_box;
use std::time::{Duration, Instant};

/// Incoherent rays: origins uniform in `(lo, hi)`, unit directions uniform on the sphere.
pub fn random_rays(lo: Vec3, hi: Vec3, count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            let origin = lo + (hi - lo) * Vec3::from_array(std::array::from_fn(|_| rng.random()));
            // Uniform on the sphere: z uniform in [-1, 1], azimuth uniform.
            let z: f32 = rng.random_range(-1.0..1.0);
            let phi: f32 = rng.random_range(0.0..std::f32::consts::TAU);
            let r = (1.0 - z * z).max(0.0).sqrt();
            Ray::new(
                origin,
                Vec3::new(r * phi.cos(), r * phi.sin(), z),
                0.0,
                f32::INFINITY,
            )
        })
        .collect()
}

/// Pixel coordinates of a `width × height` image in 4×4 tiles, so that each packet of
/// [`PACKET_SIZE`] consecutive pixels covers one tile.
pub fn tiled_pixels(width: u32, height: u32) -> impl Iterator<Item = (u32, u32)> {
    const TILE: u32 = 4;
    const _: () = assert!((TILE * TILE) as usize == PACKET_SIZE);
    (0..height).step_by(TILE as usize).flat_map(move |ty| {
        (0..width).step_by(TILE as usize).flat_map(move |tx| {
            (ty..(ty + TILE).min(height))
                .flat_map(move |y| (tx..(tx + TILE).min(width)).map(move |x| (x, y)))
        })
    })
}

/// Coherent rays: the camera's pixel centres at `width × height`, in [`tiled_pixels`] order.
pub fn camera_rays(camera: &Camera, width: u32, height: u32) -> Vec<Ray> {
    let camera = camera.resized(width, height);
    tiled_pixels(width, height)
        .map(|(x, y)| camera.ray(x as f32 + 0.5, y as f32 + 0.5))
        .collect()
}

/// Shortest time of `passes` runs of `f`, and what `f` counted.
pub fn best(passes: usize, mut f: impl FnMut() -> usize) -> (Duration, usize) {
    let [result] = best_interleaved(passes, [&mut f]);
    result
}

/// [`best`] of several measurements that are to be compared: each pass runs every one of
/// them once, in turn, so that a change in the machine's load between passes weighs on all
/// of them alike instead of on whichever happened to run then.
pub fn best_interleaved<const N: usize>(
    passes: usize,
    mut fs: [&mut dyn FnMut() -> usize; N],
) -> [(Duration, usize); N] {
    let mut results = [(Duration::MAX, 0); N];
    for _ in 0..passes.max(1) {
        for (f, (fastest, count)) in fs.iter_mut().zip(&mut results) {
            let start = Instant::now();
            *count = black_box(f());
            *fastest = (*fastest).min(start.elapsed());
        }
    }
    results
}

/// A back-end's name and packet width as the bench tables print it: `embree/8`, `bvh/1`.
pub fn accel_label(accel: &dyn Accel) -> String {
    format!("{}/{}", accel.name(), accel.packet_lanes())
}

fn intersect_single(accel: &dyn Accel, rays: &[Ray]) -> usize {
    rays.iter()
        .filter(|r| accel.intersect(black_box(r)).is_some())
        .count()
}

fn intersect_packets(accel: &dyn Accel, rays: &[Ray], coherence: Coherence) -> usize {
    let mut hits = [None::<Hit>; PACKET_SIZE];
    rays.chunks(PACKET_SIZE)
        .map(|packet| {
            let hits = &mut hits[..packet.len()];
            accel.intersect_packet(black_box(packet), hits, coherence);
            hits.iter().filter(|h| h.is_some()).count()
        })
        .sum()
}

fn occluded_single(accel: &dyn Accel, rays: &[Ray]) -> usize {
    rays.iter().filter(|r| accel.occluded(black_box(r))).count()
}

fn occluded_packets(accel: &dyn Accel, rays: &[Ray], coherence: Coherence) -> usize {
    let mut blocked = [false; PACKET_SIZE];
    rays.chunks(PACKET_SIZE)
        .map(|packet| {
            let blocked = &mut blocked[..packet.len()];
            accel.occluded_packet(black_box(packet), blocked, coherence);
            blocked.iter().filter(|&&b| b).count()
        })
        .sum()
}

/// Millions of rays per second of one back-end on one ray set, on the calling thread.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct RayRates {
    pub closest_single: f64,
    pub closest_packet: f64,
    pub occluded_single: f64,
    pub occluded_packet: f64,
    /// Fraction of the rays that hit something.
    pub hit_fraction: f64,
}

/// Measures [`RayRates`], each query the best of `passes` (interleaved); packets are traced
/// with the traversal `coherence` asks for.
pub fn ray_rates(accel: &dyn Accel, rays: &[Ray], coherence: Coherence, passes: usize) -> RayRates {
    let n = rays.len() as f64;
    let mrays = |d: Duration| n / d.as_secs_f64().max(1e-12) / 1e6;
    let [(closest_single, hits), (closest_packet, _), (occluded_single, _), (occluded_packet, _)] =
        best_interleaved(
            passes,
            [
                &mut || intersect_single(accel, rays),
                &mut || intersect_packets(accel, rays, coherence),
                &mut || occluded_single(accel, rays),
                &mut || occluded_packets(accel, rays, coherence),
            ],
        );
    RayRates {
        closest_single: mrays(closest_single),
        closest_packet: mrays(closest_packet),
        occluded_single: mrays(occluded_single),
        occluded_packet: mrays(occluded_packet),
        hit_fraction: hits as f64 / n.max(1.0),
    }
}
