//! The guide at one path vertex ([`Vertex`], Open PGL's `SurfaceSamplingDistribution`):
//! what [`Guide::at`] found there — the level's cones and patches, the spatial field's
//! region, or the BRDF alone — and the density and the sampling of the mixture they make
//! with the BRDF (see [`super::guide`]).

use super::field::{guide_share, SpatialField};
use super::level::Level;
#[cfg(doc)]
use super::Guide;
use crate::scene::material::bsdf::{self, Frame};
use crate::scene::Material;
use crate::scene::MaterialAt;
use glam::{DVec3, Vec3};

/// A direction drawn from a guide.
pub struct GuideSample {
    pub wi: Vec3,
    /// `p_k(wi)`, solid angle.
    pub pdf: f64,
    /// BRDF × cos / pdf.
    pub weight: Vec3,
}

/// What samples directions at one vertex (see [`Guide::at`]): a level samples its BRDF
/// share from the spatial guide's region where there is one.
#[derive(Clone, Copy)]
pub(super) enum VertexSampler<'a> {
    /// The guide's level for this vertex index: its cones and patches, and its BRDF share
    /// (mixed with the spatial field's region, if any).
    Level(&'a Level, Option<(&'a SpatialField, usize)>),
    /// Past the levels: the spatial field's region, mixed with the BRDF.
    Spatial(&'a SpatialField, usize),
    /// The BRDF alone.
    Brdf,
}

/// The guide of one vertex: the point `x`, its normal `n` (facing the path's `wo`) and
/// what samples directions there.
#[derive(Clone, Copy)]
pub struct Vertex<'a> {
    pub(super) sampler: VertexSampler<'a>,
    /// The probability of next-event estimation here.
    pub(super) light_share: f64,
    /// The guide's fault injection (1 without).
    pub(super) scale: f64,
    /// The spatial region's share of guided sampling, and the share its densities are
    /// computed with (the same but in a test's wrong input): see
    /// [`Lookup`](super::field::Lookup).
    pub(super) share: f64,
    pub(super) density_share: f64,
    pub(super) x: DVec3,
    pub(super) frame: Frame,
}

impl Vertex<'_> {
    /// The probability of next-event estimation here: 1, or less in a cell of the spatial
    /// guide where training never saw a light sample reach a light. Multiple importance
    /// sampling weighs the light sample's density times this.
    pub fn light_share(&self) -> f64 {
        self.light_share
    }

    /// Whether this vertex samples anything but the BRDF.
    pub fn guides(&self) -> bool {
        !matches!(self.sampler, VertexSampler::Brdf)
    }

    /// This vertex without the spatial field's region, for a material whose
    /// [`guide_share`] is 0: the same density, without the region's descents (a level's
    /// cones and patches stay).
    pub(super) fn without_spatial(self) -> Self {
        let sampler = match self.sampler {
            VertexSampler::Spatial(..) => VertexSampler::Brdf,
            VertexSampler::Level(level, _) => VertexSampler::Level(level, None),
            VertexSampler::Brdf => VertexSampler::Brdf,
        };
        Self { sampler, ..self }
    }

    /// The share of guided sampling at this vertex of `m`, and the share its densities are
    /// computed with ([`guide_share`] of the region's).
    fn shares(&self, m: &Material) -> (f64, f64) {
        (
            guide_share(m, self.share),
            guide_share(m, self.density_share),
        )
    }

    /// The share of the spatial guide's density in this vertex's density for `m` (see
    /// [`guide_share`]).
    pub(super) fn density_share(&self, m: &Material) -> f64 {
        self.shares(m).1
    }

    /// The density of the spatial field's region here at unit `wi`, where a region
    /// guides this vertex.
    pub fn spatial_pdf(&self, wi: Vec3) -> Option<f64> {
        match self.sampler {
            VertexSampler::Spatial(s, cell) | VertexSampler::Level(_, Some((s, cell))) => {
                Some(s.pdf(cell, wi))
            }
            _ => None,
        }
    }

    /// Cones, patches or spatial regions: the densities one evaluation of `pdf` costs.
    pub fn samplers(&self) -> usize {
        match self.sampler {
            VertexSampler::Level(l, spatial) => l.samplers() + usize::from(spatial.is_some()),
            VertexSampler::Spatial(..) => 1,
            VertexSampler::Brdf => 0,
        }
    }

    /// The density of a spatially guided vertex from the guide's and the BRDF's, the guide
    /// sampled with probability `share` ([`guide_share`]).
    fn spatial_mix(&self, share: f64, guide_pdf: f64, brdf_pdf: f64) -> f64 {
        share * self.scale * guide_pdf + (1.0 - share) * brdf_pdf
    }

    /// `p(wi)` for the material's BRDF pdf `brdf_pdf` here, the spatial guide's share of
    /// the BRDF's part being `share` (the material's [`guide_share`]).
    pub(super) fn pdf_with(&self, wi: DVec3, brdf_pdf: f64, share: f64) -> f64 {
        match self.sampler {
            VertexSampler::Brdf => brdf_pdf,
            VertexSampler::Spatial(s, cell) => {
                self.spatial_mix(share, s.pdf(cell, wi.as_vec3()), brdf_pdf)
            }
            VertexSampler::Level(level, spatial) => {
                let brdf_pdf = match spatial {
                    Some((s, cell)) => self.spatial_mix(share, s.pdf(cell, wi.as_vec3()), brdf_pdf),
                    None => brdf_pdf,
                };
                level.brdf * brdf_pdf + self.scale * level.density(self.x, wi)
            }
        }
    }

    /// `p(wi)` for `material` seen from `wo`.
    pub fn pdf<'m>(&self, material: impl Into<MaterialAt<'m>>, wo: Vec3, wi: Vec3) -> f64 {
        let material = material.into();
        let brdf_pdf = bsdf::pdf(material, self.frame, wo, wi);
        self.pdf_with(wi.as_dvec3(), brdf_pdf, self.density_share(&material))
    }

    /// A direction out of this vertex of `material` seen from `wo`, from four uniform
    /// numbers: `u[0]` picks the sampler, the rest drive it. `None` where the direction
    /// carries nothing.
    pub fn sample<'m>(
        &self,
        material: impl Into<MaterialAt<'m>>,
        wo: Vec3,
        u: [f64; 4],
    ) -> Option<GuideSample> {
        let material = material.into();
        let rest = [u[1], u[2], u[3]];
        let n = self.frame;
        let (share, density_share) = self.shares(&material);
        let wi = match self.sampler {
            VertexSampler::Brdf => {
                let s = bsdf::sample(material, n, wo, rest)?;
                return Some(GuideSample {
                    wi: s.wi,
                    pdf: s.pdf,
                    weight: s.weight,
                });
            }
            VertexSampler::Spatial(s, cell) => {
                // The guide's own sample brings its density from the descent that drew it.
                let (wi, guided) = if u[0] < share {
                    let (wi, pdf) = s.sample(cell, rest);
                    (wi, Some(pdf))
                } else {
                    (bsdf::sample_direction(material, n, wo, rest)?, None)
                };
                return self.finish_sample(material, wo, wi, |brdf_pdf| {
                    let guide_pdf = guided.unwrap_or_else(|| s.pdf(cell, wi));
                    self.spatial_mix(density_share, guide_pdf, brdf_pdf)
                });
            }
            VertexSampler::Level(level, spatial) => {
                let target = u[0] - level.brdf;
                match spatial {
                    _ if target >= 0.0 => level.sample(self.x, target, rest),
                    // The BRDF share as the spatial guide samples: `u[0] / brdf` picks.
                    Some((s, cell)) if u[0] < share * level.brdf => s.sample(cell, rest).0,
                    _ => bsdf::sample_direction(material, n, wo, rest)?,
                }
            }
        };
        self.finish_sample(material, wo, wi, |brdf_pdf| {
            self.pdf_with(wi.as_dvec3(), brdf_pdf, density_share)
        })
    }

    /// The guide sample of direction `wi`: its density (`pdf` of the BRDF's density, asked
    /// only where the direction carries something) and weight.
    fn finish_sample(
        &self,
        material: MaterialAt,
        wo: Vec3,
        wi: Vec3,
        pdf: impl FnOnce(f64) -> f64,
    ) -> Option<GuideSample> {
        let n = self.frame;
        // The guide covers the sphere; the material says where light goes (above the
        // surface, or through it for a rough dielectric) and with which cosine.
        let cos = bsdf::cosine(&material, n, wi)?;
        let (f, bsdf_pdf) = bsdf::eval_pdf(material, n, wo, wi);
        if f.max_element() <= 0.0 {
            return None;
        }
        let pdf = pdf(bsdf_pdf);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(GuideSample {
            wi,
            pdf,
            weight: f * (cos as f64 / pdf) as f32,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guiding::field::tests::trained_around;
    use crate::guiding::guide::tests::{mixture, PATCH};
    use crate::guiding::square::to_square;
    use crate::guiding::Guide;
    use crate::sampling::patch::PatchShape;
    use crate::sampling::{sample_rng, uniform};
    use crate::scene::Material;
    use std::sync::Arc;

    /// Monte Carlo ∫ p_0(ω) dω over the sphere, uniform directions: 1 for a density.
    fn integral(guide: &Guide, material: &Material) -> f64 {
        integral_at(guide, material, 0)
    }

    /// ∫ p_k(ω) dω at the origin.
    fn integral_at(guide: &Guide, material: &Material, k: usize) -> f64 {
        let n = Vec3::Y;
        let wo = Vec3::new(0.3, 1.0, 0.1).normalize();
        let mut rng = sample_rng(5, 0, 0);
        // The cone and the patch hold 0.58 of the mass in 0.3 sr: the estimate's standard
        // deviation is about 0.002.
        let count = 4_000_000;
        let mut sum = 0.0;
        for _ in 0..count {
            let z = 1.0 - 2.0 * uniform(&mut rng);
            let phi = std::f32::consts::TAU * uniform(&mut rng);
            let r = (1.0 - z * z).max(0.0).sqrt();
            let wi = Vec3::new(r * phi.cos(), z, r * phi.sin());
            sum += guide.pdf(k, material, Vec3::ZERO, Frame::new(n, Vec3::ZERO), wo, wi);
        }
        sum / count as f64 * 4.0 * std::f64::consts::PI
    }

    fn white() -> Material {
        Material {
            name: "white".into(),
            kd: Vec3::splat(0.5),
            ks: Vec3::ZERO,
            glossy: crate::scene::Glossy::None,
            mirror: false,
            ke: Vec3::ZERO,
            two_sided: true,
            conductor: None,
            dielectric: None,
            textures: None,
        }
    }

    /// Past the mixture's two levels, a spatial guide trained on records around one
    /// direction: a density (and the check rejects its density off by 10 %), whose samples
    /// carry the density `pdf` reports and go where the records did.
    #[test]
    fn spatial_guide_past_the_levels_is_a_density() {
        let material = white();
        // Records spread over a square of side 1/16 of the square map at `target`, all
        // at the origin, on a floor (facing +y).
        let (field, [tu, tv]) = trained_around(Vec3::new(0.6, 0.7, -0.3).normalize());
        let spatial = Arc::new(field);
        // Near: within the records' square widened by the finest leaf (1/32 of the square),
        // the resolution of the guide.
        let near = |d: Vec3| {
            let [u, v] = to_square(d);
            let around = -1.0 / 32.0..3.0 / 32.0;
            around.contains(&(u - tu)) && around.contains(&(v - tv))
        };
        let guide = Guide::new(&mixture()).with_spatial(Some(spatial));
        assert!(
            guide.guides(2)
                && guide
                    .at(2, Vec3::ZERO, Frame::new(Vec3::Y, Vec3::ZERO), false)
                    .samplers()
                    == 1
        );
        let total = integral_at(&guide, &material, 2);
        assert!((total - 1.0).abs() < 0.01, "∫ p = {total}");
        // Half the density is the spatial guide's: ×1.1 there makes ∫ p ≈ 1.05.
        let wrong = integral_at(&guide.clone().with_pdf_error(1.1), &material, 2);
        assert!(
            (wrong - 1.0).abs() > 0.03,
            "∫ p = {wrong} with a wrong density"
        );
        let (n, wo) = (Vec3::Y, Vec3::new(0.3, 1.0, 0.1).normalize());
        let mut rng = sample_rng(7, 0, 0);
        // Of 10 000 samples at level `k`, each carrying the density `pdf` reports: how
        // many are near the records.
        let mut samples_near = |k: usize| {
            let mut count = 0;
            for _ in 0..10_000 {
                let u = std::array::from_fn(|_| uniform(&mut rng) as f64);
                if let Some(s) =
                    guide.sample(k, &material, Vec3::ZERO, Frame::new(n, Vec3::ZERO), wo, u)
                {
                    let p = guide.pdf(
                        k,
                        &material,
                        Vec3::ZERO,
                        Frame::new(n, Vec3::ZERO),
                        wo,
                        s.wi,
                    );
                    assert!((s.pdf - p).abs() <= 1e-9 * p, "{} vs {p}", s.pdf);
                    count += usize::from(near(s.wi));
                }
            }
            count
        };
        // 0.5 · 0.9 of the samples near the records (1/64 of the square with the margin).
        let towards = samples_near(2);
        assert!(towards > 4_000, "{towards} samples near the records");
        // At the levels, the BRDF share samples as the spatial guide does: still a density,
        // whose samples carry the density `pdf` reports, and the check rejects it off by
        // 10 % (the cone, the patch and the spatial guide hold 0.85 of level 0: ∫ ≈ 1.085).
        let by_spatial = samples_near(0);
        assert!(
            by_spatial > 500,
            "{by_spatial} samples near the records at level 0"
        );
        for k in 0..2 {
            assert_eq!(
                guide
                    .at(k, Vec3::ZERO, Frame::new(Vec3::Y, Vec3::ZERO), false)
                    .samplers(),
                3 - k
            );
            let total = integral_at(&guide, &material, k);
            assert!((total - 1.0).abs() < 0.01, "level {k}: ∫ p = {total}");
        }
        let wrong = integral_at(&guide.clone().with_pdf_error(1.1), &material, 0);
        assert!(
            (wrong - 1.0).abs() > 0.02,
            "∫ p = {wrong} with a wrong density"
        );
        // On a surface facing another way, where nothing was recorded: BRDF sampling alone.
        let (n, wo) = (Vec3::X, Vec3::new(1.0, 0.3, 0.1).normalize());
        let wi = Vec3::new(0.5, 0.5, 0.0).normalize();
        let brdf_pdf = bsdf::pdf(&material, Frame::new(n, Vec3::ZERO), wo, wi);
        assert_eq!(
            guide.pdf(2, &material, Vec3::ZERO, Frame::new(n, Vec3::ZERO), wo, wi),
            brdf_pdf
        );
    }

    #[test]
    fn guide_is_a_density_and_sampling_agrees_with_pdf() {
        let material = white();
        let guide = Guide::new(&mixture());
        assert!(guide.guides(0) && guide.guides(1) && !guide.guides(2));
        let total = integral(&guide, &material);
        assert!((total - 1.0).abs() < 0.01, "∫ p = {total}");
        // The same check rejects cone and patch densities off by 10 % (weight 0.7: ∫ p ≈
        // 1.07).
        let wrong = integral(&guide.clone().with_pdf_error(1.1), &material);
        assert!(
            (wrong - 1.0).abs() > 0.03,
            "∫ p = {wrong} with a wrong density"
        );
        // Every sample carries the density `pdf` reports for its direction.
        let (n, wo) = (Vec3::Y, Vec3::new(0.3, 1.0, 0.1).normalize());
        let mut rng = sample_rng(6, 0, 0);
        let (mut anchored, mut patched) = (0, 0);
        let shape = PatchShape::new(&PATCH);
        for _ in 0..10_000 {
            let u = std::array::from_fn(|_| uniform(&mut rng) as f64);
            if let Some(s) =
                guide.sample(0, &material, Vec3::ZERO, Frame::new(n, Vec3::ZERO), wo, u)
            {
                let p = guide.pdf(
                    0,
                    &material,
                    Vec3::ZERO,
                    Frame::new(n, Vec3::ZERO),
                    wo,
                    s.wi,
                );
                assert!((s.pdf - p).abs() <= 1e-9 * p, "{} vs {p}", s.pdf);
                let expected = bsdf::eval(&material, Frame::new(n, Vec3::ZERO), wo, s.wi)
                    * (n.dot(s.wi) / p as f32);
                assert!((s.weight - expected).length() <= 1e-5 * expected.length());
                anchored += usize::from(s.wi.dot(Vec3::new(1.0, 2.0, 0.0).normalize()) > 0.98);
                patched += usize::from(shape.patch_density(DVec3::ZERO, s.wi.as_dvec3()) > 0.0);
            }
        }
        // About 0.5 · 0.8 of the samples go into the 0.2-rad cone, 0.2 · 0.9 to the patch.
        assert!(anchored > 3_500, "{anchored} samples in the anchor cone");
        assert!(patched > 1_600, "{patched} samples towards the patch");
    }
}
