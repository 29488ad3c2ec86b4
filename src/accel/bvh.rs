//! Ray queries through the pure-Rust `obvhs` crate: a binary BVH built with PLOC and
//! reinsertion, traversed one ray at a time.
//!
//! Not obvhs's faster CWBVH: its node test clamps the entry distance to a fixed 1e-4
//! (`cwbvh::node::EPSILON`) instead of the ray's `tmin`, so it misses every hit closer than
//! 1e-4 whose leaf box ends before that — all hits of a scene of scale 1e-4, and any-hit
//! queries with `tmax < 1e-4`. The BVH2 node test has no such floor.

use super::{Accel, AnalyticShapes, Coherence, Hit, Ray, TriangleMesh, PACKET_SIZE};
use obvhs::bvh2::{builder::build_bvh2_from_tris, Bvh2};
use obvhs::ray::RayHit;
use obvhs::rt_triangle::RtTriangle;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use std::time::Duration;

pub struct BvhAccel {
    /// `None` for an empty mesh, which obvhs cannot build a tree for.
    bvh: Option<Bvh2>,
    /// Triangles in the BVH's leaf order, so a leaf's primitives are read contiguously;
    /// `prim_ids[i]` is the index of `tris[i]` in [`TriangleMesh::triangles`].
    tris: Vec<RtTriangle>,
    prim_ids: Vec<u32>,
    normals: Vec<glam::Vec3>,
    /// Spheres and disks, tested after the triangles.
    analytic: AnalyticShapes,
}

impl BvhAccel {
    pub fn new(mesh: &TriangleMesh) -> Self {
        let triangles: Vec<Triangle> = (0..mesh.triangles.len() as u32)
            .map(|prim| {
                let [v0, v1, v2] = mesh.vertices(prim).map(glam::Vec3A::from);
                Triangle { v0, v1, v2 }
            })
            .collect();
        if triangles.is_empty() {
            return Self {
                bvh: None,
                tris: Vec::new(),
                prim_ids: Vec::new(),
                normals: Vec::new(),
                analytic: mesh.analytic_shapes(),
            };
        }
        // medium_build: about Embree's build time with faster traversal (obvhs's own advice).
        let bvh = build_bvh2_from_tris(
            &triangles,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        let prim_ids = bvh.primitive_indices.clone();
        let tris = prim_ids
            .iter()
            .map(|&i| RtTriangle::from(&triangles[i as usize]))
            .collect();
        Self {
            bvh: Some(bvh),
            tris,
            prim_ids,
            normals: mesh.normals.clone(),
            analytic: mesh.analytic_shapes(),
        }
    }
}

fn obvhs_ray(ray: &Ray) -> obvhs::ray::Ray {
    obvhs::ray::Ray::new(ray.origin.into(), ray.dir.into(), ray.tmin, ray.tmax)
}

impl BvhAccel {
    /// The closest triangle along a valid `ray`.
    fn intersect_triangles(&self, ray: &Ray) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let ray = obvhs_ray(ray);
        let mut hit = RayHit::none();
        if !bvh.ray_traverse(ray, &mut hit, |r, i| self.tris[i].intersect(r)) {
            return None;
        }
        let slot = hit.primitive_id as usize;
        let prim = self.prim_ids[slot];
        // RtTriangle's barycentrics are Embree's (u weights v1, v weights v2);
        // Triangle::compute_barycentric uses another convention.
        let uv = self.tris[slot].compute_barycentric(&ray);
        Some(Hit {
            t: hit.t,
            prim,
            u: uv.x,
            v: uv.y,
            ng: self.normals[prim as usize],
        })
    }
}

impl Accel for BvhAccel {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if !ray.is_valid() {
            return None;
        }
        let hit = self.intersect_triangles(ray);
        if self.analytic.is_empty() {
            return hit;
        }
        self.analytic.closest(ray, hit)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        if !ray.is_valid() {
            return true;
        }
        self.bvh.as_ref().is_some_and(|bvh| {
            !bvh.ray_traverse_miss(obvhs_ray(ray), |r, i| self.tris[i].intersect(r))
        }) || self.analytic.occludes(ray)
    }

    fn intersect_packet(&self, rays: &[Ray], hits: &mut [Option<Hit>], _: Coherence) {
        assert!(rays.len() <= PACKET_SIZE && rays.len() == hits.len());
        for (ray, hit) in rays.iter().zip(hits) {
            *hit = self.intersect(ray);
        }
    }

    fn occluded_packet(&self, rays: &[Ray], blocked: &mut [bool], _: Coherence) {
        assert!(rays.len() <= PACKET_SIZE && rays.len() == blocked.len());
        for (ray, out) in rays.iter().zip(blocked) {
            *out = self.occluded(ray);
        }
    }

    fn name(&self) -> &'static str {
        "bvh"
    }

    fn packet_lanes(&self) -> usize {
        1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn hits_the_right_triangle_with_embree_barycentrics() {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let accel = BvhAccel::new(&TriangleMesh::new(positions, vec![[0, 1, 2], [0, 2, 3]]));
        let down = Vec3::new(0.0, 0.0, -1.0);
        // In triangle 0 = (v0, v1, v2), (0.75, 0.25) = v0 + 0.5 (v1 − v0) + 0.25 (v2 − v0).
        let hit = accel.intersect(&Ray::new(
            Vec3::new(0.75, 0.25, 2.0),
            down,
            0.0,
            f32::INFINITY,
        ));
        let hit = hit.expect("ray through the quad hits");
        assert_eq!(hit.prim, 0);
        assert!((hit.t - 2.0).abs() < 1e-6);
        assert!(
            (hit.u - 0.5).abs() < 1e-6 && (hit.v - 0.25).abs() < 1e-6,
            "{hit:?}"
        );
        assert_eq!(hit.ng, Vec3::Z);
        let hit = accel.intersect(&Ray::new(Vec3::new(0.25, 0.75, 2.0), down, 0.0, 5.0));
        assert_eq!(hit.map(|h| h.prim), Some(1));
        assert!(accel
            .intersect(&Ray::new(Vec3::new(1.5, 0.5, 2.0), down, 0.0, 5.0))
            .is_none());
        assert!(!accel.occluded(&Ray::new(Vec3::new(0.5, 0.5, 2.0), down, 0.0, 1.9)));
        assert!(accel.occluded(&Ray::new(Vec3::new(0.5, 0.5, 2.0), down, 0.0, 2.1)));
    }

    #[test]
    fn empty_mesh_misses_everything() {
        let accel = BvhAccel::new(&TriangleMesh::default());
        let ray = Ray::new(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY);
        assert!(accel.intersect(&ray).is_none());
        assert!(!accel.occluded(&ray));
    }
}
