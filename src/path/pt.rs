//! `pt`: unidirectional path tracing with next-event estimation at every vertex and BSDF
//! sampling, combined by the power heuristic (Veach & Guibas 1995), Russian roulette from
//! depth 5 (on the throughput with glass's radiance scale undone, as Mitsuba's `eta`). The
//! baseline users compare genpath against.
//!
//! With a guide (`--method ga-pt`, `pg`: `guiding::Guide`), directions out of
//! non-delta vertices come from the guide's per-vertex mixture of BRDF and anchor samplers
//! instead of the BSDF alone, and the power heuristic weighs light sampling against that
//! mixture's density.
//!
//! # Guides as transport sees them
//!
//! Guiding builds on transport (a guide is made of a mixture's generators), so this module
//! knows guides only by two traits and imports nothing of `guiding`:
//!
//! * a [`PathGuide`] is asked at each scattering vertex for a [`GuidedVertex`]: the
//!   probability of next-event estimation there, and the BSDF that the loop evaluates,
//!   weighs and samples there (a [`VertexBsdf`]: for `guiding::Guide`, its
//!   `GuidedBsdf`, whose contract is written there);
//! * a [`PathRecorder`] is told what a training path found at its vertices.
//!
//! [`radiance_guided`] is generic over both, so that each guide and recorder gets a loop of
//! its own, monomorphised, with no virtual call per vertex. [`Unguided`], whose BSDF is the
//! material's own ([`Bsdf`]), is plain path tracing, and [`NoRecorder`] records nothing:
//! [`radiance`] is the loop with those two.

use super::{emitted, EndPoint, RayCounts, SceneView};
use crate::accel::Ray;
use crate::sampling::{uniform, Rng};
use crate::scene::material::bsdf::{self, Frame};
use crate::scene::material::specular;
use crate::scene::material::BrdfSample;
use crate::scene::{
    DirectPick, Emitter, LightSample, LightSampler, Material, MaterialAt, SurfacePoint, RR_START,
};
use glam::Vec3;

/// The BSDF at one path vertex, as the path tracer uses it: its value for next-event
/// estimation, and a direction to continue along with the density multiple importance
/// sampling weighs it with.
pub trait VertexBsdf {
    /// `f(wo, wi)`, the BSDF's own value (no cosine).
    fn eval(&self, wi: Vec3) -> Vec3;
    /// The solid-angle density with which [`Self::sample`] draws unit `wi`.
    fn pdf(&self, wi: Vec3) -> f64;
    /// [`Self::eval`] and [`Self::pdf`] at once, bit for bit theirs (Mitsuba's `eval_pdf`);
    /// a BSDF whose two share work overrides it to do that work once.
    fn eval_pdf(&self, wi: Vec3) -> (Vec3, f64) {
        (self.eval(wi), self.pdf(wi))
    }
    /// A direction drawn with the next uniform numbers of `rng`; `None` where the direction
    /// carries nothing (the path ends).
    fn sample(&self, rng: &mut Rng) -> Option<BrdfSample>;
    /// The sampler densities beyond the BSDF's that one evaluation of [`Self::pdf`] costs
    /// (see [`RayCounts::densities`]).
    fn samplers(&self) -> usize {
        0
    }
    /// Where a guide samples beside the BSDF with a share that can be learned: its density
    /// and the BSDF's own at unit `wi` (what the share is fitted to; `None` elsewhere).
    fn selection_densities(&self, _wi: Vec3) -> Option<(f64, f64)> {
        None
    }
}

/// The BSDF of `material` at a vertex whose shading frame faces `wo` ([`Frame::facing`]):
/// [`bsdf`]'s evaluation, density and sampling, and [`specular`]'s sampling of a delta BSDF.
#[derive(Clone, Copy)]
pub struct Bsdf<'a> {
    pub material: MaterialAt<'a>,
    pub frame: Frame,
    pub wo: Vec3,
    /// The shading normal as stored (`n` or `−n`): a dielectric tells its sides apart by
    /// it.
    pub ns: Vec3,
}

impl VertexBsdf for Bsdf<'_> {
    fn eval(&self, wi: Vec3) -> Vec3 {
        bsdf::eval(self.material, self.frame, self.wo, wi)
    }

    fn pdf(&self, wi: Vec3) -> f64 {
        bsdf::pdf(self.material, self.frame, self.wo, wi)
    }

    fn eval_pdf(&self, wi: Vec3) -> (Vec3, f64) {
        bsdf::eval_pdf(self.material, self.frame, self.wo, wi)
    }

    /// [`bsdf::sample`] from three uniform numbers ([`specular::sample_in`] from the first of
    /// them for a delta BSDF), in the frame's transport mode.
    fn sample(&self, rng: &mut Rng) -> Option<BrdfSample> {
        let u = [
            uniform(rng) as f64,
            uniform(rng) as f64,
            uniform(rng) as f64,
        ];
        if self.material.mirror {
            let (mode, ng) = (self.frame.mode, self.frame.ng);
            specular::sample_in(self.material, self.ns, self.wo, u[0], mode, ng)
        } else {
            bsdf::sample(self.material, self.frame, self.wo, u)
        }
    }
}

/// What a guide says about one vertex.
pub struct GuidedVertex<B> {
    /// The probability of next-event estimation here: its density for multiple importance
    /// sampling is the light sample's times this.
    pub light_share: f64,
    /// What the vertex samples and weighs directions with.
    pub bsdf: B,
}

/// What guides a path tracer's directions (see the module documentation).
pub trait PathGuide {
    type Bsdf<'a>: VertexBsdf
    where
        Self: 'a;
    /// The `k`-th non-delta vertex of a path, at `x`, where the path meets `bsdf` (`last`:
    /// at the path's last bounce, whose direction can only find emission).
    fn vertex<'a>(
        &'a self,
        k: usize,
        x: Vec3,
        bsdf: Bsdf<'a>,
        last: bool,
    ) -> GuidedVertex<Self::Bsdf<'a>>;
    /// Whether a path ends where the direction sampled at its `bounce`-th vertex (1: the
    /// camera ray's hit) is a delta lobe's; never, but for [`NoDeltaFirst`].
    fn ends_at_delta(&self, _bounce: u32) -> bool {
        false
    }
}

/// No guide: next-event estimation at every vertex, and the material's own BSDF.
#[derive(Clone, Copy, Debug, Default)]
pub struct Unguided;

impl PathGuide for Unguided {
    type Bsdf<'a> = Bsdf<'a>;
    fn vertex<'a>(&'a self, _: usize, _: Vec3, bsdf: Bsdf<'a>, _: bool) -> GuidedVertex<Bsdf<'a>> {
        GuidedVertex {
            light_share: 1.0,
            bsdf,
        }
    }
}

/// No guide, and no path on through a delta lobe at the camera ray's hit (a mirror or
/// smooth glass seen directly, a smooth plastic's coat): the paths a light tracer reaches
/// ([`super::lt`]), for comparing the two.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoDeltaFirst;

impl PathGuide for NoDeltaFirst {
    type Bsdf<'a> = Bsdf<'a>;
    fn vertex<'a>(
        &'a self,
        k: usize,
        x: Vec3,
        bsdf: Bsdf<'a>,
        last: bool,
    ) -> GuidedVertex<Bsdf<'a>> {
        Unguided.vertex(k, x, bsdf, last)
    }
    fn ends_at_delta(&self, bounce: u32) -> bool {
        bounce == 1
    }
}

/// What a training path tells the recorder that learns from it, vertex by vertex (at a
/// vertex `x` with normal `n`; `wi` unit).
pub trait PathRecorder {
    /// A light sample was taken at `x`; whether it reached a light (an unoccluded emitter
    /// that the BSDF reflects).
    fn light_try(&mut self, x: Vec3, n: Vec3, reached: bool);
    /// A light sample that reached a light along `wi`: `value` is its MIS-weighted
    /// `L_e |cos| / pdf` (throughput excluded).
    fn light(&mut self, x: Vec3, n: Vec3, wi: Vec3, value: Vec3);
    /// Whether it records [`Sampled::densities`] (which cost a density evaluation each).
    fn records_densities(&self) -> bool {
        false
    }
    /// The direction `sampled` at `x`, the throughput after the sample and the radiance
    /// collected so far.
    fn sampled(&mut self, x: Vec3, n: Vec3, sampled: Sampled, beta: Vec3, before: Vec3);
    /// The last sampled direction found emission at once, which brought the estimate to
    /// `radiance`.
    fn emission_seen(&mut self, radiance: Vec3);
    /// The path ended with the estimate `radiance`.
    fn finish(&mut self, radiance: Vec3);
}

/// A direction sampled at a vertex, as a [`PathRecorder`] is told of it.
pub struct Sampled {
    /// The unit direction.
    pub wi: Vec3,
    /// `|cos| / pdf`.
    pub cos_over_pdf: f32,
    /// `f · |cos| / pdf`, what the throughput was multiplied by.
    pub weight: Vec3,
    /// The guide's and the BSDF's densities at `wi`, where the recorder asks for them
    /// ([`PathRecorder::records_densities`]) and the vertex has them
    /// ([`VertexBsdf::selection_densities`]).
    pub densities: Option<(f64, f64)>,
}

impl Sampled {
    /// The direction `bs` sampled with `bsdf` at a vertex of normal `n`, with its densities
    /// when `densities`.
    fn of(bs: &BrdfSample, n: Vec3, bsdf: &impl VertexBsdf, densities: bool) -> Self {
        Self {
            wi: bs.wi,
            cos_over_pdf: (n.dot(bs.wi).abs() as f64 / bs.pdf) as f32,
            weight: bs.weight,
            densities: densities.then(|| bsdf.selection_densities(bs.wi)).flatten(),
        }
    }
}

/// The recorder of paths that record nothing: there is none (`Option<&mut NoRecorder>` is
/// always `None`).
#[derive(Debug)]
pub enum NoRecorder {}

/// No recorder, for paths that record nothing.
pub const NO_RECORDER: Option<&mut NoRecorder> = None;

impl PathRecorder for NoRecorder {
    fn light_try(&mut self, _: Vec3, _: Vec3, _: bool) {
        match *self {}
    }
    fn light(&mut self, _: Vec3, _: Vec3, _: Vec3, _: Vec3) {
        match *self {}
    }
    fn sampled(&mut self, _: Vec3, _: Vec3, _: Sampled, _: Vec3, _: Vec3) {
        match *self {}
    }
    fn emission_seen(&mut self, _: Vec3) {
        match *self {}
    }
    fn finish(&mut self, _: Vec3) {
        match *self {}
    }
}

fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

/// Solid-angle density, as seen from a point at distance² `dist2`, of the emitter sampling
/// strategy choosing the emitter point `y` with normal cosine `cos_light`.
fn light_pdf_solid_angle(pdf_area: f64, dist2: f32, cos_light: f32) -> f32 {
    (pdf_area * dist2 as f64 / cos_light as f64) as f32
}

/// A point `y` on an emitter, sampled for next-event estimation at `x`, and what joins them.
pub struct LightPoint {
    /// `y`, the unit normal of its emitter there, and the emitter's triangle.
    pub y: EndPoint,
    pub prim: u32,
    /// The unit direction from `x` to `y`, and their squared distance.
    pub wi: Vec3,
    pub dist2: f32,
    /// `|cos|` at `x` (against its facing normal, [`bsdf::cosine`]) and `cos` at `y`
    /// (against `y`'s normal, towards `x`).
    pub cos_x: f32,
    pub cos_light: f32,
    /// The emitters' density of `y` per unit area.
    pub pdf_area: f64,
}

/// Where a light sample is taken: the surface point, the material that scatters there
/// towards the path's `wo`, and its shading frame facing `wo`. Which lights can reach it is
/// the material's to say ([`bsdf::cosine`]): those above the surface, or on either side for
/// a material that transmits.
pub type Receiver<'a> = (&'a SurfacePoint, &'a Material, Frame);

impl LightPoint {
    /// A point on the emitters from the next three uniform numbers of `rng`, seen from `x`;
    /// `None` where the material at `x` cannot scatter light from it (behind a surface that
    /// only reflects), where it faces away from `x` (either way it sends `x` nothing), or
    /// where the scene has no area emitter. Visibility is not tested.
    pub fn sample(view: &SceneView, at: Receiver, rng: &mut Rng) -> Option<Self> {
        let u = [uniform(rng), uniform(rng), uniform(rng)];
        Self::from_uniforms(view, at, u)
    }

    /// [`Self::sample`] from the three uniform numbers `u`.
    pub fn from_uniforms(
        view: &SceneView,
        (x, material, frame): Receiver,
        u: [f32; 3],
    ) -> Option<Self> {
        let scene = view.scene;
        if scene.emitters.prims.is_empty() {
            return None;
        }
        let ls = scene.emitters.sample_seen_from(&scene.mesh, x.p, u);
        Self::seen_from(ls, (x, material, frame))
    }

    /// The emitter point `ls` as seen from `x`; `None` as for [`Self::from_uniforms`].
    fn seen_from(ls: LightSample, (x, material, frame): Receiver) -> Option<Self> {
        let y = EndPoint {
            p: ls.point,
            ng: ls.normal,
        };
        let d = y.p - x.p;
        let dist2 = d.length_squared();
        let wi = d / dist2.sqrt();
        let cos_x = bsdf::cosine(material, frame, wi)?;
        let cos_light = -y.ng.dot(wi);
        (cos_light > 0.0 && dist2 > 0.0).then_some(Self {
            y,
            prim: ls.prim,
            wi,
            dist2,
            cos_x,
            cos_light,
            pdf_area: ls.pdf_area,
        })
    }

    /// A point on emitting primitive `prim` alone (the light tree picked it), from two
    /// uniform numbers; `None` as for [`Self::from_uniforms`].
    pub fn on_prim(
        view: &SceneView,
        (x, material, frame): Receiver,
        prim: u32,
        u: (f32, f32),
    ) -> Option<Self> {
        let scene = view.scene;
        let ls = scene
            .emitters
            .sample_prim_seen_from(&scene.mesh, prim, x.p, u);
        Self::seen_from(ls, (x, material, frame))
    }

    /// The density of `y` in solid angle at `x`.
    pub fn pdf_solid_angle(&self) -> f32 {
        light_pdf_solid_angle(self.pdf_area, self.dist2, self.cos_light)
    }
}

/// One path-traced estimate of the radiance arriving along `ray`, with at most `max_bounces`
/// scattering events.
pub fn radiance(
    view: &SceneView,
    ray: &Ray,
    max_bounces: u32,
    rng: &mut Rng,
    counts: &mut RayCounts,
) -> Vec3 {
    radiance_guided(view, ray, max_bounces, rng, counts, &Unguided, NO_RECORDER)
}

/// A light sample that reached a light: the direction to it, its emission, the BSDF's value
/// and the MIS-weighted `|cos| / pdf`; `delta` for a delta light (which no direction finds).
struct LightHit {
    wi: Vec3,
    le: Vec3,
    f: Vec3,
    scale: f32,
    delta: bool,
}

/// Where a light sample's shadow ray goes.
#[derive(Clone, Copy, Debug)]
enum Target {
    /// To a point (on an area emitter, or a point light's position).
    Point(EndPoint),
    /// Out of the scene (the environment, a directional light).
    Infinity,
}

/// How a [`LightCandidate`]'s density is made: kept apart so that each kind rounds as it
/// always did.
#[derive(Clone, Copy, Debug)]
enum Density {
    /// A point on the area emitters: its solid-angle density at `x`.
    Area(f32),
    /// A direction towards the environment: its solid-angle density.
    Environment(f64),
    /// A delta light: its pick's probability alone.
    Delta,
}

/// A light sample drawn for next-event estimation at `x`, before its shadow ray: Mitsuba's
/// uniform pick of an emitter (`Scene::pick_light`), then a point on the area emitters, a
/// direction towards the environment, or a delta light's own point or direction.
#[derive(Clone, Copy, Debug)]
pub struct LightCandidate {
    /// Unit direction from `x` towards the light, with `|cos|` against `x`'s facing normal
    /// (positive: [`bsdf::cosine`]).
    pub wi: Vec3,
    pub cos_x: f32,
    /// What arrives along `wi`: radiance, or a delta light's intensity / d² or irradiance.
    pub le: Vec3,
    pub delta: bool,
    /// The probability of the emitter's pick.
    pick: f64,
    density: Density,
    target: Target,
}

impl LightCandidate {
    /// A light sample at `x` (see [`Receiver`]) from three uniform numbers: `u[0]` picks
    /// the emitter (rescaled, it then picks the area emitter), the others place the point or
    /// direction. `None` where it cannot reach `x` (behind a surface that only reflects,
    /// facing away, or no emitter).
    pub fn sample(view: &SceneView, at: Receiver, u: [f32; 3]) -> Option<Self> {
        let (x, material, frame) = at;
        let scene = view.scene;
        let (pick, pmf, u0) =
            scene.pick_direct(view.light_sampler, x.p, frame.n, f64::from(u[0]))?;
        let (wi, le, density, target) = match pick {
            DirectPick::Environment => {
                let env = scene.environment.as_ref()?;
                let (wi, le, pdf) = env.sample(u[1], u[2]);
                (wi, le, Density::Environment(pdf), Target::Infinity)
            }
            DirectPick::Delta(i) => {
                let a = scene.delta_lights[i].arrival(x.p)?;
                let target = match a.position {
                    Some(p) => Target::Point(EndPoint { p, ng: Vec3::ZERO }),
                    None => Target::Infinity,
                };
                (a.wi, a.value, Density::Delta, target)
            }
            DirectPick::AreaGroup => {
                let l = LightPoint::from_uniforms(view, at, [u0 as f32, u[1], u[2]])?;
                let le = view.material(l.prim).ke;
                let density = Density::Area(l.pdf_solid_angle());
                (l.wi, le, density, Target::Point(l.y))
            }
            DirectPick::Prim(prim) => {
                let l = LightPoint::on_prim(view, at, prim, (u[1], u[2]))?;
                let le = view.material(l.prim).ke;
                let density = Density::Area(l.pdf_solid_angle());
                (l.wi, le, density, Target::Point(l.y))
            }
        };
        let cos_x = bsdf::cosine(material, frame, wi)?;
        let density_positive = match density {
            Density::Environment(pdf) => pdf > 0.0,
            _ => true,
        };
        (le.max_element() > 0.0 && density_positive).then_some(Self {
            wi,
            cos_x,
            le,
            delta: matches!(density, Density::Delta),
            pick: pmf,
            density,
            target,
        })
    }

    /// The sample's density where next-event estimation runs with probability
    /// `light_share`: in solid angle at `x`, or for a delta light the probability of its
    /// pick.
    pub fn pdf(&self, light_share: f64) -> f32 {
        let share = light_share * self.pick;
        match self.density {
            Density::Area(pdf) => share as f32 * pdf,
            Density::Environment(pdf) => (share * pdf) as f32,
            Density::Delta => share as f32,
        }
    }

    /// Whether nothing blocks the light from `x` (one shadow ray; masks passed at random,
    /// [`SceneView::unblocked_through`]).
    pub fn visible(
        &self,
        view: &SceneView,
        x: &SurfacePoint,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> bool {
        match &self.target {
            Target::Point(y) => view.unoccluded(x, y, rng, counts),
            Target::Infinity => view.escapes(x, self.wi, rng, counts),
        }
    }
}

/// Next-event estimation at `x` (see [`Receiver`]), where it runs with probability
/// `light_share`: a [`LightCandidate`] from three uniform numbers, and what it brings if it
/// reaches `x`, weighed against `bsdf`'s density by the power heuristic (a delta light's
/// weight is 1). With area emitters alone the numbers and the arithmetic are those they
/// always were.
fn next_event<B: VertexBsdf>(
    view: &SceneView,
    at: Receiver,
    bsdf: &B,
    light_share: f64,
    rng: &mut Rng,
    counts: &mut RayCounts,
) -> Option<LightHit> {
    let x = at.0;
    let u = [uniform(rng), uniform(rng), uniform(rng)];
    let light = LightCandidate::sample(view, at, u)?;
    // A delta light's weight needs no density of the BSDF's.
    let (f, pdf_bsdf) = match light.delta {
        true => (bsdf.eval(light.wi), 0.0),
        false => bsdf.eval_pdf(light.wi),
    };
    if !(f.max_element() > 0.0 && light.visible(view, x, rng, counts)) {
        return None;
    }
    let pdf_light = light.pdf(light_share);
    let weight = match light.delta {
        true => 1.0,
        false => power_heuristic(pdf_light, pdf_bsdf as f32),
    };
    Some(LightHit {
        wi: light.wi,
        le: light.le,
        f,
        scale: light.cos_x * weight / pdf_light,
        delta: light.delta,
    })
}

/// The MIS weight of the emission that the direction `bs` sampled at `x` found at `y`, where
/// next-event estimation ran with probability `light_share`; `None` where `y` emits away
/// from `x`.
fn emission_weight(
    view: &SceneView,
    (x, n, y): (&SurfacePoint, Vec3, &SurfacePoint),
    bs: &BrdfSample,
    light_share: f64,
) -> Option<f32> {
    let cos_light = y.ng.dot(-bs.wi);
    if cos_light > 0.0 {
        Some(if bs.delta {
            1.0
        } else {
            let dist2 = (y.p - x.p).length_squared();
            let scene = view.scene;
            let sampler = view.light_sampler;
            let pdf_area = match sampler {
                LightSampler::Uniform => {
                    scene
                        .emitters
                        .pdf_area_seen_from(&scene.mesh, x.p, y.p, y.prim)
                }
                LightSampler::Bvh | LightSampler::Auto => {
                    scene
                        .emitters
                        .pdf_prim_seen_from(&scene.mesh, x.p, y.p, y.prim)
                }
            };
            let pick = scene.pmf_direct(sampler, x.p, n, Emitter::Area(y.prim));
            #[cfg(feature = "testing")]
            let pick = pick
                * if view.fault_light_pick_halved {
                    0.5
                } else {
                    1.0
                };
            let share = light_share * pick;
            let pdf_light = share as f32 * light_pdf_solid_angle(pdf_area, dist2, cos_light);
            power_heuristic(bs.pdf as f32, pdf_light)
        })
    } else {
        None
    }
}

/// The environment's radiance that the direction `bs` sampled at `x` (normal `n`) found by
/// escaping the scene, MIS weighted against next-event estimation (which ran with
/// probability `light_share`).
fn escape_radiance(
    view: &SceneView,
    (x, n): (&SurfacePoint, Vec3),
    bs: &BrdfSample,
    light_share: f64,
) -> Vec3 {
    let Some(env) = &view.scene.environment else {
        return Vec3::ZERO;
    };
    let (radiance, pdf) = env.eval_pdf(bs.wi);
    let weight = if bs.delta {
        1.0
    } else {
        let pick = (view.scene).pmf_direct(view.light_sampler, x.p, n, Emitter::Environment);
        let pdf_light = (light_share * pick * pdf) as f32;
        power_heuristic(bs.pdf as f32, pdf_light)
    };
    radiance * weight
}

/// [`radiance`], with directions drawn from `guide`'s BSDF at every vertex and next-event
/// estimation at its light share (see the module documentation); [`Unguided`] is plain path
/// tracing, with the same random numbers. With a `recorder`, every non-delta vertex records
/// the incident light along the light sample's and the sampled direction, for training a
/// spatial guide.
pub fn radiance_guided<G: PathGuide, R: PathRecorder>(
    view: &SceneView,
    ray: &Ray,
    max_bounces: u32,
    rng: &mut Rng,
    counts: &mut RayCounts,
    guide: &G,
    mut recorder: Option<&mut R>,
) -> Vec3 {
    let Some(mut x) = view.trace_through(ray, rng, counts) else {
        return view.seen_directly(None, ray.dir);
    };
    let mut wo = -ray.dir;
    let mut radiance = view.seen_directly(Some(&x), ray.dir);
    let mut beta = Vec3::ONE;
    // What Russian roulette multiplies `beta` by: the radiance scale of the interfaces
    // crossed so far undone (1 where no glass was crossed).
    let mut unscale = 1.0f32;
    // Non-delta vertices so far: the guide's level.
    let mut k = 0;
    for bounce in 1..=max_bounces {
        let material = view.scattering_material(&x, wo);
        if !material.scatters() {
            break;
        }
        let frame = Frame::facing(&x, wo);
        let n = frame.n;
        let last = bounce == max_bounces;
        // At a diffuse vertex (no glossy lobe: Phong, or a rough conductor, plastic or
        // dielectric) the spatial guide's records leave out the direct light, which
        // next-event estimation samples well there (see `guiding::field`).
        let diffuse = !material.mirror && !material.is_glossy();
        let GuidedVertex { light_share, bsdf } = guide.vertex(
            k,
            x.p,
            Bsdf {
                material,
                frame,
                wo,
                ns: x.ns,
            },
            last,
        );
        // The light sample's and the sampled direction's densities.
        counts.densities += 2 * bsdf.samplers() as u64;

        // Next-event estimation (impossible through a delta BSDF: a mirror, or glass, which
        // blocks shadow rays as in Mitsuba), where it runs.
        if !material.mirror && (light_share >= 1.0 || f64::from(uniform(rng)) < light_share) {
            let hit = next_event(
                view,
                (&x, &material, frame),
                &bsdf,
                light_share,
                rng,
                counts,
            );
            if let Some(h) = &hit {
                radiance += beta * h.f * h.le * h.scale;
                // A delta light, which no direction finds, is nothing for a guide to learn.
                if let Some(r) = recorder.as_deref_mut().filter(|_| !diffuse && !h.delta) {
                    r.light(x.p, n, h.wi, h.le * h.scale);
                }
            }
            if let Some(r) = recorder.as_deref_mut() {
                r.light_try(x.p, n, hit.is_some());
            }
        }

        // BSDF sampling, guided where the guide's BSDF is.
        let Some(bs) = bsdf.sample(rng) else {
            break;
        };
        if bs.delta && guide.ends_at_delta(bounce) {
            break;
        }
        if !material.mirror {
            k += 1;
        }
        beta *= bs.weight;
        let wi = bs.wi;
        if material.interface_eta().is_some() {
            unscale /= specular::radiance_scale(&material, x.ns, wo, wi);
        }
        if let Some(r) = recorder.as_deref_mut().filter(|_| !bs.delta) {
            let sampled = Sampled::of(&bs, n, &bsdf, r.records_densities());
            r.sampled(x.p, n, sampled, beta, radiance);
        }
        let next_ray = view.spawn(&x, wi);
        let Some(y) = view.trace_through(&next_ray, rng, counts) else {
            // The environment's light stays in a diffuse vertex's record (unlike an area
            // emitter's): its light samples, uniform over the sphere, do not sample it well.
            if view.scene.environment.is_some() {
                radiance += beta * escape_radiance(view, (&x, n), &bs, light_share);
            }
            break;
        };
        let y_material = view.material(y.prim);
        if y_material.is_emitter() {
            if let Some(weight) = emission_weight(view, (&x, n, &y), &bs, light_share) {
                radiance += beta * emitted(y_material, &y, -wi) * weight;
                if let Some(r) = recorder.as_deref_mut().filter(|_| diffuse && !bs.delta) {
                    r.emission_seen(radiance);
                }
            }
        }
        if bounce >= RR_START {
            let q = (1.0 - beta.max_element() * unscale).max(0.05);
            if uniform(rng) < q {
                break;
            }
            beta /= 1.0 - q;
        }
        x = y;
        wo = -wi;
    }
    if let Some(r) = recorder {
        r.finish(radiance);
    }
    radiance
}
