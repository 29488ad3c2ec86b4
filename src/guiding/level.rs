//! The samplers of one vertex index of a [`Guide`](super::Guide) ([`Level`]): the weighted
//! anchor cones and patches of a mixture's generators at that index. Apart from the guide,
//! so that the guide's vertices (`vertex.rs`) read a level without importing the guide
//! that makes them.

use crate::sampling::anchor::{AnchorSampler, ConeTest};
use crate::sampling::patch::{PatchSampler, PatchShape};
use glam::{DVec3, Vec3};

/// One weighted anchor cone of a level, with what its density and its sampling need
/// precomputed: the guide evaluates every cone of a level twice per vertex (light sample and
/// guided sample).
#[derive(Clone, Copy, Debug)]
struct GuideAnchor {
    weight: f64,
    sampler: AnchorSampler,
    /// [`AnchorSampler::extents`], computed once.
    extents: (f64, f64),
    /// `weight · p1`, `weight · p2` and the sampler's cone test.
    inside: f64,
    outside: f64,
    test: ConeTest,
}

impl GuideAnchor {
    fn new(weight: f64, sampler: AnchorSampler) -> Self {
        // One sin_cos for all three: the guide makes these per pixel.
        let extents = sampler.extents();
        let (p1, p2) = sampler.densities_with_extents(extents);
        Self {
            weight,
            sampler,
            extents,
            inside: weight * p1,
            outside: weight * p2,
            // tan²(θc/2) = h_c / g_c, as `AnchorSampler::tan2_half`.
            test: ConeTest::new(extents.0 / extents.1),
        }
    }

    /// `weight · pdf(wi)` from `x`: [`AnchorSampler::pdf`] without recomputing constants.
    #[inline]
    fn weighted_pdf(&self, x: DVec3, wi: DVec3) -> f64 {
        if self.test.inside(self.sampler.anchor - x, wi) {
            self.inside
        } else {
            self.outside
        }
    }
}

/// One weighted patch of a level, with its constants.
#[derive(Clone, Copy, Debug)]
struct GuidePatch {
    weight: f64,
    shape: PatchShape,
}

/// The samplers of one vertex index.
#[derive(Clone, Debug, Default)]
pub(super) struct Level {
    /// Summed weight of BRDF sampling.
    pub(super) brdf: f64,
    /// Anchor cones and their weights.
    anchors: Vec<GuideAnchor>,
    /// Patches and their weights.
    patches: Vec<GuidePatch>,
}

impl Level {
    pub(super) fn set(&mut self, cones: &[(f64, AnchorSampler)], patches: &[(f64, PatchSampler)]) {
        self.anchors.clear();
        self.anchors
            .extend(cones.iter().map(|&(w, a)| GuideAnchor::new(w, a)));
        self.patches.clear();
        self.patches
            .extend(patches.iter().map(|(weight, sampler)| GuidePatch {
                weight: *weight,
                shape: PatchShape::new(sampler),
            }));
    }

    /// Whether the level samples anything but the BRDF.
    pub(super) fn guides(&self) -> bool {
        !(self.anchors.is_empty() && self.patches.is_empty())
    }

    /// Cones and patches: the densities one evaluation of [`Self::density`] costs.
    pub(super) fn samplers(&self) -> usize {
        self.anchors.len() + self.patches.len()
    }

    /// `Σ_j w_j · p_j(wi)` from `x`: the cones' and patches' weighted densities, without the
    /// BRDF's share.
    pub(super) fn density(&self, x: DVec3, wi: DVec3) -> f64 {
        let anchors: f64 = self.anchors.iter().map(|a| a.weighted_pdf(x, wi)).sum();
        let patches: f64 = self
            .patches
            .iter()
            .map(|p| p.weight * p.shape.pdf(x, wi))
            .sum();
        anchors + patches
    }

    /// A direction out of `x` from the cone or patch that `target` (a uniform number less
    /// the BRDF's weight) picks, driven by `rest`.
    pub(super) fn sample(&self, x: DVec3, mut target: f64, rest: [f64; 3]) -> Vec3 {
        // Sampler `i`: the cones, then the patches; rounding past the end takes the last
        // one.
        let cones = self.anchors.len();
        let weight = |i: usize| match i < cones {
            true => self.anchors[i].weight,
            false => self.patches[i - cones].weight,
        };
        let mut i = 0;
        while i + 1 < cones + self.patches.len() && target >= weight(i) {
            target -= weight(i);
            i += 1;
        }
        let dir = match self.anchors.get(i) {
            Some(a) => a.sampler.sample_with_extents(x, rest, a.extents),
            None => self.patches[i - cones].shape.sampler.sample(x, rest),
        };
        dir.as_vec3().normalize()
    }
}
