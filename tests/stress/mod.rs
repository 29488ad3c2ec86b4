//! Generated geometry and rays shared by the cross-check test and the ray benchmark
//! (`benches/rays.rs` includes this file by path).

use genpath::accel::{Ray, TriangleMesh};
use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// A stress scene of 106 800 triangles with lots of occlusion and shared edges:
/// a bumpy sphere (cube-sphere, 6·80² quads), a wavy floor grid (100² quads) and a soup of
/// 10 000 small random triangles that pierce both and each other.
pub fn stress_mesh(seed: u64) -> TriangleMesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    bumpy_sphere(80, &mut positions, &mut triangles);
    wavy_floor(100, &mut positions, &mut triangles);
    triangle_soup(10_000, seed, &mut positions, &mut triangles);
    TriangleMesh::new(positions, triangles)
}

/// Two triangles per grid cell of a `(n+1)²` vertex grid starting at index `base`.
fn grid_triangles(base: u32, n: u32, triangles: &mut Vec<[u32; 3]>) {
    let at = |i: u32, j: u32| base + i * (n + 1) + j;
    for i in 0..n {
        for j in 0..n {
            triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
}

/// Each cube face gridded and pushed onto a displaced unit sphere. Vertices on the cube's
/// edges are computed from the same cube point by both faces, so the seams close exactly.
fn bumpy_sphere(n: u32, positions: &mut Vec<Vec3>, triangles: &mut Vec<[u32; 3]>) {
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let base = positions.len() as u32;
            for i in 0..=n {
                for j in 0..=n {
                    let a = -1.0 + 2.0 * i as f32 / n as f32;
                    let b = -1.0 + 2.0 * j as f32 / n as f32;
                    let mut cube = [0.0; 3];
                    cube[axis] = sign;
                    cube[(axis + 1) % 3] = a;
                    cube[(axis + 2) % 3] = b;
                    let dir = Vec3::from_array(cube).normalize();
                    let bump =
                        0.08 * (7.0 * dir.x).sin() * (5.0 * dir.y).sin() * (6.0 * dir.z).sin();
                    positions.push(dir * (1.0 + bump));
                }
            }
            grid_triangles(base, n, triangles);
        }
    }
}

fn wavy_floor(n: u32, positions: &mut Vec<Vec3>, triangles: &mut Vec<[u32; 3]>) {
    let base = positions.len() as u32;
    for i in 0..=n {
        for j in 0..=n {
            let x = -2.0 + 4.0 * i as f32 / n as f32;
            let z = -2.0 + 4.0 * j as f32 / n as f32;
            positions.push(Vec3::new(
                x,
                -1.3 + 0.05 * (3.0 * x).sin() * (2.0 * z).cos(),
                z,
            ));
        }
    }
    grid_triangles(base, n, triangles);
}

fn triangle_soup(
    count: usize,
    seed: u64,
    positions: &mut Vec<Vec3>,
    triangles: &mut Vec<[u32; 3]>,
) {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    for _ in 0..count {
        let center = Vec3::from_array(std::array::from_fn(|_| rng.random_range(-1.6..1.6)));
        let base = positions.len() as u32;
        for _ in 0..3 {
            let offset = Vec3::from_array(std::array::from_fn(|_| rng.random_range(-0.08..0.08)));
            positions.push(center + offset);
        }
        triangles.push([base, base + 1, base + 2]);
    }
}

use genpath::report::bench::tiled_pixels;

/// Coherent rays: a pinhole camera's `width × height` pixel centres in [`tiled_pixels`] order.
pub fn camera_rays(eye: Vec3, target: Vec3, fov_x_deg: f32, width: u32, height: u32) -> Vec<Ray> {
    let forward = (target - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let half_width = (fov_x_deg.to_radians() / 2.0).tan();
    let half_height = half_width * height as f32 / width as f32;
    tiled_pixels(width, height)
        .map(|(x, y)| {
            let sx = (2.0 * (x as f32 + 0.5) / width as f32 - 1.0) * half_width;
            let sy = (1.0 - 2.0 * (y as f32 + 0.5) / height as f32) * half_height;
            let dir = (forward + sx * right + sy * up).normalize();
            Ray::new(eye, dir, 0.0, f32::INFINITY)
        })
        .collect()
}
