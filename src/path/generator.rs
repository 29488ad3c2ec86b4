//! Path generators and their weighted sets (paper §5.1–5.3; docs/methods/mixture.md,
//! "Path generators and mixtures").
//!
//! A [`PathGenerator`] is a sequence of (directional sampler, absorption) pairs plus a
//! light-point sampler. It samples an eye path vertex by vertex, as a `Walk` (`walk.rs`: a state
//! machine that stops at each ray it needs traced, so that one implementation serves single
//! rays, [`PathGenerator::sample_path`], and packets). Delta vertices (mirrors, glass:
//! [`crate::scene::material::specular`]) consume no sampler and never absorb; glass's choice
//! between reflection and refraction is the material's, left out of every density. Where the estimator does next-event estimation is its [`Nee`]:
//!
//! * [`Nee::End`], the paper's: at the k-th non-delta vertex the path absorbs with
//!   probability `a_k`, then draws a point on a light and traces one shadow ray, or samples a
//!   direction with `s_k` and traces on. Emission found by a direction counts only through a
//!   delta vertex.
//! * [`Nee::Every`]: at every non-delta vertex a light point and its shadow ray first, then
//!   absorption or a direction; emission found by a direction always counts. A path of `n`
//!   scattering vertices then comes from each generator by two techniques, direction
//!   sampling at every vertex (`p_dir`) or up to `x_{n−1}` and a light point from `x_n`
//!   (`p_light`, without `x_n`'s absorption), which the mixture weighs by the balance
//!   heuristic over every (generator, technique) pair.
//!
//! The light sample picks an emitter as `pt` does ([`crate::scene::Scene::pick_light`]):
//! a point on the area emitters by the generator's light-point sampler, a direction towards
//! the environment, or a delta light ([`LightEnd`]). A delta light is reached by the light
//! technique alone (its density the pick's probability); the environment by both with
//! [`Nee::Every`], by the light sample alone with [`Nee::End`], as an area emitter.
//!
//! Every generator evaluates the density of a path that *any* generator produced from the
//! stored vertices alone ([`PathGenerator::pdf_contribution`]), which is what the
//! balance-heuristic estimator of a [`Mixture`](super::mixture::Mixture) (paper eq. 7–8) and
//! the fitness of the genetic algorithm need.

use super::SceneView;
use crate::sampling::anchor::{AnchorSampler, AnchorShape};
use crate::sampling::light_point::{LightDensity, LightPointSampler, PointCells};
use crate::sampling::patch::{PatchSampler, PatchShape};
use crate::scene::material::bsdf;
use crate::scene::SurfacePoint;
use glam::{DVec3, Vec3};

/// Smallest and largest absorption before the last sampler: keeps every path length
/// reachable (unbiasedness) and every generator able to continue.
pub const ABSORPTION_MIN: f64 = 1e-3;
pub const ABSORPTION_MAX: f64 = 1.0 - 1e-3;
/// The default absorption of the `srt` generator at each vertex (`[srt] srt_absorption`)
/// where next-event estimation runs at the path's end alone ([`Nee::End`]): the paper's
/// estimator, and the test paths of `ga-pt`'s GA.
pub const SRT_ABSORPTION: f64 = 0.5;
/// The absorption of the `srt` generator with next-event estimation at every vertex
/// ([`Nee::Every`]) from its [`SRT_ROULETTE_FROM`]-th step on, where each vertex gathers
/// direct light and absorption only shortens the paths that gather it: about ten vertices
/// past that step where `max_depth` leaves paths unbounded.
pub const SRT_ABSORPTION_NEE_EVERY: f64 = 0.1;
/// With [`Nee::Every`], the `srt` generator's steps before this one do not absorb (their
/// absorption is [`ABSORPTION_MIN`]), as `pt`'s Russian roulette starts at bounce
/// [`RR_START`](crate::scene::RR_START). Absorbing from the first vertex made `srt` noisier
/// than `pt` per sample (docs/methods/srt.md, "The `srt` generator's absorption with NEE
/// at every vertex").
pub const SRT_ROULETTE_FROM: usize = crate::scene::RR_START as usize;

/// The `srt` generator's absorption: `per_vertex` at each step from step `from` on, and
/// [`ABSORPTION_MIN`] before it. A plain number is the paper's fixed absorption at every
/// vertex (`from` 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SrtAbsorption {
    pub per_vertex: f64,
    pub from: usize,
}

impl SrtAbsorption {
    /// The absorption of step `k`.
    pub fn at(self, k: usize) -> f64 {
        if k < self.from {
            ABSORPTION_MIN
        } else {
            self.per_vertex
        }
    }
}

impl Default for SrtAbsorption {
    /// [`Nee::default`]'s.
    fn default() -> Self {
        Nee::default().default_srt_absorption()
    }
}

impl From<f64> for SrtAbsorption {
    fn from(per_vertex: f64) -> Self {
        Self {
            per_vertex,
            from: 0,
        }
    }
}

/// Where a mixture's estimator does next-event estimation (the setting `nee`).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum Nee {
    /// At every non-delta vertex, before absorption, with the balance heuristic over every
    /// (generator, technique) pair: what stands against path tracing.
    #[default]
    Every,
    /// Only at the absorbing vertex (paper §5, its Fig. 7).
    End,
}

impl Nee {
    /// The `srt` generator's default absorption with this estimator: with [`Nee::Every`]
    /// [`SRT_ABSORPTION_NEE_EVERY`] from step [`SRT_ROULETTE_FROM`] on, none before; with
    /// [`Nee::End`] the paper's [`SRT_ABSORPTION`] at every vertex.
    pub fn default_srt_absorption(self) -> SrtAbsorption {
        match self {
            Nee::Every => SrtAbsorption {
                per_vertex: SRT_ABSORPTION_NEE_EVERY,
                from: SRT_ROULETTE_FROM,
            },
            Nee::End => SRT_ABSORPTION.into(),
        }
    }
}

/// A generator's density of the first `vertices` vertices of a path (the product over
/// its `steps` non-delta ones of `(1 − absorption) × direction density`), kept between the
/// contributions of one path by [`PathGenerator::pdf_techniques_after`]; `absorbed` where a
/// step's absorption of 1 makes every longer contribution's density 0.
#[derive(Clone, Copy, Debug)]
pub struct Prefix {
    vertices: usize,
    steps: usize,
    pdf: f64,
    absorbed: bool,
}

impl Default for Prefix {
    fn default() -> Self {
        Self {
            vertices: 0,
            steps: 0,
            pdf: 1.0,
            absorbed: false,
        }
    }
}

/// How a generator picks the direction out of a vertex. In text (JSON, TOML) it is tagged by
/// `type` (`{ type = "anchor", anchor = […], … }`); in binary formats (a plan file), which
/// cannot read such tags, by the variant's index ([`serde_direction`]).
#[derive(Clone, Debug, PartialEq)]
pub enum DirectionSampler {
    /// Proportional to BRDF × cos (the material's own sampler).
    Brdf,
    /// A cone towards an anchor point (paper §5.2).
    Anchor(AnchorSampler),
    /// Points on a parallelogram in space (beyond the paper: light that arrives from a
    /// long, thin region, which cones cover poorly).
    Patch(PatchSampler),
}

/// [`DirectionSampler`]'s two serialised forms: tagged by `type` where the format is
/// human-readable, by variant index where it is not.
mod serde_direction {
    use super::{AnchorSampler, DirectionSampler, PatchSampler};
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    #[derive(Serialize, Deserialize)]
    #[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
    enum Tagged {
        Brdf,
        Anchor(AnchorSampler),
        Patch(PatchSampler),
    }

    #[derive(Serialize, Deserialize)]
    enum Indexed {
        Brdf,
        Anchor(AnchorSampler),
        Patch(PatchSampler),
    }

    impl Serialize for DirectionSampler {
        fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
            let human = serializer.is_human_readable();
            match (self.clone(), human) {
                (DirectionSampler::Brdf, true) => Tagged::Brdf.serialize(serializer),
                (DirectionSampler::Anchor(a), true) => Tagged::Anchor(a).serialize(serializer),
                (DirectionSampler::Patch(p), true) => Tagged::Patch(p).serialize(serializer),
                (DirectionSampler::Brdf, false) => Indexed::Brdf.serialize(serializer),
                (DirectionSampler::Anchor(a), false) => Indexed::Anchor(a).serialize(serializer),
                (DirectionSampler::Patch(p), false) => Indexed::Patch(p).serialize(serializer),
            }
        }
    }

    impl<'de> Deserialize<'de> for DirectionSampler {
        fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
            Ok(if deserializer.is_human_readable() {
                match Tagged::deserialize(deserializer)? {
                    Tagged::Brdf => DirectionSampler::Brdf,
                    Tagged::Anchor(a) => DirectionSampler::Anchor(a),
                    Tagged::Patch(p) => DirectionSampler::Patch(p),
                }
            } else {
                match Indexed::deserialize(deserializer)? {
                    Indexed::Brdf => DirectionSampler::Brdf,
                    Indexed::Anchor(a) => DirectionSampler::Anchor(a),
                    Indexed::Patch(p) => DirectionSampler::Patch(p),
                }
            })
        }
    }
}

/// One step of a generator: a directional sampler and the absorption before it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Step {
    pub sampler: DirectionSampler,
    /// Probability of ending the path at this vertex (then a light point is sampled).
    pub absorption: f64,
}

/// A path generator: steps for the non-delta vertices 1, 2, … and a light-point sampler.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathGenerator {
    pub steps: Vec<Step>,
    pub light: LightPointSampler,
}

/// Whether every generator's absorption is 1 at scattering event `bounce` (no direction is
/// sampled there): from `max_bounces` on, or with next-event estimation at every vertex
/// after the light point (`after_light`) only past it ([`PathGenerator::absorption`],
/// [`PathGenerator::absorption_after_light`]). It depends on the path alone.
#[inline]
pub fn absorbs_at(bounce: usize, max_bounces: u32, after_light: bool) -> bool {
    let max = max_bounces as usize;
    if after_light {
        bounce > max
    } else {
        bounce >= max
    }
}

/// One vertex of a sampled eye path, with what any generator needs to evaluate its density.
#[derive(Clone, Copy, Debug)]
pub struct PathVertex {
    pub point: SurfacePoint,
    /// Unit direction towards the previous vertex (the camera for the first).
    pub wo: Vec3,
    /// The shading frame the vertex scatters in, `Frame::facing(point, wo)`: built once by
    /// the walk, read by every generator's density.
    pub frame: bsdf::Frame,
    /// Unit direction sampled out of this vertex (zero at the path's end).
    pub wi: Vec3,
    /// A delta vertex (a mirror, glass): its direction was determined by the material (or
    /// chosen by it, for glass), not sampled by a generator.
    pub delta: bool,
    /// Density with which the sampling generator continued here: `(1 − a)·p(wi)`; 1 at a
    /// delta vertex. Kept to check [`PathGenerator::pdf_path`] against.
    pub pdf_sampled: f64,
}

/// What a light technique's sample, or a sampled direction, ends on after the last
/// scattering vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightEnd {
    /// A point on the area emitters, on primitive `prim`.
    Area { point: DVec3, prim: u32 },
    /// A delta light (`point`, `directional`), which only the light technique reaches: its
    /// density is the probability of its pick.
    Delta,
    /// The environment, along the direction that reached it.
    Environment,
}

/// The light sample drawn at the absorbing vertex (with [`Nee::End`]).
#[derive(Clone, Copy, Debug)]
pub struct LightVertex {
    pub end: LightEnd,
    /// Unit direction from the absorbing vertex towards it.
    pub wi: Vec3,
    /// Density with which the sampling generator ended here: `a · p_light`, `p_light`
    /// ([`PathGenerator::light_pdf`]) by area for a point on an area emitter, in solid angle
    /// for the environment, the pick's probability for a delta light.
    pub pdf_sampled: f64,
}

/// An eye path `x1 … xn` and, when it ended by absorption, its light point.
#[derive(Clone, Debug, Default)]
pub struct PathVertices {
    pub vertices: Vec<PathVertex>,
    pub light: Option<LightVertex>,
}

/// With [`Nee::Every`], what ends a contribution after its last scattering vertex `x_len`
/// (non-delta): an emitter point, a delta light or the environment, with what the other
/// technique's density needs.
#[derive(Clone, Copy, Debug)]
pub struct Connection {
    pub end: LightEnd,
    /// Unit direction from `x_len` towards it.
    pub wi: Vec3,
    /// `d² / cos_y` for an emitter point (it turns an area density at `y` into a
    /// solid-angle density at `x_len`); 1 otherwise.
    pub area_to_solid_angle: f64,
    /// Density with which the sampling generator drew it: the light technique's
    /// ([`PathGenerator::light_pdf`], by area for an emitter point), or the direction's
    /// `(1 − a)·p(wi)`.
    pub pdf_sampled: f64,
}

/// A path that carries light to the camera: its contribution `F(X)` (RGB, measurement
/// contribution with the pixel filter factored out) and where it ends.
///
/// With [`Nee::End`] the light point's measure is area; with [`Nee::Every`] every
/// contribution's last segment is in solid angle at `x_len`, the measure both techniques
/// share there.
#[derive(Clone, Copy, Debug)]
pub struct Contribution {
    pub f: DVec3,
    /// Number of scattering vertices of the path (`x1 … x_len`) before the emitter.
    pub len: usize,
    /// Ends with a light point (`true`) or on an emitter a sampled direction hit.
    pub nee: bool,
    /// With [`Nee::Every`], what ends the contribution after a non-delta `x_len` (none after
    /// a delta one, which admits direction sampling alone).
    pub light: Option<Connection>,
    /// Ends at the environment: by a direction that escaped the scene, or by a light
    /// sample towards it.
    pub escaped: bool,
}

/// [`PathGenerator::light_pdf`] where it is the same for every generator: for a delta light
/// and the environment (`None` for a point on the area emitters).
pub fn fixed_light_pdf(view: &SceneView, end: &LightEnd, wi: Vec3) -> Option<f64> {
    let scene = view.scene;
    match end {
        LightEnd::Area { .. } => None,
        LightEnd::Delta => Some(scene.light_pmf()),
        LightEnd::Environment => Some(
            scene
                .environment
                .as_ref()
                .map_or(0.0, |env| scene.light_pmf() * env.pdf_solid_angle(wi)),
        ),
    }
}

impl Contribution {
    /// What the contribution ends on after its last scattering vertex, where a light
    /// technique could have drawn it: its connection, or with [`Nee::End`] the light sample
    /// of `path` (its absorbing vertex's).
    pub fn end(&self, path: &PathVertices) -> Option<LightEnd> {
        self.light_end(path).map(|(end, _)| end)
    }

    /// [`Self::end`] and the unit direction towards it from `x_len`.
    pub fn light_end(&self, path: &PathVertices) -> Option<(LightEnd, Vec3)> {
        match (self.light, self.nee, path.light) {
            (Some(l), _, _) => Some((l.end, l.wi)),
            (None, true, Some(l)) => Some((l.end, l.wi)),
            _ => None,
        }
    }
}

/// A generator step's direction sampler with the constants of its density computed once (an
/// anchor cone's densities and test, a patch's inverse Gram matrix), for the many vertices
/// the mixture's densities and the fitness evaluate it on.
#[derive(Clone, Copy, Debug)]
pub enum StepDensity {
    Brdf,
    Anchor(AnchorShape),
    Patch(PatchShape),
}

impl StepDensity {
    pub fn new(sampler: &DirectionSampler) -> Self {
        match sampler {
            DirectionSampler::Brdf => Self::Brdf,
            DirectionSampler::Anchor(s) => Self::Anchor(AnchorShape::new(s)),
            DirectionSampler::Patch(s) => Self::Patch(PatchShape::new(s)),
        }
    }

    /// The density of unit direction `wi` out of `from`, `(from, wi) = at()`; for the BSDF's
    /// sampler, `brdf()`: it is the same for every generator that samples the BSDF at a
    /// vertex, so the caller evaluates it once for all. Each is read only where needed.
    #[inline]
    pub fn pdf(&self, at: impl FnOnce() -> (DVec3, DVec3), brdf: impl FnOnce() -> f64) -> f64 {
        match self {
            Self::Brdf => brdf(),
            Self::Anchor(s) => {
                let (from, wi) = at();
                s.pdf(from, wi)
            }
            Self::Patch(s) => {
                let (from, wi) = at();
                s.pdf(from, wi)
            }
        }
    }
}

/// A generator's densities with their constants computed once for a scene: each step's
/// ([`StepDensity`]) and its light-point sampler's ([`LightDensity`]), the same values as
/// the samplers' own `pdf`s. Both the render's mixture densities
/// ([`PathGenerator::pdf_techniques_after`]) and the fitness
/// (`genetic::test_paths::TestPaths::generator_pdfs`) evaluate through it.
#[derive(Clone, Debug)]
pub struct GeneratorDensity {
    steps: Vec<StepDensity>,
    light: LightDensity,
    /// The probability that the light technique picks the area emitters.
    area_pmf: f64,
}

impl GeneratorDensity {
    pub fn new(g: &PathGenerator, view: &SceneView) -> Self {
        let scene = view.scene;
        Self {
            steps: g
                .steps
                .iter()
                .map(|s| StepDensity::new(&s.sampler))
                .collect(),
            light: g.light.density(&scene.mesh, &scene.emitters),
            area_pmf: scene.area_light_pmf(),
        }
    }

    /// Step `k`'s density of the direction `at()` gives ([`StepDensity::pdf`]).
    #[inline]
    pub fn direction(
        &self,
        k: usize,
        at: impl FnOnce() -> (DVec3, DVec3),
        brdf: impl FnOnce() -> f64,
    ) -> f64 {
        self.steps[k].pdf(at, brdf)
    }

    /// Step `k`'s density of the direction sampled out of vertex `j`, `v`, of the path
    /// `shared` holds the BSDF densities of.
    #[inline]
    fn direction_at(
        &self,
        view: &SceneView,
        k: usize,
        (j, v): (usize, &PathVertex),
        shared: &mut PathDensities,
    ) -> f64 {
        let at = || (v.point.p.as_dvec3(), v.wi.as_dvec3());
        self.direction(k, at, || shared.along(view, j, v))
    }

    /// [`PathGenerator::light_pdf`] of an end whose density is `fixed` where it is the same
    /// for every generator ([`fixed_light_pdf`]), else a point on emitter triangle `prim`
    /// whose cell of a level is `cell_at(level)` (asked for only where this generator's light
    /// region needs it; [`PointCells::at`]).
    #[inline]
    pub fn light(
        &self,
        view: &SceneView,
        (fixed, prim): (Option<f64>, u32),
        cell_at: impl FnOnce(u8) -> u32,
    ) -> f64 {
        match fixed {
            Some(fixed) => fixed,
            None => self.area_pmf * self.light.pdf_area(&view.scene.emitters, prim, cell_at),
        }
    }
}

/// What the densities of every generator of a mixture share on one path: the BSDF density
/// of each vertex's direction (the same for every generator whose step samples the BSDF
/// there, evaluated when the first one needs it, once per path), that of the direction from
/// `x_len` to the current contribution's end, and that end's light density where it is the
/// same for every generator, or its emitter point and [`PointCells`] (found as deep as the
/// generators' light regions need, once per contribution).
#[derive(Clone, Debug, Default)]
pub struct PathDensities {
    along: Vec<Option<f64>>,
    to_end: Option<f64>,
    /// The contribution's end: [`fixed_light_pdf`], the emitter point and its triangle.
    end: Option<(Option<f64>, DVec3, u32)>,
    /// The end's [`PointCells`], found as deep as the generators' light regions asked.
    cells: Option<PointCells>,
}

impl PathDensities {
    /// Starts on `path`: no density evaluated yet.
    pub fn start_path(&mut self, path: &PathVertices) {
        self.along.clear();
        self.along.resize(path.vertices.len(), None);
        self.to_end = None;
        self.end = None;
    }

    /// Starts on a contribution of the path that ends at `end` (along the unit direction
    /// from `x_len`; [`Contribution::light_end`]): no density towards it evaluated yet.
    pub fn start_contribution(&mut self, view: &SceneView, end: Option<(LightEnd, Vec3)>) {
        self.to_end = None;
        self.cells = None;
        self.end = end.map(|(end, wi)| match end {
            LightEnd::Area { point, prim } => (None, point, prim),
            _ => (fixed_light_pdf(view, &end, wi), DVec3::ZERO, u32::MAX),
        });
    }

    /// Ready for the contribution of `path` that ends at `end`.
    fn of(view: &SceneView, path: &PathVertices, end: Option<(LightEnd, Vec3)>) -> Self {
        let mut shared = Self::default();
        shared.start_path(path);
        shared.start_contribution(view, end);
        shared
    }

    /// The BSDF density of the direction sampled out of vertex `j`, `v`.
    fn along(&mut self, view: &SceneView, j: usize, v: &PathVertex) -> f64 {
        *self.along[j].get_or_insert_with(|| brdf_pdf(view, v, v.wi))
    }

    /// The BSDF density of unit `wi` out of `last`, `x_len`, towards the contribution's end.
    fn towards_end(&mut self, view: &SceneView, last: &PathVertex, wi: Vec3) -> f64 {
        *self.to_end.get_or_insert_with(|| brdf_pdf(view, last, wi))
    }

    /// The light density of the generator of `density` at the contribution's end (`None`
    /// where it has none).
    fn light(&mut self, view: &SceneView, density: &GeneratorDensity) -> Option<f64> {
        let (fixed, point, prim) = self.end?;
        let cells = &mut self.cells;
        let cell_at = |level| {
            let cells = cells.get_or_insert_with(|| PointCells::new(&view.scene.mesh, prim, point));
            cells.at(level)
        };
        Some(density.light(view, (fixed, prim), cell_at))
    }
}

/// The BSDF density of unit `wi` out of vertex `v`.
fn brdf_pdf(view: &SceneView, v: &PathVertex, wi: Vec3) -> f64 {
    let m = view.scattering_material(&v.point, v.wo);
    bsdf::pdf(m, v.frame, v.wo, wi)
}

impl PathGenerator {
    /// The paper's "stochastic ray tracing" generator: BRDF sampling at every vertex with the
    /// absorption `absorption` (a number: the paper's fixed absorption at every vertex),
    /// uniform light sampling by area.
    pub fn srt(
        max_bounces: u32,
        absorption: impl Into<SrtAbsorption>,
        light: LightPointSampler,
    ) -> Self {
        let absorption = absorption.into();
        let steps = (0..max_bounces as usize)
            .map(|k| Step {
                sampler: DirectionSampler::Brdf,
                absorption: absorption.at(k),
            })
            .collect();
        Self { steps, light }
    }

    /// Absorption at the `k`-th non-delta vertex, which is scattering event `bounce`: 1 after
    /// the last step and at `max_bounces` ([`absorbs_at`]).
    pub fn absorption(&self, k: usize, bounce: usize, max_bounces: u32) -> f64 {
        self.absorption_unless(k, absorbs_at(bounce, max_bounces, false))
    }

    /// With [`Nee::Every`], the absorption at the `k`-th non-delta vertex, scattering event
    /// `bounce`, after its light point: as [`Self::absorption`], but at `max_bounces` itself
    /// the path may still sample a direction, which can only find emission (as `pt`'s last
    /// BSDF sample: light points alone there have unbounded variance where an emitter meets
    /// the surface, as in a furnace's corners).
    pub fn absorption_after_light(&self, k: usize, bounce: usize, max_bounces: u32) -> f64 {
        self.absorption_unless(k, absorbs_at(bounce, max_bounces, true))
    }

    /// Step `k`'s absorption, 1 past the last step or where `absorbs` (the scattering event
    /// is past the last that samples a direction, [`absorbs_at`]).
    #[inline]
    pub fn absorption_unless(&self, k: usize, absorbs: bool) -> f64 {
        match self.steps.get(k) {
            Some(step) if !absorbs => step.absorption,
            _ => 1.0,
        }
    }

    /// The density with which this generator's light technique draws `end` (along unit
    /// `wi`): the probability of the emitter's pick ([`crate::scene::Scene::pick_light`])
    /// times its light-point sampler's density by area for a point on the area emitters, the
    /// environment's in solid angle, or 1 for a delta light.
    pub fn light_pdf(&self, view: &SceneView, end: &LightEnd, wi: Vec3) -> f64 {
        let scene = view.scene;
        match (*end, fixed_light_pdf(view, end, wi)) {
            (_, Some(pdf)) => pdf,
            (LightEnd::Area { point, prim }, None) => {
                scene.area_light_pmf()
                    * self
                        .light
                        .pdf_area(&scene.mesh, &scene.emitters, point, prim)
            }
            (_, None) => 0.0,
        }
    }

    /// Density with which this generator produces the first `len` vertices of `path`
    /// followed by its light point (`nee`), or by an emitter hit through a delta vertex, or
    /// by the environment (the direction out of `x_len` escaped).
    /// Directions in solid angle, the light point in area: the measure all generators share.
    pub fn pdf_path(
        &self,
        view: &SceneView,
        path: &PathVertices,
        len: usize,
        nee: bool,
        max_bounces: u32,
    ) -> f64 {
        let end = path.light.filter(|_| nee).map(|l| (l.end, l.wi));
        let mut shared = PathDensities::of(view, path, end);
        let density = GeneratorDensity::new(self, view);
        self.pdf_path_with(&density, view, path, (len, nee, max_bounces), &mut shared)
    }

    /// [`Self::pdf_path`] with this generator's `density` and what every generator's
    /// density shares on `path` (`shared`, started on the contribution).
    pub fn pdf_path_with(
        &self,
        density: &GeneratorDensity,
        view: &SceneView,
        path: &PathVertices,
        (len, nee, max_bounces): (usize, bool, u32),
        shared: &mut PathDensities,
    ) -> f64 {
        let mut pdf = 1.0;
        let mut k = 0;
        let scattering = if nee { len - 1 } else { len };
        for (j, v) in path.vertices[..scattering].iter().enumerate() {
            if v.delta {
                continue;
            }
            let a = self.absorption(k, j + 1, max_bounces);
            if a >= 1.0 {
                return 0.0;
            }
            pdf *= (1.0 - a) * density.direction_at(view, k, (j, v), shared);
            k += 1;
        }
        if nee {
            if path.vertices.get(len - 1).is_none_or(|last| last.delta) {
                return 0.0;
            }
            let Some(light) = shared.light(view, density) else {
                return 0.0;
            };
            pdf *= self.absorption(k, len, max_bounces) * light;
        }
        pdf
    }

    /// With [`Nee::Every`], the densities `(p_dir, p_light)` with which this generator
    /// produces contribution `c` of `path` by its two techniques: directions at all `c.len`
    /// vertices, or at the first `c.len − 1` and then a light sample from `x_len`, whose
    /// absorption does not enter. Directions in solid angle, the last segment too (a light
    /// point's density converted there). After a delta `x_len` `p_light` is 0, and for a
    /// delta light `p_dir` is.
    pub fn pdf_techniques(
        &self,
        view: &SceneView,
        path: &PathVertices,
        c: &Contribution,
        max_bounces: u32,
    ) -> (f64, f64) {
        let mut prefix = Prefix::default();
        let mut shared = PathDensities::of(view, path, c.light_end(path));
        let density = GeneratorDensity::new(self, view);
        let state = (&mut prefix, &mut shared);
        self.pdf_techniques_after(&density, view, (path, false), c, max_bounces, state)
    }

    /// [`Self::pdf_techniques`] with this generator's `density`, continuing `prefix`, this
    /// generator's density of the path's first vertices from an earlier (shorter)
    /// contribution of the same path: the contributions of a path then cost one direction
    /// density per vertex, not one per vertex and contribution; `shared`, what every
    /// generator's density shares on the path (started on `c`). With `own`, this generator
    /// sampled `path`: the densities its walk drew with (each `pdf_sampled`) are then taken
    /// as stored, and only those of what it did not draw (the other technique's at `x_len`)
    /// are evaluated. The same products in the same order of the same factors: the same
    /// densities, bit for bit.
    pub fn pdf_techniques_after(
        &self,
        density: &GeneratorDensity,
        view: &SceneView,
        (path, own): (&PathVertices, bool),
        c: &Contribution,
        max_bounces: u32,
        (prefix, shared): (&mut Prefix, &mut PathDensities),
    ) -> (f64, f64) {
        if prefix.vertices > c.len - 1 {
            *prefix = Prefix::default();
        }
        for (j, v) in path.vertices[..c.len - 1]
            .iter()
            .enumerate()
            .skip(prefix.vertices)
        {
            prefix.vertices = j + 1;
            if prefix.absorbed || v.delta {
                continue;
            }
            let a = self.absorption(prefix.steps, j + 1, max_bounces);
            if a >= 1.0 {
                prefix.absorbed = true;
                continue;
            }
            prefix.pdf *= match own {
                true => v.pdf_sampled,
                false => (1.0 - a) * density.direction_at(view, prefix.steps, (j, v), shared),
            };
            prefix.steps += 1;
        }
        if prefix.absorbed {
            return (0.0, 0.0);
        }
        let (prefix, k) = (prefix.pdf, prefix.steps);
        let a = self.absorption_after_light(k, c.len, max_bounces);
        let last = &path.vertices[c.len - 1];
        let Some(end) = c.light else {
            // An emitter reached through a delta `x_len`: its direction had no density.
            if last.delta {
                return (prefix, 0.0);
            }
            let dir = match a >= 1.0 {
                true => 0.0,
                false => (1.0 - a) * density.direction_at(view, k, (c.len - 1, last), shared),
            };
            return (prefix * dir, 0.0);
        };
        // What this generator drew itself (`own`): the direction that found the emitter
        // (not `c.nee`) or the light point (`c.nee`), with the density it was drawn with.
        let dir = match end.end {
            LightEnd::Delta => 0.0,
            _ if own && !c.nee => end.pdf_sampled,
            _ if a >= 1.0 => 0.0,
            _ => {
                let at = || (last.point.p.as_dvec3(), end.wi.as_dvec3());
                let brdf = || shared.towards_end(view, last, end.wi);
                (1.0 - a) * density.direction(k, at, brdf)
            }
        };
        let light = match own && c.nee {
            true => end.pdf_sampled,
            false => shared.light(view, density).unwrap_or(0.0),
        };
        (prefix * dir, prefix * (light * end.area_to_solid_angle))
    }

    /// This generator's density of contribution `c` of `path` for the estimator `nee`: the
    /// one technique's with [`Nee::End`] ([`Self::pdf_path`]), the sum of both with
    /// [`Nee::Every`] ([`Self::pdf_techniques`]).
    pub fn pdf_contribution(
        &self,
        view: &SceneView,
        path: &PathVertices,
        c: &Contribution,
        (max_bounces, nee): (u32, Nee),
    ) -> f64 {
        match nee {
            Nee::End => self.pdf_path(view, path, c.len, c.nee, max_bounces),
            Nee::Every => {
                let (dir, light) = self.pdf_techniques(view, path, c, max_bounces);
                dir + light
            }
        }
    }
}
