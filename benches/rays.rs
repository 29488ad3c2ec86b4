//! Rays per second of each built back-end, on one thread: single rays against 16-wide packets,
//! coherent (camera) against incoherent (random) rays, closest hit and any hit.
//!
//! `cargo bench --features embree,obvhs --bench rays [-- scenes/cbox/scene.toml]`: a scene's
//! camera gives the coherent rays; without a scene, the generated 106 800-triangle stress mesh
//! of the cross-check test is seen by a camera placed outside its bounds.

#[path = "../tests/stress/mod.rs"]
mod stress;

use genpath::accel::{self, Accel, AccelError, AccelKind, Hit, Ray, PACKET_SIZE};
use genpath::scene::Scene;
use glam::Vec3;
use std::error::Error;
use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

/// Rays per set (a 1024² camera image); every timing covers a whole set.
const RAYS: u32 = 1024;
/// Each figure is the best of this many passes (the machine is shared).
const PASSES: usize = 3;

fn main() -> Result<(), Box<dyn Error>> {
    // `cargo bench` passes `--bench`; anything else not starting with `-` is a scene path.
    let path = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let (mesh, coherent, label) = match &path {
        Some(path) => {
            let scene = Scene::load(Path::new(path))?;
            let camera = scene.camera.resized(RAYS, RAYS);
            let rays = stress::tiled_pixels(RAYS, RAYS)
                .map(|(x, y)| camera.ray(x as f32 + 0.5, y as f32 + 0.5))
                .collect();
            (scene.mesh, rays, path.clone())
        }
        None => {
            let mesh = stress::stress_mesh(7);
            let (lo, hi) = stress::bounds(&mesh);
            let center = (lo + hi) / 2.0;
            let eye = center + Vec3::new(0.07, 0.18, 1.0).normalize() * 0.65 * (hi - lo).length();
            let rays = stress::camera_rays(eye, center, 50.0, RAYS, RAYS);
            (mesh, rays, "generated stress mesh".to_string())
        }
    };
    let (lo, hi) = stress::bounds(&mesh);
    let sets = [
        ("coherent", coherent),
        (
            "incoherent",
            stress::random_rays(lo, hi, (RAYS * RAYS) as usize, 11),
        ),
    ];

    println!(
        "{label}: {} triangles; {} rays per set; best of {PASSES}; one thread",
        mesh.triangles.len(),
        RAYS * RAYS
    );
    println!(
        "{:<8} {:<11} {:<10} {:>13} {:>15} {:>7}",
        "back-end", "rays", "query", "single Mray/s", "packet16 Mray/s", "hit %"
    );
    for kind in [AccelKind::Embree, AccelKind::Bvh] {
        let start = Instant::now();
        let accel = match accel::build(kind, &mesh) {
            Ok(accel) => accel,
            Err(AccelError::NotBuilt(name, feature)) => {
                println!("{name:<8} not built (feature `{feature}`)");
                continue;
            }
            Err(err) => return Err(err.into()),
        };
        let build = start.elapsed();
        for (set, rays) in &sets {
            let (single, hits) = best(|| intersect_single(&*accel, rays));
            let (packet, _) = best(|| intersect_packets(&*accel, rays));
            row(
                accel.name(),
                set,
                "intersect",
                rays.len(),
                single,
                packet,
                hits,
            );
            let (single, blocked) = best(|| occluded_single(&*accel, rays));
            let (packet, _) = best(|| occluded_packets(&*accel, rays));
            row(
                accel.name(),
                set,
                "occluded",
                rays.len(),
                single,
                packet,
                blocked,
            );
        }
        println!(
            "{:<8} build {:.0} ms",
            accel.name(),
            build.as_secs_f64() * 1e3
        );
    }
    Ok(())
}

fn row(
    name: &str,
    set: &str,
    query: &str,
    n: usize,
    single: Duration,
    packet: Duration,
    hits: usize,
) {
    let mrays = |d: Duration| n as f64 / d.as_secs_f64() / 1e6;
    let hit_percent = 100.0 * hits as f64 / n as f64;
    println!(
        "{name:<8} {set:<11} {query:<10} {:>13.2} {:>15.2} {hit_percent:>7.1}",
        mrays(single),
        mrays(packet)
    );
}

/// Shortest time of `PASSES` runs of `f`, and what `f` counted.
fn best(mut f: impl FnMut() -> usize) -> (Duration, usize) {
    let mut fastest = Duration::MAX;
    let mut count = 0;
    for _ in 0..PASSES {
        let start = Instant::now();
        count = black_box(f());
        fastest = fastest.min(start.elapsed());
    }
    (fastest, count)
}

fn intersect_single(accel: &dyn Accel, rays: &[Ray]) -> usize {
    rays.iter()
        .filter(|r| accel.intersect(black_box(r)).is_some())
        .count()
}

fn intersect_packets(accel: &dyn Accel, rays: &[Ray]) -> usize {
    let mut hits = [None::<Hit>; PACKET_SIZE];
    rays.chunks(PACKET_SIZE)
        .map(|packet| {
            let hits = &mut hits[..packet.len()];
            accel.intersect_packet(black_box(packet), hits);
            hits.iter().filter(|h| h.is_some()).count()
        })
        .sum()
}

fn occluded_single(accel: &dyn Accel, rays: &[Ray]) -> usize {
    rays.iter().filter(|r| accel.occluded(black_box(r))).count()
}

fn occluded_packets(accel: &dyn Accel, rays: &[Ray]) -> usize {
    let mut blocked = [false; PACKET_SIZE];
    rays.chunks(PACKET_SIZE)
        .map(|packet| {
            let blocked = &mut blocked[..packet.len()];
            accel.occluded_packet(black_box(packet), blocked);
            blocked.iter().filter(|&&b| b).count()
        })
        .sum()
}
