//! Rays per second of each built back-end, on one thread: single rays against 16-wide packets,
//! coherent (camera) against incoherent (random) rays, closest hit and any hit.
//!
//! `cargo bench --features embree,obvhs --bench rays [-- scenes/cbox/scene.toml]`: a scene's
//! camera gives the coherent rays; without a scene, the generated 106 800-triangle stress mesh
//! of the cross-check test is seen by a camera placed outside its bounds. `genpath bench`
//! measures the same on a scene, with fitness evaluations and thread scaling.

#[path = "../tests/stress/mod.rs"]
mod stress;

use genpath::accel::{self, AccelError, AccelKind, Coherence};
use genpath::report::bench::{accel_label, camera_rays, random_rays, ray_rates};
use genpath::scene::Scene;
use glam::Vec3;
use std::error::Error;
use std::path::Path;
use std::time::Instant;

/// Rays per set (a 1024² camera image); every timing covers a whole set.
const RAYS: u32 = 1024;
/// Each figure is the best of this many passes (the machine is shared).
const PASSES: usize = 5;

fn main() -> Result<(), Box<dyn Error>> {
    // `cargo bench` passes `--bench`; anything else not starting with `-` is a scene path.
    let path = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let (mesh, coherent, label) = match &path {
        Some(path) => {
            let scene = Scene::load(Path::new(path))?;
            let rays = camera_rays(&scene.camera, RAYS, RAYS);
            (scene.mesh, rays, path.clone())
        }
        None => {
            let mesh = stress::stress_mesh(7);
            let (lo, hi) = mesh.bounds();
            let center = (lo + hi) / 2.0;
            let eye = center + Vec3::new(0.07, 0.18, 1.0).normalize() * 0.65 * (hi - lo).length();
            let rays = stress::camera_rays(eye, center, 50.0, RAYS, RAYS);
            (mesh, rays, "generated stress mesh".to_string())
        }
    };
    let (lo, hi) = mesh.bounds();
    let sets = [
        ("coherent", coherent, Coherence::Coherent),
        (
            "incoherent",
            random_rays(lo, hi, (RAYS * RAYS) as usize, 11),
            Coherence::Incoherent,
        ),
    ];

    println!(
        "{label}: {} triangles; {} rays per set; best of {PASSES}; one thread",
        mesh.triangles.len(),
        RAYS * RAYS
    );
    println!(
        "{:<11} {:<11} {:<10} {:>13} {:>15} {:>7}",
        "back/lanes", "rays", "query", "single Mray/s", "packet16 Mray/s", "hit %"
    );
    for kind in [AccelKind::Embree, AccelKind::Bvh] {
        let start = Instant::now();
        let accel = match accel::build(kind, &mesh) {
            Ok(accel) => accel,
            Err(AccelError::NotBuilt(name, feature)) => {
                println!("{name:<11} not built (feature `{feature}`)");
                continue;
            }
            Err(err) => return Err(err.into()),
        };
        let build = start.elapsed();
        for (set, rays, coherence) in &sets {
            let r = ray_rates(&*accel, rays, *coherence, PASSES);
            for (query, single, packet) in [
                ("intersect", r.closest_single, r.closest_packet),
                ("occluded", r.occluded_single, r.occluded_packet),
            ] {
                println!(
                    "{:<11} {set:<11} {query:<10} {single:>13.2} {packet:>15.2} {:>7.1}",
                    accel_label(&*accel),
                    100.0 * r.hit_fraction
                );
            }
        }
        println!(
            "{:<8} build {:.0} ms",
            accel.name(),
            build.as_secs_f64() * 1e3
        );
    }
    Ok(())
}
