//! Weighted sets of path generators (paper eq. 7) and the balance-heuristic estimator
//! (paper eq. 8), with next-event estimation at the path's end or at every vertex ([`Nee`]).

use super::generator::{
    Contribution, GeneratorDensity, LightEnd, Nee, PathDensities, PathGenerator, PathVertices,
    Prefix,
};
use super::{RayCounts, SceneView};
use crate::sampling::{uniform, Rng};
use crate::scene::material::bsdf::Frame;
use crate::scene::{Glossy, SurfacePoint};
use glam::{DVec3, Vec3};
use std::borrow::Cow;
use std::sync::OnceLock;

/// A weighted set of path generators, `pdf(X) = Σ w_g p_g(X)`, `Σ w_g = 1`. Component 0 is
/// the defensive `srt` generator: with weight ≥ `w_min` it keeps every light-carrying path
/// reachable, so the estimator stays unbiased whatever the other components do.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Mixture {
    /// The components, which its densities' constants are prepared from on their first
    /// evaluation: a mixture with other generators is a new one ([`Mixture::new`]).
    pub generators: Vec<PathGenerator>,
    pub weights: Vec<f64>,
    /// Where the estimator does next-event estimation: with [`Nee::Every`] the density of a
    /// contribution is `Σ_g w_g (p_g,dir + p_g,light)`, the balance heuristic over every
    /// (generator, technique) pair.
    pub nee: Nee,
    /// Fault injection for statistical tests: (component, factor) multiplies that
    /// component's density in [`Mixture::pdf_path`] only, making the estimator biased.
    #[serde(skip)]
    pdf_error: Option<(usize, f64)>,
    /// Fault injection for statistical tests: with [`Nee::Every`], [`Mixture::pdf_path`]
    /// leaves the light technique's densities out.
    #[serde(skip)]
    light_density_dropped: bool,
    /// Fault injection for statistical tests: [`Mixture::pdf_path`] evaluates the BSDF
    /// densities in the geometric frame (each vertex's shading normal replaced by its
    /// geometric one, its normal or bump map dropped), while paths are sampled in the
    /// shading frame.
    #[serde(skip)]
    geometric_frame: bool,
    /// Fault injection for statistical tests: [`Mixture::pdf_path`] leaves the probability
    /// of a delta light's pick out of the density of the paths that end at one.
    #[serde(skip)]
    delta_pick_dropped: bool,
    /// Fault injection for statistical tests: [`Mixture::pdf_path`] evaluates the density
    /// of every direction that crossed its surface (through a rough dielectric) at its
    /// mirror image in the surface, as a density that forgot transmission would.
    #[serde(skip)]
    transmission_folded: bool,
    /// Fault injection for statistical tests: [`Mixture::pdf_path`] multiplies the density
    /// by the probability of every diffuse choice a smooth plastic made on the path (which
    /// the choice's weight in the path's value already accounts for: it is counted twice).
    #[serde(skip)]
    plastic_choice_counted: bool,
    /// Each generator's density constants, computed on the first evaluation.
    #[serde(skip)]
    densities: Densities,
}

/// A mixture's [`GeneratorDensity`]s, prepared on its first density evaluation for the scene
/// evaluated in (whose address they keep): the render evaluates them on every path of every
/// pixel, the mixture's generators unchanged from construction on. Not part of the mixture's
/// value: every two compare equal.
#[derive(Clone, Default)]
struct Densities(OnceLock<(usize, Vec<GeneratorDensity>)>);

impl PartialEq for Densities {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for Densities {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self.0.get() {
            Some(_) => "Densities(prepared)",
            None => "Densities(not yet)",
        })
    }
}

/// `path` with each vertex's shading normal replaced by its geometric one, and its normal or
/// bump map's dropped (the fault of [`Mixture::with_geometric_frame_density`]).
fn in_geometric_frame(path: &PathVertices) -> PathVertices {
    let mut flat = path.clone();
    for v in &mut flat.vertices {
        v.point.ns = v.point.ng;
        v.point.np = Vec3::ZERO;
        v.frame = Frame::facing(&v.point, v.wo);
    }
    flat
}

/// `path` with every sampled direction that crossed its vertex's surface (`wo` and `wi` on
/// either side of the shading normal) mirrored in the surface (the fault of
/// [`Mixture::with_transmission_folded_density`]).
fn transmission_folded(path: &PathVertices) -> PathVertices {
    let mut folded = path.clone();
    for v in &mut folded.vertices {
        let n = v.point.ns;
        if !v.delta && n.dot(v.wo) * n.dot(v.wi) < 0.0 {
            v.wi = (v.wi - 2.0 * n.dot(v.wi) * n).normalize();
        }
    }
    folded
}

/// The product of the probabilities of the diffuse choices smooth plastics made at the
/// scattering vertices of contribution `c` (the fault of
/// [`Mixture::with_plastic_choice_in_density`]).
fn plastic_choices(view: &SceneView, path: &PathVertices, c: &Contribution) -> f64 {
    let vertices = &path.vertices[..c.len.min(path.vertices.len())];
    vertices
        .iter()
        .filter(|v| !v.delta)
        .map(|v| match &view.material(v.point.prim).glossy {
            Glossy::Plastic(p) => {
                1.0 - p.specular_probability(f64::from(v.point.ns.dot(v.wo).abs()))
            }
            _ => 1.0,
        })
        .product()
}

/// Reusable buffers of one worker, so that sampling allocates nothing per path.
#[derive(Default)]
pub struct MixtureScratch {
    path: PathVertices,
    contributions: Vec<Contribution>,
    /// Each generator's density of the path's first vertices, between its contributions.
    prefixes: Vec<Prefix>,
    /// What the generators' densities share on the path.
    shared: PathDensities,
}

impl Mixture {
    /// A mixture of the given generators with the default estimator ([`Nee::default`]);
    /// `weights` are normalised.
    pub fn new(generators: Vec<PathGenerator>, weights: Vec<f64>) -> Self {
        let total: f64 = weights.iter().sum();
        Self {
            generators,
            weights: weights.iter().map(|w| w / total).collect(),
            nee: Nee::default(),
            pdf_error: None,
            light_density_dropped: false,
            geometric_frame: false,
            delta_pick_dropped: false,
            transmission_folded: false,
            plastic_choice_counted: false,
            densities: Densities::default(),
        }
    }

    /// This mixture with the estimator `nee`.
    pub fn with_nee(mut self, nee: Nee) -> Self {
        self.nee = nee;
        self
    }

    /// This mixture with component `index`'s density deliberately scaled by `factor` when
    /// evaluated (not when sampled): a wrong input that unbiasedness tests must reject.
    #[cfg(any(test, feature = "testing"))]
    pub fn with_pdf_error(mut self, index: usize, factor: f64) -> Self {
        self.pdf_error = Some((index, factor));
        self
    }

    /// This mixture (with [`Nee::Every`]) with the light technique's densities left out of
    /// every contribution's density when evaluated: a wrong input that unbiasedness tests
    /// must reject.
    #[cfg(any(test, feature = "testing"))]
    pub fn with_light_density_dropped(mut self) -> Self {
        self.light_density_dropped = true;
        self
    }

    /// This mixture with its densities evaluated in the geometric frame where paths were
    /// sampled in the shading frame (a normal or bump map's included): a wrong input that
    /// unbiasedness tests on smooth-shaded or normal-mapped scenes must reject.
    #[cfg(any(test, feature = "testing"))]
    pub fn with_geometric_frame_density(mut self) -> Self {
        self.geometric_frame = true;
        self
    }

    /// This mixture with the probability of a delta light's pick left out of the density of
    /// every path that ends at one (as if each delta light were the only emitter): a wrong
    /// input that unbiasedness tests on scenes with several emitters must reject.
    #[cfg(any(test, feature = "testing"))]
    pub fn with_delta_pick_dropped(mut self) -> Self {
        self.delta_pick_dropped = true;
        self
    }

    /// This mixture with the density of every direction that went through a rough
    /// dielectric evaluated at its mirror image above the surface (a reflection's): a wrong
    /// input that unbiasedness tests on scenes with rough glass must reject.
    #[cfg(any(test, feature = "testing"))]
    pub fn with_transmission_folded_density(mut self) -> Self {
        self.transmission_folded = true;
        self
    }

    /// This mixture with the probability of every smooth plastic's diffuse choice on a path
    /// in the path's density: a wrong input that unbiasedness tests on scenes with smooth
    /// plastics must reject.
    #[cfg(any(test, feature = "testing"))]
    pub fn with_plastic_choice_in_density(mut self) -> Self {
        self.plastic_choice_counted = true;
        self
    }

    /// One normalised mixture from several, each scaled by its weight (for pixels between
    /// GA pixels): the union of their components. Still one mixture, so still unbiased.
    pub fn combine(parts: &[(f64, &Mixture)]) -> Self {
        let total: f64 = parts.iter().map(|(w, _)| w).sum();
        let parts: Vec<(f64, &Mixture)> = parts.iter().map(|&(w, m)| (w / total, m)).collect();
        Self::union(&parts)
    }

    /// The union of several mixtures, mixture `m` scaled by `w`, with the weights as given
    /// (the caller normalises them), and the first one's estimator. A generator that occurs
    /// in several parts (the defensive `srt` one, a shared neighbour's) becomes one component
    /// with the summed weight, so its density is evaluated once per path.
    pub fn union(parts: &[(f64, &Mixture)]) -> Self {
        let mut generators: Vec<PathGenerator> = Vec::new();
        let mut weights: Vec<f64> = Vec::new();
        for (w, m) in parts {
            for (g, wg) in m.generators.iter().zip(&m.weights) {
                match generators.iter().position(|h| h == g) {
                    Some(i) => weights[i] += w * wg,
                    None => {
                        generators.push(g.clone());
                        weights.push(w * wg);
                    }
                }
            }
        }
        Self {
            generators,
            weights,
            nee: parts.first().map_or_else(Nee::default, |(_, m)| m.nee),
            pdf_error: None,
            light_density_dropped: parts.iter().any(|(_, m)| m.light_density_dropped),
            geometric_frame: parts.iter().any(|(_, m)| m.geometric_frame),
            delta_pick_dropped: parts.iter().any(|(_, m)| m.delta_pick_dropped),
            transmission_folded: parts.iter().any(|(_, m)| m.transmission_folded),
            plastic_choice_counted: parts.iter().any(|(_, m)| m.plastic_choice_counted),
            densities: Densities::default(),
        }
    }

    /// Each generator's [`GeneratorDensity`] for `view`'s scene: prepared once, on the first
    /// call, and for another scene than that one's (which a mixture's light regions do not
    /// name) computed anew.
    fn densities(&self, view: &SceneView) -> Cow<'_, [GeneratorDensity]> {
        let scene = std::ptr::from_ref(view.scene) as usize;
        let prepare = || {
            let generators = self.generators.iter();
            generators.map(|g| GeneratorDensity::new(g, view)).collect()
        };
        match self.densities.0.get_or_init(|| (scene, prepare())) {
            (prepared, densities) if *prepared == scene => Cow::Borrowed(densities),
            _ => Cow::Owned(prepare()),
        }
    }

    /// Mixture density of a contribution (eq. 7; with [`Nee::Every`], over every
    /// generator's two techniques).
    pub fn pdf_path(
        &self,
        view: &SceneView,
        path: &PathVertices,
        c: &Contribution,
        max_bounces: u32,
    ) -> f64 {
        let mut shared = PathDensities::default();
        shared.start_path(path);
        self.pdf_path_after(view, (path, None), c, max_bounces, (None, &mut shared))
    }

    /// [`Self::pdf_path`], continuing each generator's density of the path's first vertices
    /// from an earlier contribution of the same path (`prefixes`, one per generator, default
    /// for a new path; [`PathGenerator::pdf_techniques_after`]); without them, from the
    /// path's start. `shared` holds what every generator's density shares on the path
    /// ([`PathDensities`], started on it). With [`Nee::Every`] the component that sampled
    /// `path` (`sampled_by`, if known) takes the densities its walk drew with as stored
    /// instead of evaluating them again: the same values, bit for bit.
    fn pdf_path_after(
        &self,
        view: &SceneView,
        (path, sampled_by): (&PathVertices, Option<usize>),
        c: &Contribution,
        max_bounces: u32,
        (mut prefixes, shared): (Option<&mut [Prefix]>, &mut PathDensities),
    ) -> f64 {
        // The faults that evaluate another path than the one sampled evaluate it all (each
        // contribution's the same other path, whose densities `shared` then holds).
        let sampled_by = sampled_by.filter(|_| !self.geometric_frame && !self.transmission_folded);
        let flat;
        let folded;
        let path = match self.geometric_frame {
            true => {
                flat = in_geometric_frame(path);
                &flat
            }
            false => path,
        };
        let path = match self.transmission_folded {
            true => {
                folded = transmission_folded(path);
                &folded
            }
            false => path,
        };
        shared.start_contribution(view, c.light_end(path));
        let densities = self.densities(view);
        let mut pdf = 0.0;
        let components = self.generators.iter().zip(&self.weights).zip(&*densities);
        for (i, ((g, &w), density)) in components.enumerate() {
            if w > 0.0 {
                let mut fresh = Prefix::default();
                let prefix = match prefixes.as_deref_mut() {
                    Some(prefixes) => &mut prefixes[i],
                    None => &mut fresh,
                };
                let scale = match self.pdf_error {
                    Some((index, factor)) if index == i => factor,
                    _ => 1.0,
                };
                let p = match self.nee {
                    Nee::Every => {
                        let own = sampled_by == Some(i);
                        let (dir, light) = g.pdf_techniques_after(
                            density,
                            view,
                            (path, own),
                            c,
                            max_bounces,
                            (prefix, shared),
                        );
                        match self.light_density_dropped {
                            true => dir,
                            false => dir + light,
                        }
                    }
                    Nee::End => {
                        let len = (c.len, c.nee, max_bounces);
                        g.pdf_path_with(density, view, path, len, shared)
                    }
                };
                pdf += w * scale * p;
            }
        }
        if self.delta_pick_dropped && c.end(path) == Some(LightEnd::Delta) {
            pdf /= view.scene.light_pmf();
        }
        if self.plastic_choice_counted {
            pdf *= plastic_choices(view, path, c);
        }
        match &view.scene.environment {
            Some(env) if c.escaped => pdf * env.escape_pdf_scale(),
            _ => pdf,
        }
    }

    /// Picks a component by its weight, `u` uniform in [0, 1).
    pub fn choose(&self, u: f64) -> usize {
        let mut acc = 0.0;
        for (i, w) in self.weights.iter().enumerate() {
            acc += w;
            if u < acc {
                return i;
            }
        }
        self.weights.len() - 1
    }

    /// One sample of eq. 8 for the radiance arriving from `x1` (the first hit of a camera
    /// ray from `camera`), emission seen directly at `x1` excluded.
    #[allow(clippy::too_many_arguments)]
    pub fn estimate(
        &self,
        view: &SceneView,
        camera: Vec3,
        x1: SurfacePoint,
        max_bounces: u32,
        rng: &mut Rng,
        counts: &mut RayCounts,
        scratch: &mut MixtureScratch,
    ) -> DVec3 {
        let g = self.choose(uniform(rng) as f64);
        scratch.contributions.clear();
        self.generators[g].sample_path(
            view,
            camera,
            x1,
            (max_bounces, self.nee),
            rng,
            counts,
            &mut scratch.path,
            &mut scratch.contributions,
        );
        let mut sum = DVec3::ZERO;
        scratch.prefixes.clear();
        scratch
            .prefixes
            .resize(self.generators.len(), Prefix::default());
        let components = self.weights.iter().filter(|&&w| w > 0.0).count() as u64;
        // With a light point at every vertex, each density has one sampler more: the
        // other technique's at the last vertex.
        let extra = u64::from(self.nee == Nee::Every);
        scratch.shared.start_path(&scratch.path);
        for c in &scratch.contributions {
            counts.densities += components * (c.len as u64 + extra);
            let pdf = self.pdf_path_after(
                view,
                (&scratch.path, Some(g)),
                c,
                max_bounces,
                (Some(&mut scratch.prefixes), &mut scratch.shared),
            );
            if pdf > 0.0 {
                sum += c.f / pdf;
            }
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::path::generator::PathGenerator;
    use crate::sampling::light_point::LightPointSampler;

    fn generator(absorption: f64) -> PathGenerator {
        let light = LightPointSampler::uniform(0);
        PathGenerator::srt(3, absorption, light)
    }

    #[test]
    fn combine_is_a_normalised_union() {
        let a = Mixture::new(vec![generator(0.1), generator(0.2)], vec![1.0, 3.0]);
        let b = Mixture::new(vec![generator(0.3)], vec![2.0]);
        let c = Mixture::combine(&[(3.0, &a), (1.0, &b)]);
        assert_eq!(c.generators.len(), 3);
        let expected = [0.75 * 0.25, 0.75 * 0.75, 0.25];
        for (w, e) in c.weights.iter().zip(expected) {
            assert!((w - e).abs() < 1e-15, "{:?}", c.weights);
        }
        assert!((c.weights.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert_eq!(c.generators[2], b.generators[0]);
    }

    #[test]
    fn union_merges_shared_generators() {
        let srt = generator(0.5);
        let a = Mixture::new(vec![srt.clone(), generator(0.1)], vec![0.2, 0.8]);
        let b = Mixture::new(vec![srt.clone(), generator(0.3)], vec![0.5, 0.5]);
        let u = Mixture::union(&[(0.25, &a), (0.75, &b)]);
        assert_eq!(u.generators.len(), 3);
        assert_eq!(u.generators[0], srt);
        let expected = [0.25 * 0.2 + 0.75 * 0.5, 0.25 * 0.8, 0.75 * 0.5];
        for (w, e) in u.weights.iter().zip(expected) {
            assert!((w - e).abs() < 1e-15, "{:?}", u.weights);
        }
        // Weights are taken as given: unnormalised parts give an unnormalised union.
        let v = Mixture::union(&[(0.5, &a), (0.75, &b)]);
        assert!((v.weights.iter().sum::<f64>() - 1.25).abs() < 1e-15);
    }
}
