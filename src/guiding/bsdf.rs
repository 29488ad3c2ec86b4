//! The guided BSDF, after the `GuidedBSDF` of Open PGL's pbrt-v4 fork: the material's BSDF
//! at a vertex together with what the [`Guide`] samples there, as one [`VertexBsdf`] that
//! the path tracer's loop evaluates, weighs and samples at every vertex of a guided path
//! ([`crate::path::pt`]); and [`Guide`] as a [`PathGuide`], which makes it.

use super::field::takes_guide;
use super::guide::Guide;
use super::vertex::Vertex;
use crate::path::pt::{Bsdf, GuidedVertex, PathGuide, VertexBsdf};
use crate::sampling::{uniform, Rng};
use crate::scene::material::BrdfSample;
use glam::Vec3;

/// The BSDF at one vertex with the guide's samplers there ([`Vertex`]). Its contract:
///
/// * [`eval`](VertexBsdf::eval) is the BSDF's own value `f(wo, wi)`: the guide changes how
///   directions are drawn, never what they carry;
/// * [`pdf`](VertexBsdf::pdf) is the density of the mixture that `sample` draws from, the
///   guide's samplers and the BSDF each with its selection probability (`p_k` of
///   [`super::guide`]: the level's weights, and the material's [`guide_share`](super::field::guide_share) of the
///   spatial field's region against the BSDF), the density multiple importance sampling
///   weighs next-event estimation against;
/// * [`sample`](VertexBsdf::sample) draws from that mixture with four uniform numbers,
///   `u[0]` picking the sampler and the other three driving it, and weighs the direction
///   by `f · |cos| / pdf`; `None` where the direction carries nothing;
/// * delta lobes (mirrors) are never guided, nor is a vertex where the guide samples only
///   the BSDF: there, and with no guide, it is exactly BSDF sampling — the BSDF's own value,
///   density and sample, from three uniform numbers, as [`Bsdf`] draws them.
#[derive(Clone, Copy)]
pub struct GuidedBsdf<'a> {
    bsdf: Bsdf<'a>,
    guide: Option<Vertex<'a>>,
}

impl<'a> GuidedBsdf<'a> {
    /// `bsdf` guided by `guide`, where it guides (see the type's documentation): not at
    /// all at a delta vertex, and without the spatial field where the material's
    /// [`guide_share`](super::field::guide_share) is 0 (a rough dielectric, which the BSDF alone samples).
    pub fn new(bsdf: Bsdf<'a>, guide: Option<Vertex<'a>>) -> Self {
        let unshared = !takes_guide(&bsdf.material);
        let guide = guide
            .map(|v| if unshared { v.without_spatial() } else { v })
            .filter(|v| !bsdf.material.mirror && v.guides());
        Self { bsdf, guide }
    }

    /// The BSDF it samples beside the guide.
    pub fn bsdf(&self) -> &Bsdf<'a> {
        &self.bsdf
    }

    /// The density of the mixture at `wi` where the BSDF's own is `bsdf_pdf`.
    fn mixed(&self, wi: Vec3, bsdf_pdf: f64) -> f64 {
        match &self.guide {
            Some(v) => v.pdf_with(
                wi.as_dvec3(),
                bsdf_pdf,
                v.density_share(&self.bsdf.material),
            ),
            None => bsdf_pdf,
        }
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
        self.mixed(wi, self.bsdf.pdf(wi))
    }

    /// The BSDF's value and the mixture's density, the BSDF's work shared
    /// ([`VertexBsdf::eval_pdf`] of [`Bsdf`]).
    fn eval_pdf(&self, wi: Vec3) -> (Vec3, f64) {
        let (f, pdf) = self.bsdf.eval_pdf(wi);
        (f, self.mixed(wi, pdf))
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

    /// The spatial region's density and the BSDF's, where the region samples beside the
    /// BSDF (the material [`takes_guide`]; see [`super::selection`]).
    fn selection_densities(&self, wi: Vec3) -> Option<(f64, f64)> {
        let guide_pdf = self.guide.as_ref()?.spatial_pdf(wi)?;
        Some((guide_pdf, self.bsdf.pdf(wi)))
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
        let vertex =
            (!bsdf.material.mirror && self.guides(k)).then(|| self.at(k, x, bsdf.frame, last));
        GuidedVertex {
            light_share: vertex.map_or(1.0, |v| v.light_share()),
            bsdf: GuidedBsdf::new(bsdf, vertex),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guiding::field::tests::trained_around;
    use crate::guiding::guide::tests::mixture;
    use crate::guiding::SpatialField;
    use crate::path::pt::Unguided;
    use crate::sampling::sample_rng;
    use crate::scene::material::bsdf;
    use crate::scene::Material;
    use std::sync::Arc;

    fn material(ks: f32, mirror: bool) -> Material {
        Material {
            name: "test".into(),
            kd: Vec3::new(0.5, 0.4, 0.3),
            ks: if mirror { Vec3::splat(ks) } else { Vec3::ZERO },
            glossy: match mirror {
                true => crate::scene::Glossy::None,
                false => crate::scene::Glossy::Phong {
                    ks: Vec3::splat(ks),
                    ns: 20.0,
                },
            },
            mirror,
            ke: Vec3::ZERO,
            two_sided: true,
            conductor: None,
            dielectric: None,
            textures: None,
        }
    }

    /// A field trained at the origin, on a floor (facing +y), on records around one
    /// direction.
    fn field() -> Arc<SpatialField> {
        Arc::new(trained_around(Vec3::new(0.6, 0.7, -0.3).normalize()).0)
    }

    /// The bits of a sample, to compare two for identity.
    fn bits(s: Option<BrdfSample>) -> Option<([u32; 3], u64, [u32; 3], bool)> {
        s.map(|s| {
            let v = |v: Vec3| v.to_array().map(f32::to_bits);
            (v(s.wi), s.pdf.to_bits(), v(s.weight), s.delta)
        })
    }

    const N: Vec3 = Vec3::Y;

    fn frame() -> bsdf::Frame {
        bsdf::Frame::new(N, Vec3::ZERO)
    }

    fn wo() -> Vec3 {
        Vec3::new(0.3, 1.0, 0.1).normalize()
    }

    /// `guided`'s draws against `expected`'s from the same stream, over many streams: the
    /// same samples bit for bit, the same densities and values for them, and the streams
    /// left at the same place.
    fn assert_draws_as(
        guided: &GuidedBsdf,
        expected: impl Fn(&mut Rng) -> Option<BrdfSample>,
        expected_pdf: impl Fn(Vec3) -> f64,
    ) {
        let mut sampled = 0;
        for stream in 0..2000 {
            let (mut a, mut b) = (sample_rng(3, stream, 0), sample_rng(3, stream, 0));
            let s = guided.sample(&mut a);
            assert_eq!(bits(s), bits(expected(&mut b)), "stream {stream}");
            assert_eq!(uniform(&mut a).to_bits(), uniform(&mut b).to_bits());
            if let Some(s) = s {
                assert_eq!(guided.pdf(s.wi).to_bits(), expected_pdf(s.wi).to_bits());
                let f = bsdf::eval(guided.bsdf.material, frame(), wo(), s.wi);
                assert_eq!(guided.eval(s.wi), f);
                sampled += 1;
            }
        }
        assert!(sampled > 1000, "{sampled} samples");
    }

    /// With no guide, where the guide has nothing (a guide without levels or field, the
    /// path's last vertex past the levels), and at a mirror under a guide that guides: the
    /// BSDF's own sampling from three uniform numbers, density and value.
    #[test]
    fn unguided_is_exactly_bsdf_sampling() {
        let guiding = Guide::new(&mixture()).with_spatial(Some(field()));
        let nothing = Guide::default();
        for m in [
            material(0.0, false),
            material(0.3, false),
            material(0.9, true),
        ] {
            let bsdf = Bsdf {
                material: (&m).into(),
                frame: frame(),
                wo: wo(),
                ns: N,
            };
            let mut cases = vec![
                (GuidedBsdf::new(bsdf, None), 1.0),
                {
                    let v = nothing.vertex(0, Vec3::ZERO, bsdf, false);
                    (v.bsdf, v.light_share)
                },
                {
                    let v = guiding.vertex(2, Vec3::ZERO, bsdf, true);
                    (v.bsdf, v.light_share)
                },
            ];
            if m.mirror {
                let v = guiding.vertex(0, Vec3::ZERO, bsdf, false);
                cases.push((v.bsdf, v.light_share));
            }
            assert_eq!(Unguided.vertex(0, Vec3::ZERO, bsdf, false).light_share, 1.0);
            for (guided, light_share) in cases {
                assert!(!guided.guided() && light_share == 1.0);
                assert_eq!(guided.samplers(), 0);
                // As `pt` drew them before the guided BSDF.
                let bsdf_sampled = |rng: &mut Rng| {
                    let u = [
                        uniform(rng) as f64,
                        uniform(rng) as f64,
                        uniform(rng) as f64,
                    ];
                    bsdf::sample(&m, frame(), wo(), u)
                };
                assert_draws_as(&guided, bsdf_sampled, |wi| bsdf::pdf(&m, frame(), wo(), wi));
            }
        }
    }

    /// At a vertex the guide guides (its two levels, each with the field's region, and past
    /// them the field alone): the vertex's mixture, sampled from four uniform numbers, and
    /// its density.
    #[test]
    fn guided_sampling_is_the_vertex_mixture_from_four_numbers() {
        let guide = Guide::new(&mixture()).with_spatial(Some(field()));
        for m in [material(0.0, false), material(0.3, false)] {
            let bsdf = Bsdf {
                material: (&m).into(),
                frame: frame(),
                wo: wo(),
                ns: N,
            };
            for k in 0..3 {
                let v = guide.vertex(k, Vec3::ZERO, bsdf, false);
                let vertex = guide.at(k, Vec3::ZERO, frame(), false);
                assert!(v.bsdf.guided() && v.bsdf.samplers() == vertex.samplers());
                assert_eq!(v.light_share, 1.0);
                let mixture_sampled = |rng: &mut Rng| {
                    let u = std::array::from_fn(|_| uniform(rng) as f64);
                    let s = vertex.sample(&m, wo(), u)?;
                    Some(BrdfSample {
                        wi: s.wi,
                        pdf: s.pdf,
                        weight: s.weight,
                        delta: false,
                    })
                };
                assert_draws_as(&v.bsdf, mixture_sampled, |wi| vertex.pdf(&m, wo(), wi));
            }
        }
    }
}
