//! Ray queries against the scene's triangles and analytic shapes: one interface, two
//! back-ends.
//!
//! `embree.rs` goes through Intel Embree (`embree4-sys`), `bvh.rs` through the pure-Rust
//! `obvhs` crate. Both answer closest-hit and any-hit queries for single rays and for
//! packets of up to [`PACKET_SIZE`] rays; a packet query returns exactly what the same rays
//! would return one at a time, with one exception: a ray that meets two triangles at the
//! same `t` (through an edge they share) may get either from Embree's coherent packet
//! traversal, which visits triangles in another order.

use glam::{DVec3, Vec3};

mod analytic;
#[cfg(feature = "obvhs")]
mod bvh;
#[cfg(feature = "embree")]
#[allow(unsafe_code)]
mod embree;

pub use analytic::{concentric_disk, Analytic, AnalyticError, AnalyticShapes, SphereCone};
#[cfg(feature = "obvhs")]
pub use bvh::BvhAccel;
#[cfg(feature = "embree")]
pub use embree::EmbreeAccel;

/// Rays per packet query (Embree's `rtcIntersect16`).
pub const PACKET_SIZE: usize = 16;

/// How alike the rays of a packet are, which a back-end may use to pick its traversal.
/// Answers depend on it only at exact ties (see the module documentation); speed does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coherence {
    /// Rays with nearby origins and directions, e.g. camera rays through one pixel or tile:
    /// Embree traverses them as a packet (one frustum).
    Coherent,
    /// Rays in unrelated directions, e.g. after a bounce: Embree's default (hybrid)
    /// traversal, which goes on ray by ray once few rays of the packet are left.
    Incoherent,
}

/// A ray segment `origin + t·dir`, `t ∈ [tmin, tmax]`. `dir` need not be normalised; `t` is
/// measured in units of `dir`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    pub tmin: f32,
    pub tmax: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Self {
        Self {
            origin,
            dir,
            tmin,
            tmax,
        }
    }

    /// A query both back-ends answer: finite origin and direction, `0 ≤ tmin ≤ tmax` (`tmax`
    /// may be infinite). Embree asserts on anything else, so every back-end answers an invalid
    /// ray the same conservative way instead: no hit, and blocked.
    pub fn is_valid(&self) -> bool {
        self.origin.is_finite()
            && self.dir.is_finite()
            && self.tmin.is_finite()
            && self.tmin >= 0.0
            && self.tmax >= self.tmin
    }
}

/// The closest intersection of a ray with the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Index of the triangle in [`TriangleMesh::triangles`], or past them, of the analytic
    /// shape in [`TriangleMesh::shapes`].
    pub prim: u32,
    /// Barycentrics in Embree's convention: `p = (1−u−v)·v0 + u·v1 + v·v2`; on an analytic
    /// shape, its parameterisation ([`Analytic::intersect`]).
    pub u: f32,
    pub v: f32,
    /// Unit geometric normal `normalize(cross(v1 − v0, v2 − v0))`, or the analytic shape's.
    pub ng: Vec3,
}

/// Triangles as the accelerators consume them (shared vertices and indices), and the
/// analytic shapes after them: primitive `triangles.len() + i` is `shapes[i]`.
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Unit geometric normal of each triangle (`cross(v1 − v0, v2 − v0)`, normalised).
    pub normals: Vec<Vec3>,
    pub shapes: Vec<Analytic>,
}

impl TriangleMesh {
    /// Builds a mesh and its face normals. Degenerate triangles get a zero normal; callers
    /// that must not see them remove them first.
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Self {
        let normals = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                (b - a).cross(c - a).normalize_or_zero()
            })
            .collect();
        Self {
            positions,
            triangles,
            normals,
            shapes: Vec::new(),
        }
    }

    /// The vertices of triangle `prim` (not of an analytic shape).
    pub fn vertices(&self, prim: u32) -> [Vec3; 3] {
        self.triangles[prim as usize].map(|i| self.positions[i as usize])
    }

    /// Triangles and analytic shapes.
    pub fn prim_count(&self) -> usize {
        self.triangles.len() + self.shapes.len()
    }

    /// The analytic shape `prim` is, `None` for a triangle.
    pub fn analytic(&self, prim: u32) -> Option<&Analytic> {
        (prim as usize)
            .checked_sub(self.triangles.len())
            .and_then(|i| self.shapes.get(i))
    }

    /// The analytic shapes as the back-ends answer them.
    pub fn analytic_shapes(&self) -> AnalyticShapes {
        AnalyticShapes {
            shapes: self.shapes.clone(),
            first: self.triangles.len() as u32,
        }
    }

    /// Area of primitive `prim`.
    pub fn area(&self, prim: u32) -> f64 {
        match self.analytic(prim) {
            Some(shape) => shape.area(),
            None => crate::math::triangle_area(self.vertices(prim)),
        }
    }

    /// Unit geometric normal of primitive `prim` at `p`, a point on it.
    pub fn normal_at(&self, prim: u32, p: DVec3) -> DVec3 {
        match self.analytic(prim) {
            Some(shape) => shape.normal_at(p),
            None => self.normals[prim as usize].as_dvec3(),
        }
    }

    /// Axis-aligned bounds of the vertices and shapes (`lo > hi` for a mesh without any).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self
            .positions
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        self.shapes.iter().fold((lo, hi), |(lo, hi), s| {
            let (a, b) = s.bounds();
            (lo.min(a.as_vec3()), hi.max(b.as_vec3()))
        })
    }
}

/// What every back-end answers.
pub trait Accel: Send + Sync {
    /// Closest hit along the ray, if any.
    fn intersect(&self, ray: &Ray) -> Option<Hit>;
    /// Whether anything blocks the ray within `[tmin, tmax]`.
    fn occluded(&self, ray: &Ray) -> bool;
    /// Closest hits of up to [`PACKET_SIZE`] rays; `hits.len() == rays.len()`.
    fn intersect_packet(&self, rays: &[Ray], hits: &mut [Option<Hit>], coherence: Coherence);
    /// Any-hit answers of up to [`PACKET_SIZE`] rays; `blocked.len() == rays.len()`.
    fn occluded_packet(&self, rays: &[Ray], blocked: &mut [bool], coherence: Coherence);
    /// Back-end name for logs and stats.
    fn name(&self) -> &'static str;
    /// What decides this back-end's answers to the last bit: its name, and for Embree the
    /// instruction set of the kernels it traces with (a shard's identity records it, since
    /// kernels for other instruction sets may round differently).
    fn kernels(&self) -> String {
        self.name().to_string()
    }
    /// Rays per traversal call inside a packet query: Embree's packet width, 1 for a back-end
    /// that answers a packet ray by ray.
    fn packet_lanes(&self) -> usize;
}

/// Which back-end to build, chosen by `--accel`.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum AccelKind {
    /// Intel Embree (feature `embree`).
    Embree,
    /// Pure-Rust obvhs (feature `obvhs`).
    Bvh,
}

impl AccelKind {
    /// The back-end used when `--accel` is not given: Embree where it is built.
    pub fn default_available() -> Self {
        if cfg!(feature = "embree") {
            AccelKind::Embree
        } else {
            AccelKind::Bvh
        }
    }
}

/// The instruction sets Embree has kernels for (its `isa=` device setting). genpath always
/// names one when it creates the device (the best the CPU runs unless `--embree-isa` pins
/// another), so that the kernels are known, and neither Embree's own choice nor an
/// `.embree3` file can change them unseen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, clap::ValueEnum)]
pub enum EmbreeIsa {
    #[value(name = "sse2")]
    Sse2,
    #[value(name = "sse4.2")]
    Sse42,
    #[value(name = "avx")]
    Avx,
    #[value(name = "avx2")]
    Avx2,
    #[value(name = "avx512")]
    Avx512,
}

impl EmbreeIsa {
    /// Embree's name of the instruction set.
    pub fn name(self) -> &'static str {
        match self {
            EmbreeIsa::Sse2 => "sse2",
            EmbreeIsa::Sse42 => "sse4.2",
            EmbreeIsa::Avx => "avx",
            EmbreeIsa::Avx2 => "avx2",
            EmbreeIsa::Avx512 => "avx512",
        }
    }

    /// Whether this CPU (and its operating system) runs the instruction set, with the
    /// features Embree's kernels for it need (Embree's `getCPUFeatures` groups).
    pub fn runs_here(self) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            match self {
                EmbreeIsa::Sse2 => has!("sse2"),
                EmbreeIsa::Sse42 => has!("sse4.2") && has!("popcnt"),
                EmbreeIsa::Avx => EmbreeIsa::Sse42.runs_here() && has!("avx"),
                EmbreeIsa::Avx2 => {
                    EmbreeIsa::Avx.runs_here()
                        && has!("avx2")
                        && has!("fma")
                        && has!("bmi1")
                        && has!("bmi2")
                        && has!("lzcnt")
                        && has!("f16c")
                }
                EmbreeIsa::Avx512 => {
                    EmbreeIsa::Avx2.runs_here()
                        && has!("avx512f")
                        && has!("avx512cd")
                        && has!("avx512dq")
                        && has!("avx512bw")
                        && has!("avx512vl")
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            false
        }
    }

    /// The best instruction set this CPU runs, `None` on a CPU that is not x86-64 (where
    /// Embree chooses).
    pub fn best_here() -> Option<Self> {
        use clap::ValueEnum;
        Self::value_variants()
            .iter()
            .rev()
            .copied()
            .find(|isa| isa.runs_here())
    }
}

#[derive(Debug, thiserror::Error)]
pub enum AccelError {
    #[error("--embree-isa {}: this CPU does not run it (it runs {})", .0.name(), EmbreeIsa::best_here().map_or("none of Embree's x86-64 kernels", |b| b.name()))]
    IsaUnsupported(EmbreeIsa),
    #[error("--embree-isa {}: the ray-tracing back-end is not Embree (--accel embree)", .0.name())]
    IsaWithoutEmbree(EmbreeIsa),
    #[error("the {0} back-end is not built into this binary (rebuild with `--features {1}`)")]
    NotBuilt(&'static str, &'static str),
    #[error("Embree: {0}")]
    Embree(String),
}

/// Builds the chosen back-end over `mesh`.
pub fn build(kind: AccelKind, mesh: &TriangleMesh) -> Result<Box<dyn Accel>, AccelError> {
    build_with(kind, mesh, None)
}

/// [`build`], with Embree's kernels pinned to `isa` (`None`: the best this CPU runs).
pub fn build_with(
    kind: AccelKind,
    mesh: &TriangleMesh,
    isa: Option<EmbreeIsa>,
) -> Result<Box<dyn Accel>, AccelError> {
    if let (Some(isa), AccelKind::Bvh) = (isa, kind) {
        return Err(AccelError::IsaWithoutEmbree(isa));
    }
    match kind {
        #[cfg(feature = "embree")]
        AccelKind::Embree => Ok(Box::new(EmbreeAccel::with_isa(mesh, isa)?)),
        #[cfg(not(feature = "embree"))]
        AccelKind::Embree => Err(AccelError::NotBuilt("embree", "embree")),
        #[cfg(feature = "obvhs")]
        AccelKind::Bvh => Ok(Box::new(BvhAccel::new(mesh))),
        #[cfg(not(feature = "obvhs"))]
        AccelKind::Bvh => Err(AccelError::NotBuilt("bvh", "obvhs")),
    }
}
