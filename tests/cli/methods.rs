//! Each method's renders: determinism across threads, statistics, bad generator files.

use super::*;

#[test]
fn one_and_two_threads_give_bit_identical_images() {
    let dir = tempfile::tempdir().unwrap();
    let render = |threads: &str| {
        let out = dir.path().join(format!("t{threads}.exr"));
        render_small_fig5(&out, &["--threads", threads]);
        pixel_bits(&out)
    };
    let one = render("1");
    assert_eq!(one, render("2"));
    // And the seed matters: a different seed must change the image.
    let other = dir.path().join("seed.exr");
    render_small_fig5(&other, &["--seed", "2"]);
    assert_ne!(one, pixel_bits(&other));
}

#[test]
fn srt_and_mixture_methods_render() {
    let dir = tempfile::tempdir().unwrap();
    // The hand-made mixture with its red-wall cone replaced by a patch over the lit band.
    let patches = dir.path().join("patches.toml");
    let anchors = std::fs::read_to_string(fig5().with_file_name("anchors.toml")).unwrap();
    std::fs::write(&patches, anchors.replacen(RED_CONE, RED_PATCH, 1)).unwrap();
    for (tag, method, extra) in [
        ("srt", "srt", vec![]),
        (
            "mixture",
            "mixture",
            vec!["--generators", "scenes/fig5/anchors.toml"],
        ),
        (
            "patches",
            "mixture",
            vec!["--generators", patches.to_str().unwrap()],
        ),
    ] {
        let out = dir.path().join(format!("{tag}.exr"));
        let mut args = vec![
            "render",
            "scenes/fig5/scene.toml",
            "-o",
            out.to_str().unwrap(),
            "--spp",
            "2",
        ];
        args.extend([
            "--width", "16", "--height", "16", "--quiet", "--method", method,
        ]);
        args.extend(extra);
        let output = genpath(&args);
        assert!(
            output.status.success(),
            "{method}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let json = std::fs::read_to_string(dir.path().join(format!("{tag}.exr.json"))).unwrap();
        assert!(
            json.contains("\"generators\""),
            "{tag}: the mixture is not in the JSON"
        );
        if tag == "patches" {
            assert!(json.contains("\"patch\""), "the patch is not in the JSON");
        }
    }
}

/// The first cone of `scenes/fig5/anchors.toml`, and a patch over the band it aims at.
const RED_CONE: &str =
    r#"{ type = "anchor", anchor = [-1.0, 1.9, 0.0], theta_c = 0.45, alpha = 0.85 }"#;
const RED_PATCH: &str = r#"{ type = "patch", center = [-1.0, 1.8, 0.0], half_u = [0.0, 0.2, 0.0], half_v = [0.0, 0.0, 1.0], alpha = 0.9 }"#;

#[test]
fn bad_generator_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.exr");
    let anchors = std::fs::read_to_string(fig5().with_file_name("anchors.toml")).unwrap();
    let cases = [
        (
            anchors.replace("theta_c = 0.45", "theta_c = 4.0"),
            "cone half-angle",
        ),
        (
            anchors.replace("alpha = 0.85", "alpha = 1.0"),
            "probability in the cone",
        ),
        (
            anchors.replace("absorption = 0.95", "absorption = 1.5"),
            "absorption 1.5",
        ),
        (anchors.replace("prim = 8", "prim = 0"), "not an emitter"),
        (anchors.replace("level = 0", "level = 40"), "level"),
        (anchors.replace("beta = 0.5", "beta = 1.0"), "region"),
        (
            anchors.replace("srt_weight = 0.2", "srt_weight = 0.0"),
            "srt_weight",
        ),
        (
            anchors.replace("weight = 1.0", "weight = -1.0"),
            "weight -1",
        ),
        (anchors.replace("theta_c", "theta"), "unknown field"),
        (
            anchors.replacen(RED_CONE, &RED_PATCH.replace("0.0, 1.0]", "0.0, 0.0]"), 1),
            "span no area",
        ),
        (
            anchors.replacen(RED_CONE, &RED_PATCH.replace("0.9 }", "1.0 }"), 1),
            "probability on the patch",
        ),
        (
            anchors.replacen(RED_CONE, &RED_PATCH.replace("[-1.0, 1.8", "[nan, 1.8"), 1),
            "patch centre",
        ),
        ("[[generators]\n".to_string(), "generators.toml"),
    ];
    for (text, needle) in cases {
        let path = dir.path().join("generators.toml");
        std::fs::write(&path, text).unwrap();
        assert_fails(
            &fig5(),
            &[
                "--method",
                "mixture",
                "--generators",
                path.to_str().unwrap(),
            ],
            &out,
            &[needle],
        );
    }
    assert_fails(&fig5(), &["--method", "mixture"], &out, &["--generators"]);
    assert_fails(
        &fig5(),
        &["--method", "mixture", "--generators", "/nonexistent.toml"],
        &out,
        &["nonexistent.toml"],
    );
    assert_fails(
        &fig5(),
        &["--method", "srt", "--srt-absorption", "1.0"],
        &out,
        &["--srt-absorption"],
    );
}

/// `--method pg` and `ga-pt` (whose spatial guide is on by default): bit-identical for 1
/// and 2 threads (the training records merge in tile order), with the training in the
/// JSON: 2 passes of 1 and 2 samples per pixel, of the image's 4. `--spatial-guide false`
/// trains none.
#[test]
fn spatial_guide_renders_deterministically_with_its_training_stats() {
    let dir = tempfile::tempdir().unwrap();
    for method in [
        &["--method", "pg", "--spatial-passes", "2"][..],
        &["--method", "ga-pt", "--spatial-passes", "2"],
    ] {
        let render = |threads: &str| {
            let out = dir.path().join(format!("pg{threads}.exr"));
            render_small_fig5(&out, &[&["--threads", threads][..], method].concat());
            out
        };
        let one = render("1");
        let json: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.path().join("pg1.exr.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(pixel_bits(&one), pixel_bits(&render("2")), "{method:?}");
        let spatial = &json["spatial"];
        assert_eq!(spatial["passes"], 2, "{method:?}: {spatial}");
        assert_eq!(spatial["spp"], 3, "{method:?}: {spatial}");
        assert_eq!(json["settings"]["spp"], 4, "{method:?}: {json}");
        assert!(spatial["trained_cells"].as_u64().unwrap() > 0, "{spatial}");
        assert!(json["times_s"]["spatial"].as_f64().unwrap() > 0.0);
    }
    let out = dir.path().join("off.exr");
    render_small_fig5(&out, &["--method", "ga-pt", "--spatial-guide", "false"]);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("off.exr.json")).unwrap())
            .unwrap();
    assert!(json["spatial"].is_null(), "{json}");
    // `times_s` lists the phases the method prepared in: ga-pt without the guide has none.
    assert!(json["times_s"].get("spatial").is_none(), "{json}");
    assert!(json["times_s"]["ga"].as_f64().is_some(), "{json}");
    let out = dir.path().join("o.exr");
    for passes in ["0", "13"] {
        assert_fails(
            &fig5(),
            &["--method", "pg", "--spatial-passes", passes],
            &out,
            &["--spatial-passes"],
        );
    }
    // 3 passes take 1 + 2 + 4 samples per pixel: more than the image's 1.
    assert_fails(
        &fig5(),
        &["--method", "pg", "--spatial-passes", "3"],
        &out,
        &["--spatial-passes 3 trains on 7 samples per pixel, more than --spp 1"],
    );
}

#[test]
fn impossible_ga_flags() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), None, None, None);
    let out = dir.path().join("o.exr");
    let ga = |extra: &[&'static str]| [&["--method", "ga"], extra].concat();
    assert_fails(&scene, &ga(&["--p-cross", "2"]), &out, &["--p-cross"]);
    assert_fails(&scene, &ga(&["--population", "0"]), &out, &["--population"]);
    assert_fails(&scene, &ga(&["--test-paths", "0"]), &out, &["--test-paths"]);
    assert_fails(&scene, &ga(&["--ga-grid", "0"]), &out, &["--ga-grid"]);
    assert_fails(
        &scene,
        &ga(&["--population", "4", "--elitism", "5"]),
        &out,
        &["elitism 5 exceeds the population 4"],
    );
    assert_fails(
        &scene,
        &ga(&["--defensive-weight", "0"]),
        &out,
        &["defensive_weight"],
    );
    assert_fails(&scene, &ga(&["--ga-extra", "NaN"]), &out, &["extra"]);
    let explain = dir.path().join("e.svg");
    let explain = explain.to_str().unwrap();
    assert_fails(
        &scene,
        &["--explain", explain, "--method", "pt"],
        &out,
        &["--explain is only used with --method ga or ga-pt"],
    );
    assert!(!Path::new(explain).exists());
    assert_fails(
        &scene,
        &ga(&["--explain", "/nonexistent-dir/e.svg"]),
        &out,
        &["nonexistent-dir"],
    );
    let png = dir.path().join("e.png");
    assert_fails(
        &scene,
        &["--method", "ga", "--explain", png.to_str().unwrap()],
        &out,
        &["the explanation is an SVG picture (FILE.svg)"],
    );
    assert!(!png.exists());
}

/// `--method ga` end to end on a small image: the image, the explanation and the JSON
/// statistics (per-phase times, fitness curves, evolved generators); bit-identical for 1
/// and 2 threads, with and without the gate (whose trials count costs, not seconds), and a
/// different seed changes it.
#[test]
fn ga_method_renders_deterministically_with_stats_and_explanation() {
    let dir = tempfile::tempdir().unwrap();
    let render = |threads: &str, seed: &str, gate: bool| {
        let out = dir.path().join(format!("ga{threads}-{seed}-{gate}.exr"));
        let explain = dir.path().join(format!("ga{threads}-{seed}-{gate}.svg"));
        let mut args = vec![
            "--explain",
            explain.to_str().unwrap(),
            "--method",
            "ga",
            "--threads",
            threads,
            "--seed",
            seed,
        ];
        args.extend_from_slice(&SMALL_GA);
        if !gate {
            args.push("--no-gate");
        }
        render_small_fig5(&out, &args);
        let svg = std::fs::read_to_string(&explain).expect("no explanation picture");
        assert!(
            svg.starts_with("<svg") && svg.contains("GA pixels") && svg.contains("<image"),
            "not an explanation picture"
        );
        let mut json = out.clone().into_os_string();
        json.push(".json");
        let stats: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
        (pixel_bits(&out), stats)
    };
    let (one, stats) = render("1", "1", false);
    let (two, _) = render("2", "1", false);
    assert_eq!(one, two, "the GA render depends on the thread count");
    let (other, _) = render("2", "7", false);
    assert_ne!(one, other, "the seed does not matter");
    let (gated_one, gated) = render("1", "1", true);
    let (gated_two, _) = render("2", "1", true);
    assert_eq!(
        gated_one, gated_two,
        "the gated render depends on the thread count"
    );
    assert!(
        gated["ga"]["pixels"][0]["trial"]["gain"].is_number(),
        "{}",
        gated["ga"]["pixels"][0]
    );

    let ga = &stats["ga"];
    let pixels = ga["pixels"].as_array().expect("GA pixels in the JSON");
    // 48×40 with a 16-pixel grid: 3×3 cells, all of them see the room.
    assert!(pixels.len() >= 9, "{} GA pixels", pixels.len());
    for p in pixels {
        assert_eq!(p["test_paths"], 3000);
        let weights = p["mixture"]["weights"].as_array().unwrap();
        let sum: f64 = weights.iter().map(|w| w.as_f64().unwrap()).sum();
        assert!((sum - 1.0).abs() < 1e-9, "weights sum to {sum}");
        assert!(p["mixture"]["generators"][0]["steps"].is_array());
    }
    let curves = ga["fitness_curves"].as_array().unwrap();
    assert!(!curves.is_empty());
    for c in curves {
        let history = c["history"].as_array().unwrap();
        // Warm-started pixels run half the generations.
        assert!(
            history.is_empty() || history.len() == 6 || history.len() == 3,
            "{c}"
        );
        // Elitism: the best V never increases.
        let best: Vec<f64> = history
            .iter()
            .map(|h| h["best"].as_f64().unwrap())
            .collect();
        assert!(best.windows(2).all(|w| w[1] <= w[0]), "{best:?}");
    }
    for phase in ["baseline", "ga", "render"] {
        assert!(stats["times_s"][phase].as_f64().unwrap() >= 0.0, "{phase}");
    }
    assert_eq!(ga["config"]["population"], 12);
    // Renamed with the settings' one names (was `grid`).
    assert_eq!(ga["plan"]["ga_grid"], 16);
}

/// Pruning: by default the JSON lists what was left out (low-variance cells, generator steps
/// past the needed depth); `--no-prune` runs the GA in every cell with every step.
#[test]
fn pruning_is_listed_and_can_be_turned_off() {
    let dir = tempfile::tempdir().unwrap();
    let run_scene = |scene: &str, extra: &[&str]| {
        let out = dir
            .path()
            .join(format!("p{}-{}.exr", extra.len(), scene.len()));
        let mut args = vec![
            "render",
            scene,
            "-o",
            out.to_str().unwrap(),
            "--method",
            "ga",
            "--width",
            "32",
            "--height",
            "32",
            "--ga-grid",
            "8",
            "--test-paths",
            "2000",
            "--population",
            "8",
            "--generations",
            "3",
            "--spp",
            "2",
            "--quiet",
            // Pruning alone: the gate's pilot would leave most GA pixels out on cbox.
            "--no-gate",
        ];
        args.extend_from_slice(extra);
        let output = genpath(&args);
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        let mut json = out.into_os_string();
        json.push(".json");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
        v["ga"].clone()
    };
    let run = |extra: &[&str]| run_scene("scenes/cbox/scene.toml", extra);
    let pruned = run(&[]);
    let full = run(&["--no-prune"]);
    let text = |v: &serde_json::Value| v["left_out"].to_string();
    assert!(
        text(&pruned).contains("grid cells whose pooled baseline relative variance"),
        "{}",
        text(&pruned)
    );
    assert!(text(&full).contains("pruning is off"), "{}", text(&full));
    assert_eq!(full["stats"]["low_variance_cells"], 0);
    // cbox at 32×32 has low-variance cells (its walls are well lit): fewer GA pixels.
    assert!(pruned["stats"]["low_variance_cells"].as_u64().unwrap() > 0);
    assert!(pruned["ga_pixels"].as_u64() < full["ga_pixels"].as_u64());
    // Without pruning every generator has max_bounces − 1 steps.
    let max_steps = |v: &serde_json::Value| -> Vec<u64> {
        v["pixels"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p["steps"].as_u64().unwrap())
            .collect()
    };
    assert!(
        max_steps(&full).iter().all(|&s| s == 4),
        "{:?}",
        max_steps(&full)
    );
    // Under a lone light facing a floor, a light-carrying path samples one direction at
    // most (the one that hits the light; none before next-event estimation at the floor):
    // pruned generators get that one step.
    let scene = dir.path().join("lamp.toml");
    std::fs::write(
        dir.path().join("lamp.mtl"),
        "newmtl white\nKd 0.8 0.8 0.8\nnewmtl light\nKd 0 0 0\nKe 10 10 10\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("lamp.obj"),
        "mtllib lamp.mtl\nusemtl white\nv -1 0 -1\nv -1 0 1\nv 1 0 1\nv 1 0 -1\nf 1 2 3 4\n\
         usemtl light\nv -0.2 1 -0.2\nv 0.2 1 -0.2\nv 0.2 1 0.2\nv -0.2 1 0.2\nf 5 6 7 8\n",
    )
    .unwrap();
    std::fs::write(
        &scene,
        "mesh = \"lamp.obj\"\n[camera]\norigin = [0.0, 0.8, 1.5]\ntarget = [0.0, 0.0, 0.0]\n\
         up = [0.0, 1.0, 0.0]\nfov_x_deg = 60.0\nwidth = 32\nheight = 32\n[render]\nmax_bounces = 5\n",
    )
    .unwrap();
    let scene = scene.to_str().unwrap();
    // Every cell keeps its GA pixel (prune variance 0); only steps are pruned.
    let pruned = run_scene(scene, &["--prune-variance", "0"]);
    let full = run_scene(scene, &["--prune-variance", "0", "--no-prune"]);
    let (pruned, full) = (max_steps(&pruned), max_steps(&full));
    assert!(
        pruned.len() >= 9 && pruned.len() == full.len(),
        "{pruned:?} {full:?}"
    );
    assert!(pruned.iter().all(|&s| s == 1), "{pruned:?}");
    assert!(full.iter().all(|&s| s == 4), "{full:?}");
}

/// `--accel embree` and `--accel bvh` give the same image up to the cross-check's tolerance
/// (a ray that the two back-ends resolve differently near a shared edge changes one path),
/// for every method; a different seed does not.
#[cfg(all(feature = "embree", feature = "obvhs"))]
#[test]
fn embree_and_bvh_renders_agree() {
    let dir = tempfile::tempdir().unwrap();
    let render = |method: &str, accel: &str, seed: &str| {
        let out = dir.path().join(format!("{method}-{accel}-{seed}.exr"));
        let output = genpath(&[
            "render",
            fig5().to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--method",
            method,
            "--accel",
            accel,
            "--seed",
            seed,
            "--width",
            "24",
            "--height",
            "24",
            "--spp",
            "8",
            "--test-paths",
            "2000",
            "--population",
            "8",
            "--generations",
            "4",
            "--ga-grid",
            "8",
            "--quiet",
        ]);
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        genpath::image::read_exr(&out).unwrap()
    };
    for method in ["pt", "srt", "ga", "ga-pt"] {
        let embree = render(method, "embree", "1");
        let bvh = render(method, "bvh", "1");
        let same = genpath::image::metrics::compare(&embree, &bvh)
            .unwrap()
            .relmse;
        let other = genpath::image::metrics::compare(&embree, &render(method, "bvh", "2"))
            .unwrap()
            .relmse;
        eprintln!("{method}: embree vs bvh relMSE {same:.2e}, other seed {other:.2e}");
        assert!(
            same < 1e-4,
            "{method}: embree and bvh differ: relMSE {same:.3e}"
        );
        assert!(
            other > 100.0 * same.max(1e-9),
            "{method}: another seed changes nothing"
        );
    }
}
