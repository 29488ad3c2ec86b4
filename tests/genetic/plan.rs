//! The pixel plan: the time limit, the mixture's failed pilot, and the training passes'
//! trial of the plan's guides.

use super::*;

/// With a time limit the plan has already used up, only the gate's pilot evolves. Where the
/// pilot shows that guiding pays (fig5), the cells left without a GA pixel take their evolved
/// neighbours' guides: with a guide they are not `pt` points, which then hold only the
/// low-variance cells, and the pilot's guides reach far beyond their own cells. (With a
/// mixture they would be `pt` points; no shipped scene makes the mixture's pilot pay, see
/// `Plan::build`.)
#[test]
fn cells_the_time_limit_leaves_out_take_their_neighbours_guides() {
    let (size, grid) = (96, 12);
    let (scene, accel) = fig5_sized(AccelKind::default_available(), size);
    let view = SceneView::new(&scene, accel.as_ref());
    let plan = guide_plan(
        &view,
        PlanConfig {
            grid: Some(grid),
            time_limit: Some(0.0),
            ..PlanConfig::default()
        },
    );
    let stats = &plan.stats;
    eprintln!(
        "{} GA pixels, {} late, {} pt points, {} low-variance cells",
        plan.pixels.len(),
        stats.time_limited_pixels,
        plan.fallback_points.len(),
        stats.low_variance_cells
    );
    assert_eq!(
        stats.gated_pixels, 0,
        "the pilot must pay on fig5 for this test"
    );
    assert_eq!(plan.pixels.len(), PILOT_PIXELS, "only the pilot evolves");
    assert!(stats.time_limited_pixels > 0);
    assert_eq!(plan.fallback_points.len(), stats.low_variance_cells);
    let guided = (0..size)
        .flat_map(|y| (0..size).map(move |x| (x, y)))
        .filter(|&(x, y)| plan.local(x, y).is_some())
        .count();
    // Were the late cells `pt` points, a pixel would render guided only where a pilot
    // pixel's weight dominates, about its own grid × grid cell.
    let cells = PILOT_PIXELS * (grid * grid) as usize;
    assert!(guided > 2 * cells, "{guided} guided pixels");
}

/// cbox has nothing for a mixture to learn: its pilot fails. On one thread the pilot pixels
/// run in order and stop once the pilot cannot pay (after `PILOT_PIXELS / 2 + 1` failures),
/// no baseline runs (no cell is judged by its variance) and every pixel renders with `pt`,
/// even next to the pilot pixels. The same pilot for a guide beside the spatial guide stops
/// early and closes the plan too, without the spatial guide it runs all its pixels, and
/// without the gate every pixel gets a mixture: the stop and the closure come from the
/// failed pilot.
#[test]
fn a_mixture_pilot_that_cannot_pay_stops_early_and_leaves_pt() {
    let (scene, accel) = scene_sized("cbox", 48);
    let view = SceneView::new(&scene, accel.as_ref());
    let ga = small_mixture_ga();
    let config = PlanConfig {
        grid: Some(8),
        ..PlanConfig::default()
    };
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let build = |inputs: PlanInputs| {
        one_thread.install(|| Plan::build(&view, &inputs, 3, false).expect("plan"))
    };
    let mixture = build(PlanInputs::new(&ga, &config, PlanFor::Mixture, MAX_BOUNCES));
    let gains: Vec<f64> = mixture
        .pixels
        .iter()
        .map(|p| p.trial.map_or(0.0, |t| t.gain))
        .collect();
    eprintln!("mixture pilot gains {gains:?}");
    assert!(
        gains.iter().all(|&g| g < 2.0),
        "the pilot must fail on cbox for this test"
    );
    assert_eq!(mixture.pixels.len(), PILOT_PIXELS / 2 + 1);
    let stats = &mixture.stats;
    assert_eq!(
        stats.gated_pixels + mixture.pixels.len() + stats.empty_cells,
        36
    );
    assert!(!stats.baseline_ran);
    assert_eq!(stats.low_variance_cells, 0, "no baseline ran");
    for p in &mixture.pixels {
        assert!(
            mixture.local(p.x, p.y).is_none(),
            "({}, {}) keeps a mixture",
            p.x,
            p.y
        );
    }
    assert!((0..48).all(|y| (0..48).all(|x| mixture.local(x, y).is_none())));

    // A guide's pilot beside the spatial guide (`ga-pt`'s default) closes the plan when it
    // fails, so it stops early too; without the spatial guide the pilot pixels that do not
    // lose still guide around them, so every one runs.
    let guide = build(PlanInputs::new(&ga, &config, PlanFor::Guide, MAX_BOUNCES));
    assert!(
        (PILOT_PIXELS / 2 + 1..PILOT_PIXELS).contains(&guide.pixels.len()),
        "a guide's pilot beside the spatial guide ran {} pixels",
        guide.pixels.len()
    );
    assert!((0..48).all(|y| (0..48).all(|x| guide.local(x, y).is_none())));
    let alone = build(PlanInputs {
        spatial_guide: false,
        ..PlanInputs::new(&ga, &config, PlanFor::Guide, MAX_BOUNCES)
    });
    assert!(
        alone.pixels.len() >= PILOT_PIXELS,
        "a guide's pilot without the spatial guide does not stop early"
    );

    // Without the gate (and without pruning, which since srt's absorption of 0.1 leaves
    // most of cbox's cells below `prune_variance`) the pilot's failure stops nothing.
    let unpruned = PlanConfig {
        prune: false,
        ..config
    };
    let ungated = build(PlanInputs {
        gate: GateConfig { gate: false },
        ..PlanInputs::new(&ga, &unpruned, PlanFor::Mixture, MAX_BOUNCES)
    });
    assert!(ungated.pixels.len() > PILOT_PIXELS);
    assert!(ungated.stats.baseline_ran);
    assert!((0..48).all(|y| (0..48).all(|x| ungated.local(x, y).is_some())));
}

/// `ga`'s evolved mixtures keep only the components that pay for their densities: on fig1
/// (where every cell's variance is high) with pruning on and off, without warm starts (so
/// that each pixel's evolution is the same in both), the mixtures without pruning hold every
/// evolved component, those with it fewer in all, and each pruned mixture's `V` on the test
/// paths stays within `COMPONENT_TOLERANCE` of the whole one's.
#[test]
fn ga_mixtures_keep_only_the_components_that_pay() {
    let (scene, accel) = scene_sized("fig1", 48);
    let view = SceneView::new(&scene, accel.as_ref());
    let ga = small_mixture_ga();
    let plan = |prune| {
        let config = PlanConfig {
            grid: Some(16),
            prune,
            warm_start: false,
            ..PlanConfig::default()
        };
        let inputs = PlanInputs {
            gate: GateConfig { gate: false },
            ..PlanInputs::new(&ga, &config, PlanFor::Mixture, MAX_BOUNCES)
        };
        Plan::build(&view, &inputs, 9, false).expect("plan")
    };
    let (whole, pruned) = (plan(false), plan(true));
    let evolved = |p: &Plan| -> Vec<(u32, u32, usize, f64)> {
        let pixels = p.pixels.iter().filter(|p| !p.kept_srt);
        pixels
            .map(|p| (p.x, p.y, p.mixture.generators.len(), p.v_best))
            .collect()
    };
    let (whole, pruned) = (evolved(&whole), evolved(&pruned));
    eprintln!("whole {whole:?}\npruned {pruned:?}");
    assert!(whole.len() >= 4, "too few evolved pixels: {whole:?}");
    assert!(whole.iter().all(|p| p.2 == ga.generators + 1));
    let count = |v: &[(u32, u32, usize, f64)]| v.iter().map(|p| p.2).sum::<usize>();
    assert!(count(&pruned) < count(&whole));
    for &(x, y, n, v) in &pruned {
        let Some(&(.., v_whole)) = whole.iter().find(|p| (p.0, p.1) == (x, y)) else {
            continue;
        };
        assert!(
            v <= v_whole * (1.0 + COMPONENT_TOLERANCE),
            "({x}, {y}): {n} components, V {v} against {v_whole}"
        );
    }
}

/// `ga-pt`'s training passes try the plan's per-pixel guides against the spatial guide
/// alone, which one pixel in sixteen keeps, and keep them only if the pixels they guide are
/// not noisier. On fig5 the evolved guides win the first trial; the same plan with every
/// evolved first-vertex sampler replaced by a narrow cone aimed at the camera, with 90 % of
/// the weight (a deliberately wrong guide), must lose it, and then no pixel renders with the
/// plan's guides.
#[test]
fn training_passes_keep_the_plans_guides_only_where_they_help() {
    let (scene, accel) = fig5_sized(AccelKind::default_available(), 96);
    let view = SceneView::new(&scene, accel.as_ref());
    // Test paths at the GA pixels themselves (footprint 0, `ga-pt`'s default): the plan
    // this test was made with, whose first trial is clear-cut (with a footprint of one grid
    // cell the guides win too, ratio 0.34, but at the third pass).
    let plan = guide_plan(
        &view,
        PlanConfig {
            grid: Some(12),
            footprint: Some(0.0),
            ..PlanConfig::default()
        },
    );
    assert!(
        !plan.is_closed(),
        "the pilot must pay on fig5 for this test"
    );
    let settings = RenderSettings {
        method: genpath::integrators::Method::GaPt,
        spp: 64,
        max_bounces: MAX_BOUNCES,
        seed: 9,
        progress: false,
        shard: Default::default(),
        control: Default::default(),
        learning: None,
    };
    let schedule = TrainingSchedule::Passes(5);
    let trial_of = |plan: &Plan| {
        let beside = Beside {
            plan,
            trial: &GuidesTrialPolicy,
        };
        let training =
            train_spatial(&view, &settings, (schedule, Selection::Fixed), Some(beside)).unwrap();
        let trial = training.guide.stats.guides_trial.expect("a trial ran");
        eprintln!("{trial:?}");
        assert_eq!(
            trial.pass, FIRST_TRIAL_PASS,
            "a clear outcome ends the trials"
        );
        assert!(trial.control_pixels >= 400, "{trial:?}");
        (trial, training.plan_guides)
    };
    let (evolved, levels) = trial_of(&plan);
    assert!(evolved.kept && evolved.ratio < 1.0, "{evolved:?}");
    assert_eq!(levels, PlanGuides::Everywhere);

    let mut wrong = plan.clone();
    let aim = scene.camera.origin.as_dvec3();
    let cone = AnchorSampler::new(aim, 0.05, 0.95).expect("a valid cone");
    for pixel in &mut wrong.pixels {
        // Component 0 is the defensive `srt` generator; the others' first steps go astray,
        // and take 90 % of the weight.
        let mut generators = pixel.mixture.generators.clone();
        for g in generators.iter_mut().skip(1) {
            g.steps[0].sampler = DirectionSampler::Anchor(cone);
        }
        let others = (generators.len() - 1) as f64;
        let mut weights = vec![0.9 / others; generators.len()];
        weights[0] = 0.1;
        pixel.mixture = Mixture::new(generators, weights);
    }
    let (astray, levels) = trial_of(&wrong);
    assert!(
        !astray.kept && astray.ratio > LEVELS_KEEP_RATIO,
        "{astray:?}"
    );
    assert_eq!(levels, PlanGuides::Nowhere);
}

/// A `ga-pt` plan (guides) of `view` with [`small_guide_ga`] and `config`, seed 5.
fn guide_plan(view: &SceneView, config: PlanConfig) -> Plan {
    let ga = small_guide_ga();
    let inputs = PlanInputs::new(&ga, &config, PlanFor::Guide, MAX_BOUNCES);
    Plan::build(view, &inputs, 5, false).expect("plan")
}
