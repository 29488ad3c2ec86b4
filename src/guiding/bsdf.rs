//! The guided BSDF, after the `GuidedBSDF` of Open PGL's pbrt-v4 fork: the material's BSDF
//! at a vertex together with what the [`Guide`] samples there, as one [`VertexBsdf`] that
//! the path tracer's loop evaluates, weighs and samples at every vertex of a guided path
//! ([`crate::path::pt`]); and [`Guide`] as a [`PathGuide`], which makes it.

use super::guide::Guide;
use super::vertex::Vertex;
use crate::path::pt::{Bsdf, GuidedVertex, PathGuide, VertexBsdf};
use crate::sampling::brdf::BrdfSample;
use crate::sampling::{uniform, Rng};
use glam::Vec3;

/// The BSDF at one vertex with the guide's samplers there ([`Vertex`]). Its contract:
///
/// * [`eval`](VertexBsdf::eval) is the BSDF's own value `f(wo, wi)`: the guide changes how
///   directions are drawn, never what they carry;
/// * [`pdf`](VertexBsdf::pdf) is the density of the mixture that `sample` draws from, the
///   guide's samplers and the BSDF each with its selection probability (`p_k` of
///   [`super::guide`]: the level's weights, and [`GUIDE_SHARE`] of the spatial field's
///   region against the BSDF), the density multiple importance sampling weighs next-event
///   estimation against;
/// * [`sample`](VertexBsdf::sample) draws from that mixture with four uniform numbers,
///   `u[0]` picking the sampler and the other three driving it, and weighs the direction
///   by `f · cos / pdf`; `None` where the direction carries nothing;
/// * delta lobes (mirrors) are never guided, nor is a vertex where the guide samples only
///   the BSDF: there, and with no guide, it is exactly BSDF sampling — the BSDF's own value,
///   density and sample, from three uniform numbers, as [`Bsdf`] draws them.
///
/// [`GUIDE_SHARE`]: super::field::GUIDE_SHARE
#[derive(Clone, Copy)]
pub struct GuidedBsdf<'a> {
    bsdf: Bsdf<'a>,
    guide: Option<Vertex<'a>>,
}

impl<'a> GuidedBsdf<'a> {
    /// `bsdf` guided by `guide`, where it guides (see the type's documentation).
    pub fn new(bsdf: Bsdf<'a>, guide: Option<Vertex<'a>>) -> Self {
        let guide = guide.filter(|v| !bsdf.material.mirror && v.guides());
        Self { bsdf, guide }
    }

    /// The BSDF it samples beside the guide.
    pub fn bsdf(&self) -> &Bsdf<'a> {
        &self.bsdf
    }

    /// Whether the guide samples directions here: if not, this is the BSDF alone.
    pub fn guided(&self) -> bool {
        self.guide.is_some()
    }
}

impl VertexBsdf for GuidedBsdf<'_> {
    fn eval(&self, wi: Vec3) -> Vec3 {
        self.bsdf.eval(wi)
    }

    fn pdf(&self, wi: Vec3) -> f64 {
        match &self.guide {
            Some(v) => v.pdf_with(wi.as_dvec3(), self.bsdf.pdf(wi)),
            None => self.bsdf.pdf(wi),
        }
    }

    fn sample(&self, rng: &mut Rng) -> Option<BrdfSample> {
        let Some(v) = &self.guide else {
            return self.bsdf.sample(rng);
        };
        let u = std::array::from_fn(|_| uniform(rng) as f64);
        let s = v.sample(self.bsdf.material, self.bsdf.wo, u)?;
        Some(BrdfSample {
            wi: s.wi,
            pdf: s.pdf,
            weight: s.weight,
            delta: false,
        })
    }

    /// The guide's cones, patches and spatial regions (see [`Vertex::samplers`]).
    fn samplers(&self) -> usize {
        self.guide.map_or(0, |v| v.samplers())
    }
}

impl PathGuide for Guide {
    type Bsdf<'a> = GuidedBsdf<'a>;

    /// The guide at a non-delta vertex ([`Guide::at`]) and its light share; at a mirror,
    /// or a vertex index the guide has nothing for, the BSDF alone with next-event
    /// estimation always.
    fn vertex<'a>(
        &'a self,
        k: usize,
        x: Vec3,
        bsdf: Bsdf<'a>,
        last: bool,
    ) -> GuidedVertex<GuidedBsdf<'a>> {
        let vertex = (!bsdf.material.mirror && self.guides(k)).then(|| self.at(k, x, bsdf.n, last));
        GuidedVertex {
            light_share: vertex.map_or(1.0, |v| v.light_share()),
            bsdf: GuidedBsdf::new(bsdf, vertex),
        }
    }
}
