//! Light transport: the scene as the estimators see it, path generators and mixtures, and the
//! path tracer (the methods built on them are in `integrators`).

pub mod generator;
pub mod lt;
pub mod mixture;
pub mod mixture_file;
pub mod pt;
pub mod walk;

use crate::accel::{Accel, Coherence, Hit, Ray, PACKET_SIZE};
use crate::sampling::{uniform, Rng};
use crate::scene::{normals, LightSampler, Material, MaterialAt, Opacity, Scene, SurfacePoint};
use glam::DVec3;
use glam::{Vec2, Vec3};
use mixture::{Mixture, MixtureScratch};
use pt::{PathGuide, NO_RECORDER};

/// Where a shadow ray ends: a point and the unit normal of its surface there (zero for a
/// point light), all that [`SceneView::shadow_ray`] reads of it. Light samples carry this
/// rather than a whole [`SurfacePoint`], which they would copy for nothing.
#[derive(Clone, Copy, Debug)]
pub struct EndPoint {
    pub p: Vec3,
    pub ng: Vec3,
}

/// A scene together with the ray queries over it.
#[derive(Clone, Copy)]
pub struct SceneView<'a> {
    pub scene: &'a Scene,
    pub accel: &'a dyn Accel,
    /// Ray origin offset along the normal, relative to the scene's size.
    pub epsilon: f32,
    /// Whether some material has a `mask` (an [`Opacity`]): rays then pass through masked
    /// surfaces at random ([`SceneView::trace_through`], [`SceneView::unblocked_through`]);
    /// without, those are [`SceneView::trace`] and [`SceneView::unblocked`].
    masks: bool,
    /// Whether some material chooses its lobe where a ray meets it (a smooth plastic):
    /// [`SceneView::trace_through`] then draws the choice's uniform number at such a hit.
    choices: bool,
    /// How next-event estimation picks its light (`pt`, `pg`, `ga-pt`): never
    /// [`LightSampler::Auto`], which the view resolves for its scene.
    pub light_sampler: LightSampler,
    /// Fault injection (feature `testing`): shadow rays stop at every masked surface, as
    /// if it were opaque, while the directions that find light pass through it.
    #[cfg(feature = "testing")]
    pub fault_masks_block_shadows: bool,
    /// Fault injection (feature `testing`): the light sampler's probability of an emitter
    /// that a sampled direction found is taken as half of what it is, in that direction's
    /// multiple importance weight only.
    #[cfg(feature = "testing")]
    pub fault_light_pick_halved: bool,
}

/// The most masked surfaces one ray passes through; the next one stops it (a bound on the
/// work of a ray, far beyond any scene's stack of masks).
pub const MAX_PASSES: u32 = 256;

/// Cost of one sampler density, in rays (with their shading), as timed in `ga-pt` against
/// `pt` renders (reports/README.md, "Measurements formerly in code comments (2026-12-07)").
pub const DENSITY_COST: f64 = 0.075;

/// Counts of ray queries, for statistics.
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct RayCounts {
    pub closest: u64,
    pub shadow: u64,
    /// Sampler densities evaluated per path vertex (a mixture's generators at each vertex of
    /// each contribution; a guide's anchor cones): the shading work beyond the rays.
    pub densities: u64,
}

impl RayCounts {
    pub fn add(&mut self, other: RayCounts) {
        self.closest += other.closest;
        self.shadow += other.shadow;
        self.densities += other.densities;
    }

    /// Work in ray equivalents: every ray, and [`DENSITY_COST`] per density.
    pub fn cost(&self) -> f64 {
        self.total() as f64 + DENSITY_COST * self.densities as f64
    }
    pub fn total(&self) -> u64 {
        self.closest + self.shadow
    }
}

impl<'a> SceneView<'a> {
    pub fn new(scene: &'a Scene, accel: &'a dyn Accel) -> Self {
        Self {
            scene,
            accel,
            epsilon: 1e-5 * scene.extent.max(f32::MIN_POSITIVE),
            masks: scene.materials.iter().any(|m| m.opacity().is_some()),
            choices: scene.materials.iter().any(Material::chooses_lobe),
            light_sampler: LightSampler::default().resolve(scene),
            #[cfg(feature = "testing")]
            fault_masks_block_shadows: false,
            #[cfg(feature = "testing")]
            fault_light_pick_halved: false,
        }
    }

    /// This view with next-event estimation picking lights by `sampler`.
    pub fn with_light_sampler(mut self, sampler: LightSampler) -> Self {
        self.light_sampler = sampler.resolve(self.scene);
        self
    }

    /// Whether some surface of the scene has a `mask`.
    pub fn has_masks(&self) -> bool {
        self.masks
    }

    /// Whether a ray's hit may draw random numbers ([`SceneView::trace_through`]: masks
    /// passed, smooth plastics' lobes chosen), so that it needs its path's random stream.
    pub fn draws_at_hits(&self) -> bool {
        self.masks || self.choices
    }

    pub fn material(&self, prim: u32) -> &'a Material {
        self.scene.material(prim)
    }

    /// The material that scatters at `x` towards `wo`, its textures evaluated at `x`'s
    /// texture coordinates ([`Material::at`]): [`crate::scene::BLACK`] where a one-sided
    /// material is seen from behind its shading normal (as Mitsuba's BSDFs tell their sides
    /// apart in the shading frame; with a normal or bump map, the perturbed one that the
    /// nested BSDF sees from `wo`, [`crate::scene::normals::resolve`]).
    #[inline]
    pub fn scattering_material(&self, x: &SurfacePoint, wo: Vec3) -> MaterialAt<'a> {
        let m = self.scene.material(x.prim);
        let front = if x.np == Vec3::ZERO {
            m.two_sided || x.ns.dot(wo) > 0.0
        } else if m.two_sided && !x.np_twosided_outside {
            // Two-sided inside the map: the nested BSDF turns to `wo` whatever the side.
            true
        } else {
            let (n, _) = normals::resolve(x.ns, x.np, x.np_twosided_outside, wo);
            n.dot(wo) > 0.0
        };
        if front {
            match self.choices {
                true => m.scattering_at(x.uv, x.ns.dot(wo).abs(), x.lobe_u),
                false => m.at(x.uv),
            }
        } else {
            MaterialAt::from(&crate::scene::BLACK)
        }
    }

    fn surface_point(&self, ray: &Ray, hit: &Hit) -> SurfacePoint {
        let ns = self.scene.shading_normal(hit.prim, (hit.u, hit.v), hit.ng);
        let material = self.material(hit.prim);
        let perturbation = material.perturbation();
        let ts = match material.glossy.is_anisotropic() || perturbation.is_some() {
            true => self.scene.shading_tangent(hit.prim, hit.ng, ns),
            false => Vec3::ZERO,
        };
        let uv = match material.is_textured() {
            true => self.scene.uv(hit.prim, (hit.u, hit.v)),
            false => Vec2::ZERO,
        };
        let (np, np_twosided_outside) = match perturbation {
            Some(p) => (
                self.scene
                    .perturbed_normal(p, hit.prim, (hit.ng, ns, ts), uv),
                p.twosided_outside,
            ),
            None => (Vec3::ZERO, false),
        };
        SurfacePoint {
            p: ray.origin + ray.dir * hit.t,
            ng: hit.ng,
            ns,
            ts,
            uv,
            np,
            np_twosided_outside,
            lobe_u: 0.0,
            prim: hit.prim,
        }
    }

    /// Closest surface along `ray`, masked or not (every surface opaque).
    pub fn trace(&self, ray: &Ray, counts: &mut RayCounts) -> Option<SurfacePoint> {
        counts.closest += 1;
        self.accel
            .intersect(ray)
            .map(|hit| self.surface_point(ray, &hit))
    }

    /// The surface along `ray` where it scatters: the closest one, except that the ray
    /// passes straight through a masked surface (Mitsuba's `mask`) with probability
    /// `1 − opacity` there, one uniform number per masked surface met (none in a scene
    /// without masks: then it is [`SceneView::trace`]). A pass-through has weight 1 and is
    /// no path vertex, the same for every method and every generator's density (as glass's
    /// choice between reflection and refraction is): it is no bounce, and the surface that
    /// stops the ray scatters with the nested BSDF (weight `opacity / opacity`). One closest-
    /// hit query per surface met. Where the ray stops on a smooth plastic, one more uniform
    /// number chooses the plastic's lobe there ([`SurfacePoint::lobe_u`]).
    pub fn trace_through(
        &self,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Option<SurfacePoint> {
        let mut x = match self.masks {
            true => self.trace_masked(ray, rng, counts),
            false => self.trace(ray, counts),
        };
        if let Some(x) = x
            .as_mut()
            .filter(|x| self.choices && self.material(x.prim).chooses_lobe())
        {
            x.lobe_u = uniform(rng);
        }
        x
    }

    /// [`SceneView::trace_through`]'s passes through masks.
    fn trace_masked(
        &self,
        ray: &Ray,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> Option<SurfacePoint> {
        let mut ray = *ray;
        for _ in 0..MAX_PASSES {
            counts.closest += 1;
            let hit = self.accel.intersect(&ray)?;
            if !self.passes(&hit, rng) {
                return Some(self.surface_point(&ray, &hit));
            }
            ray = beyond(&ray, &hit, self.epsilon)?;
        }
        self.trace(&ray, counts)
    }

    /// Whether a shadow ray is free: [`SceneView::unblocked`], except that a masked surface
    /// lets it through with probability `1 − opacity` (a stochastic occluder: its
    /// expectation is the segment's transmittance, the product of the masks' `1 − opacity`).
    /// One closest-hit query per surface met in a scene with masks.
    pub fn unblocked_through(&self, ray: &Ray, rng: &mut Rng, counts: &mut RayCounts) -> bool {
        if !self.masks {
            return self.unblocked(ray, counts);
        }
        #[cfg(feature = "testing")]
        if self.fault_masks_block_shadows {
            return self.unblocked(ray, counts);
        }
        let mut ray = *ray;
        for _ in 0..MAX_PASSES {
            counts.shadow += 1;
            let Some(hit) = self.accel.intersect(&ray) else {
                return true;
            };
            if !self.passes(&hit, rng) {
                return false;
            }
            let Some(next) = beyond(&ray, &hit, self.epsilon) else {
                return true;
            };
            ray = next;
        }
        false
    }

    /// Whether a ray that meets `hit` passes through it: with probability `1 − opacity` at a
    /// masked surface (one uniform number where the opacity is strictly between 0 and 1),
    /// never elsewhere.
    fn passes(&self, hit: &Hit, rng: &mut Rng) -> bool {
        let Some(opacity) = self.material(hit.prim).opacity() else {
            return false;
        };
        let a = match opacity {
            Opacity::Constant(a) => *a,
            Opacity::Texture(_) => opacity.at(self.scene.uv(hit.prim, (hit.u, hit.v))),
        };
        if a >= 1.0 {
            false
        } else {
            a <= 0.0 || uniform(rng) >= a
        }
    }

    /// A ray leaving `x` in unit direction `dir`, its origin pushed off the surface on the
    /// side it leaves through (no self-intersection).
    pub fn spawn(&self, x: &SurfacePoint, dir: Vec3) -> Ray {
        let offset = x.ng * self.epsilon.copysign(x.ng.dot(dir));
        Ray::new(x.p + offset, dir, 0.0, f32::INFINITY)
    }

    /// Whether the segment from surface point `x` to the light sample's end `y` is free of
    /// occluders (masks passed at random: [`SceneView::unblocked_through`]).
    pub fn unoccluded(
        &self,
        x: &SurfacePoint,
        y: &EndPoint,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> bool {
        self.unblocked_through(&self.shadow_ray(x, y), rng, counts)
    }

    /// The segment from surface point `x` to the light sample's end `y` as a shadow ray
    /// (`t ∈ [0, 1]`), both ends pushed off their surfaces towards each other.
    pub fn shadow_ray(&self, x: &SurfacePoint, y: &EndPoint) -> Ray {
        let d = y.p - x.p;
        let from = x.p + x.ng * self.epsilon.copysign(x.ng.dot(d));
        let to = y.p + y.ng * self.epsilon.copysign(-y.ng.dot(d));
        Ray::new(from, to - from, 0.0, 1.0)
    }

    /// Whether nothing blocks the ray from `x` along unit `dir` out of the scene (a shadow
    /// ray towards the environment; masks passed at random).
    pub fn escapes(
        &self,
        x: &SurfacePoint,
        dir: Vec3,
        rng: &mut Rng,
        counts: &mut RayCounts,
    ) -> bool {
        self.unblocked_through(&self.spawn(x, dir), rng, counts)
    }

    /// What a camera ray along `dir` sees directly: the emission of its first hit `x1`
    /// (towards the camera) or, where it escapes, the environment's radiance; nothing with
    /// `hide_emitters`.
    pub fn seen_directly(&self, x1: Option<&SurfacePoint>, dir: Vec3) -> Vec3 {
        if self.scene.hide_emitters {
            return Vec3::ZERO;
        }
        match x1 {
            Some(x1) => emitted(self.material(x1.prim), x1, -dir),
            None => self.escaped(dir),
        }
    }

    /// The radiance a ray that escapes the scene along unit `dir` gathers: the
    /// environment's, or none.
    pub fn escaped(&self, dir: Vec3) -> Vec3 {
        self.scene
            .environment
            .as_ref()
            .map_or(Vec3::ZERO, |e| e.eval(dir))
    }

    /// Whether nothing blocks a shadow ray (from [`SceneView::shadow_ray`]).
    pub fn unblocked(&self, ray: &Ray, counts: &mut RayCounts) -> bool {
        counts.shadow += 1;
        !self.accel.occluded(ray)
    }

    /// Closest surfaces along up to [`PACKET_SIZE`] rays as one packet query: what
    /// [`SceneView::trace`] gives for each ray, counted the same way (no query for none).
    pub fn trace_packet(
        &self,
        rays: &[Ray],
        points: &mut [Option<SurfacePoint>],
        coherence: Coherence,
        counts: &mut RayCounts,
    ) {
        assert_eq!(rays.len(), points.len());
        if rays.is_empty() {
            return;
        }
        counts.closest += rays.len() as u64;
        let mut hits = [None; PACKET_SIZE];
        let hits = &mut hits[..rays.len()];
        self.accel.intersect_packet(rays, hits, coherence);
        for ((point, ray), hit) in points.iter_mut().zip(rays).zip(hits.iter()) {
            *point = hit.map(|hit| self.surface_point(ray, &hit));
        }
    }

    /// [`SceneView::unblocked`] for up to [`PACKET_SIZE`] shadow rays as one packet query
    /// (no query for none).
    pub fn unblocked_packet(&self, rays: &[Ray], free: &mut [bool], counts: &mut RayCounts) {
        if rays.is_empty() {
            return;
        }
        counts.shadow += rays.len() as u64;
        self.accel
            .occluded_packet(rays, free, Coherence::Incoherent);
        free.iter_mut().for_each(|f| *f = !*f);
    }
}

/// The rest of `ray` beyond its hit `hit` (a masked surface it passes through): from the
/// hit, pushed off the surface on the far side, in the same direction to the ray's end;
/// `None` where the hit lies at that end.
fn beyond(ray: &Ray, hit: &Hit, epsilon: f32) -> Option<Ray> {
    let p = ray.origin + ray.dir * hit.t;
    let from = p + hit.ng * epsilon.copysign(hit.ng.dot(ray.dir));
    if !ray.tmax.is_finite() {
        return Some(Ray::new(from, ray.dir, 0.0, f32::INFINITY));
    }
    // The same direction, to the same end.
    let to = ray.origin + ray.dir * ray.tmax;
    let tmax = (to - from).dot(ray.dir) / ray.dir.length_squared();
    (tmax > 0.0).then(|| Ray::new(from, ray.dir, 0.0, tmax))
}

/// Radiance leaving an emitter at `x` towards direction `w` (one-sided: normal side only).
pub fn emitted(material: &Material, x: &SurfacePoint, w: Vec3) -> Vec3 {
    if x.ng.dot(w) > 0.0 {
        material.ke
    } else {
        Vec3::ZERO
    }
}

/// One sample of the radiance along camera ray `ray`: path tracing, guided by the guide when
/// given, or with a mixture the emission seen at the first hit plus the mixture's estimator
/// (eq. 8) from there.
#[allow(clippy::too_many_arguments)]
pub fn camera_sample<G: PathGuide>(
    view: &SceneView,
    ray: &Ray,
    max_bounces: u32,
    (mixture, guide): (Option<&Mixture>, Option<&G>),
    rng: &mut Rng,
    counts: &mut RayCounts,
    scratch: &mut MixtureScratch,
) -> DVec3 {
    let Some(mixture) = mixture else {
        let radiance = match guide {
            Some(g) => pt::radiance_guided(view, ray, max_bounces, rng, counts, g, NO_RECORDER),
            None => pt::radiance(view, ray, max_bounces, rng, counts),
        };
        return radiance.as_dvec3();
    };
    let hit = view.trace_through(ray, rng, counts);
    mixture_sample(view, (ray, hit), max_bounces, mixture, rng, counts, scratch)
}

/// The mixture branch of [`camera_sample`], for camera ray `ray` already traced to `hit`:
/// what is seen directly there plus `mixture`'s estimator (eq. 8) from the hit.
pub fn mixture_sample(
    view: &SceneView,
    (ray, hit): (&Ray, Option<SurfacePoint>),
    max_bounces: u32,
    mixture: &Mixture,
    rng: &mut Rng,
    counts: &mut RayCounts,
    scratch: &mut MixtureScratch,
) -> DVec3 {
    match hit {
        None => view.seen_directly(None, ray.dir).as_dvec3(),
        Some(x1) => {
            let direct = view.seen_directly(Some(&x1), ray.dir).as_dvec3();
            direct + mixture.estimate(view, ray.origin, x1, max_bounces, rng, counts, scratch)
        }
    }
}
