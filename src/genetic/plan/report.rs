//! What a GA plan tells of itself: the JSON statistics of a render that used it, and what
//! it and the renderer left out for the scene.

use super::{GateConfig, Plan, PlanConfig, PRUNE_SHARE};
use crate::genetic::GaConfig;
use crate::scene::SceneAnalysis;

/// What the GA plan and the renderer left out for this scene, and why.
fn left_out(plan: &Plan, config: &PlanConfig, analysis: &SceneAnalysis) -> Vec<String> {
    let mut out = Vec::new();
    if analysis.glossy_triangles == 0 {
        out.push("glossy-lobe (Phong, microfacet) evaluation and sampling: no glossy material (the BRDF code runs only the lobes a material has)".to_string());
    }
    if analysis.mirror_triangles == 0 {
        out.push("delta vertices: no mirror, conductor or dielectric material".to_string());
    }
    let s = &plan.stats;
    out.push(format!(
        "GA at {} pixels that see only background or emitters ({} grid cells without a scattering pixel)",
        s.skipped_pixels, s.empty_cells
    ));
    if !config.prune {
        out.push("nothing else: pruning is off (--no-prune)".to_string());
        return out;
    }
    if !s.baseline_ran {
        out.push(format!(
            "the baseline and the GA at {} grid pixels: the gate's pilot predicted no gain (its gains over pt: geometric mean {:.2})",
            s.gated_pixels, s.pilot_gain
        ));
        return out;
    }
    out.push(format!(
        "GA in {} grid cells whose pooled baseline relative variance is below {} (cells: min {:.3}, median {:.3}, max {:.3})",
        s.low_variance_cells, config.prune_variance, s.cell_variance[0], s.cell_variance[1], s.cell_variance[2]
    ));
    let max_steps = plan.pixels.iter().map(|p| p.steps).max().unwrap_or(0);
    let cut = plan.pixels.iter().filter(|p| p.steps < max_steps).count();
    out.push(format!(
        "generator steps past the depth the test paths need (all but {} of Σ F²/q): {} of {} GA pixels evolve fewer steps than the deepest ({max_steps}); steps per pixel {:?}",
        PRUNE_SHARE,
        cut,
        plan.pixels.len(),
        {
            let mut h = std::collections::BTreeMap::new();
            for p in &plan.pixels {
                *h.entry(p.steps).or_insert(0usize) += 1;
            }
            h
        }
    ));
    out
}

/// What the JSON statistics record of a GA plan: settings, per-phase totals, every GA
/// pixel's evolved mixture, and the fitness curves of a few pixels spread over the list;
/// of a plan read from a plan file (`from_file`), a summary without the pixels and curves
/// (the file has them).
pub fn json(
    plan: &Plan,
    (ga, config, gate): (&GaConfig, &PlanConfig, &GateConfig),
    from_file: bool,
) -> serde_json::Value {
    const CURVES: usize = 8;
    let n = plan.pixels.len();
    let curves: Vec<_> = (0..n.min(CURVES))
        .map(|i| {
            let p = &plan.pixels[i * n / n.min(CURVES)];
            serde_json::json!({ "x": p.x, "y": p.y, "history": p.history })
        })
        .collect();
    let pixels: Vec<_> = plan
        .pixels
        .iter()
        .map(|p| {
            serde_json::json!({
                "x": p.x, "y": p.y, "origin": p.origin,
                "v_srt": p.v_srt, "v_best": p.v_best, "v_evolved": p.v_evolved, "kept_srt": p.kept_srt,
                "trial": p.trial, "warm": p.warm,
                "test_paths": p.test_paths, "light_paths": p.light_paths, "steps": p.steps,
                "test_path_seconds": p.test_path_seconds, "ga_seconds": p.ga_seconds,
                "mixture": p.mixture,
            })
        })
        .collect();
    let evolve_s = plan.stats.evolve_cpu_seconds.max(1e-9);
    let analysis = plan.analysis.clone();
    let (curves, pixels) = if from_file {
        let there = serde_json::json!("in the plan file (see plan_file)");
        (there.clone(), there)
    } else {
        (serde_json::json!(curves), serde_json::json!(pixels))
    };
    serde_json::json!({
        "config": ga,
        "plan": config,
        "gate": gate,
        "left_out": left_out(plan, config, &analysis),
        "scene_analysis": analysis,
        "stats": plan.stats,
        "ga_pixels": n,
        "improved_pixels": plan.pixels.iter().filter(|p| !p.kept_srt).count(),
        "individual_evaluations_per_cpu_s": plan.stats.individual_evaluations as f64 / evolve_s,
        "fitness_curves": curves,
        "pixels": pixels,
    })
}
