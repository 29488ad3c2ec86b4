//! `ga-pt`: path tracing guided at each pixel by the directional samplers of the mixtures
//! its neighbouring GA pixels evolved ([`Guide`]); with the spatial guide (the default),
//! the vertices past them are guided as `pg` guides them ([`super::pg`]).

use super::ga::{
    build_plan, check_plan_size, describe_plan, explain_plan, plan_check, plan_summary,
};
use super::pg::{GuideEstimator, PlanGuides, PlanTrial, SpatialIntegrator, TrialArms};
use super::{
    pg, Context, Description, ExplainError, Integrator, Learned, Method, MethodInfo,
    PixelIntegrator, PrepareError, SelfCheck, Settings,
};
use crate::film::PixelSums;
use crate::genetic::plan::{Plan, PlanFor};
use crate::guiding::Guide;
use crate::guiding::GuidesTrial;
use crate::image::Image;
use crate::path::mixture::Mixture;
use crate::scene::Camera;
use glam::DVec3;

/// A GA plan's guides, with path tracing's own sampling past them.
pub struct GaPt {
    pub plan: Plan,
    pub max_bounces: u32,
    /// Whether the plan was read from a plan file rather than built.
    pub from_plan_file: bool,
}

/// `ga-pt` learns a GA plan (whose GA pixels `learn --shard` splits over jobs), and with
/// the spatial guide the guide's training beside it; it explains its plan.
pub const METHOD: MethodInfo = MethodInfo {
    prepare_learned: Some(prepare_learned),
    splits_learning: true,
    explains: true,
    settings: &["srt", "ga", "plan", "gate", "spatial", "lights"],
    ..MethodInfo::plain(prepare)
};

/// `ga-pt` from a learned plan, with the spatial guide's learned training where the
/// settings ask for the guide.
fn prepare_learned(
    context: &Context,
    learned: Learned,
) -> Result<Box<dyn Integrator>, PrepareError> {
    if context.config.spatial.spatial_guide {
        return Ok(Box::new(SpatialIntegrator::learned(context, learned)?));
    }
    let plan: Plan = learned.state()?;
    check_plan_size(&plan, context)?;
    Ok(Box::new(GaPt {
        plan,
        max_bounces: context.settings.max_bounces,
        from_plan_file: true,
    }))
}

fn prepare(context: &Context) -> Result<Box<dyn Integrator>, PrepareError> {
    let spatial = context.config.spatial.spatial_guide;
    if spatial {
        pg::check_schedule(context)?;
    }
    let plan = build_plan(context, PlanFor::Guide)?;
    if spatial {
        return Ok(Box::new(pg::train(
            context,
            Some((plan, &GuidesTrialPolicy)),
        )?));
    }
    Ok(Box::new(GaPt {
        plan,
        max_bounces: context.settings.max_bounces,
        from_plan_file: false,
    }))
}

impl PixelIntegrator for GaPt {
    type Estimator<'a> = GuideEstimator<'a>;
    fn estimator(&self) -> GuideEstimator<'_> {
        GuideEstimator::new(Some(&self.plan), self.max_bounces, Guide::default())
    }
    fn learned(&self) -> Option<Learned> {
        let summary = serde_json::json!({ "plan": plan_summary(&self.plan), "spatial": null });
        Some(Learned::new(Method::GaPt, None, &self.plan, &summary))
    }
    fn describe(&self, config: &Settings) -> Description {
        describe_plan(&self.plan, config, self.from_plan_file)
    }
    fn explain(&self, camera: &Camera, image: &Image) -> Option<Result<String, ExplainError>> {
        Some(explain_plan(camera, image, &self.plan))
    }
    fn self_check(&self) -> SelfCheck<'_> {
        plan_check(&self.plan)
    }
}

/// A trial decides when the pixels the plan's guides sample have more than this many times
/// the control arm's mean relative variance times mean cost per sample (then the guides go),
/// or less than its inverse (then they stay and trials stop); in between, they stay for the
/// next pass, which tries again. The cost counts because the guides' cones and patches make
/// a sample dearer (docs/methods/ga-pt.md, "The trial against the spatial guide", has the
/// measurements behind the band).
pub const LEVELS_KEEP_RATIO: f64 = 1.15;

/// The first training pass that tries the plan's guides: the guide that pass 1 samples with
/// has learned from one sample per pixel, too little to judge against.
pub const FIRST_TRIAL_PASS: u32 = 2;

/// A trial with fewer control pixels decides nothing: the plan's guides stay.
pub const MIN_TRIAL_PIXELS: usize = 256;

/// A trial weighs a pixel's variance by its mean over the passes before in the
/// `(2r + 1)²` pixels around it (`r` this radius), not at the pixel alone: early passes
/// hold a few samples per pixel, and the pixels whose own mean happens to be near 0 would
/// decide the trial (docs/methods/ga-pt.md, "The trial against the spatial guide").
pub const TRIAL_MEAN_RADIUS: u32 = 1;

/// `ga-pt`'s trial of its plan's guides in the spatial guide's training passes: from pass
/// [`FIRST_TRIAL_PASS`] on, one pixel in sixteen is left to the spatial guide alone
/// ([`PlanGuides::OutsideControl`]) and the two arms' relative variance times cost per
/// sample (the inverse of their efficiency, as the gate compares estimators) are compared,
/// until the ratio leaves `[1 / LEVELS_KEEP_RATIO, LEVELS_KEEP_RATIO]`; above it, the plan's
/// guides sample nowhere from then on ([`PlanGuides::Nowhere`]). The gate's pilot could
/// only compare them with `pt`, since the spatial guide learns after the plan.
#[derive(Clone, Copy, Debug, Default)]
pub struct GuidesTrialPolicy;

impl PlanTrial for GuidesTrialPolicy {
    fn tries(&self, pass: u32) -> bool {
        pass >= FIRST_TRIAL_PASS
    }
    fn arms<'a>(&self, plan: &'a Plan, before: &PixelSums, width: u32) -> Box<dyn TrialArms + 'a> {
        // The means of the passes before, independent of this pass's samples: a rare large
        // sample must not lower its own pixel's relative variance.
        Box::new(Arms {
            plan,
            width,
            means: box_means(before, width, TRIAL_MEAN_RADIUS),
            guided: Arm::default(),
            control: Arm::default(),
            weights: Vec::new(),
            parts: Vec::new(),
        })
    }
}

/// Per pixel of an image `width` pixels wide, the mean of `samples` over the pixels at most
/// `radius` away in x and in y (fewer at the image's edges).
fn box_means(samples: &PixelSums, width: u32, radius: u32) -> Vec<DVec3> {
    let spp = f64::from(samples.spp.max(1));
    let (w, r) = (width as usize, radius as usize);
    let h = samples.sum.len() / w.max(1);
    let mut means = Vec::with_capacity(samples.sum.len());
    for y in 0..h {
        let rows = y.saturating_sub(r)..(y + r + 1).min(h);
        for x in 0..w {
            let columns = x.saturating_sub(r)..(x + r + 1).min(w);
            let n = (rows.len() * columns.len()) as f64;
            let total: DVec3 = (rows.clone())
                .flat_map(|yy| samples.sum[yy * w..][columns.clone()].iter())
                .sum();
            means.push(total / (n * spp));
        }
    }
    means
}

/// The two arms of a training pass's trial of `plan`'s per-pixel guides (an image `width`
/// pixels wide, whose means over the passes before are `means`): per arm, the sums over its
/// pixels of a sample's relative variance and of a sample's cost in rays
/// ([`RayCounts::cost`]: the guides' cones and patches cost densities at every vertex), and
/// its pixels. `weights` and `parts` are [`Plan::neighbour_mixtures`]'s buffers, reused for
/// every pixel.
struct Arms<'a> {
    plan: &'a Plan,
    width: u32,
    means: Vec<DVec3>,
    guided: Arm,
    control: Arm,
    weights: Vec<(f64, usize)>,
    parts: Vec<(f64, &'a Mixture)>,
}

/// One arm of a trial: sums over its pixels of a sample's relative variance and cost, and
/// its pixels.
#[derive(Clone, Copy, Default)]
struct Arm {
    relative_variance: f64,
    cost: f64,
    pixels: usize,
}

impl Arm {
    /// The mean relative variance of a sample times its mean cost: the inverse of the
    /// arm's efficiency.
    fn work_variance(&self) -> f64 {
        let n = self.pixels.max(1) as f64;
        (self.relative_variance / n) * (self.cost / n)
    }
}

impl TrialArms for Arms<'_> {
    /// Adds pixel `i`, whose pass took `n` samples with sum and sum of squares `pass` at a
    /// cost of `cost` rays; its mean over the passes before is taken around it
    /// ([`TRIAL_MEAN_RADIUS`]). Pixels the plan does not guide (`pt`'s points, a closed plan)
    /// are in neither arm.
    fn add(&mut self, i: usize, pass: (DVec3, DVec3, u32), cost: f64) {
        let (width, mean) = (self.width as usize, self.means[i]);
        let (x, y) = ((i % width) as u32, (i / width) as u32);
        if !(self.plan).neighbour_mixtures(x, y, &mut self.weights, &mut self.parts) {
            return;
        }
        let (sum, sum_sq, n) = (pass.0, pass.1, f64::from(pass.2));
        // Unbiased sample variance of one sample, per channel, weighed as relMSE weighs.
        let variance = (sum_sq - sum * sum / n) / (n - 1.0);
        let relative = variance / (mean * mean + DVec3::splat(1e-2));
        let arm = if PlanGuides::OutsideControl.off_at(x, y) {
            &mut self.control
        } else {
            &mut self.guided
        };
        arm.relative_variance += relative.max(DVec3::ZERO).element_sum() / 3.0;
        arm.cost += cost / n;
        arm.pixels += 1;
    }

    /// The trial's outcome in pass `pass`, and whether the next pass tries again: the
    /// guides stayed, but without a clear win (or with too few control pixels to tell).
    fn decide(&self, pass: u32) -> (GuidesTrial, bool) {
        let ratio = self.guided.work_variance() / self.control.work_variance();
        // A ratio that is not a number (no variance in either arm) decides nothing.
        let undecided = self.control.pixels < MIN_TRIAL_PIXELS || ratio.is_nan();
        let kept = undecided || ratio <= LEVELS_KEEP_RATIO;
        let trial = GuidesTrial {
            pass,
            guided_pixels: self.guided.pixels,
            control_pixels: self.control.pixels,
            ratio,
            kept,
        };
        (
            trial,
            kept && (undecided || ratio >= 1.0 / LEVELS_KEEP_RATIO),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::{box_means, PixelSums};
    use glam::DVec3;

    #[test]
    fn box_means_average_the_neighbourhood_within_the_image() {
        // A 3 × 2 image of 2 samples per pixel whose sums are 2, 4, …, 12 (means 1 … 6).
        let mut samples = PixelSums::zero(6);
        samples.spp = 2;
        for (i, s) in samples.sum.iter_mut().enumerate() {
            *s = DVec3::splat(2.0 * (i + 1) as f64);
        }
        let means = box_means(&samples, 3, 1);
        let want = [3.0, 3.5, 4.0, 3.0, 3.5, 4.0];
        for (m, w) in means.iter().zip(want) {
            assert!((m.x - w).abs() < 1e-12 && m.x == m.z, "{means:?}");
        }
        // Radius 0: each pixel's own mean, as without the box.
        let own = box_means(&samples, 3, 0);
        assert_eq!(own[4], DVec3::splat(5.0));
    }
}
