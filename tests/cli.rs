//! The command line on good and bad input: clear errors, non-zero exit, no panic, no output
//! file; and determinism across thread counts.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs genpath in the repository's root, where relative paths such as
/// `scenes/fig5/scene.toml` resolve.
fn genpath(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_genpath"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .output()
        .expect("run genpath")
}

fn fig5() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fig5/scene.toml")
}

/// Runs a render that must fail; checks the exit code, that the message contains every
/// `needles` and that no image or JSON was written.
fn assert_fails(scene: &Path, extra: &[&str], out: &Path, needles: &[&str]) {
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--spp",
        "1",
        "--quiet",
    ];
    args.extend_from_slice(extra);
    let output = genpath(&args);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success(),
        "expected failure for {scene:?}, stderr: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    for needle in needles {
        assert!(stderr.contains(needle), "stderr lacks `{needle}`: {stderr}");
    }
    assert!(!out.exists(), "output written despite the error: {out:?}");
    let mut json = out.as_os_str().to_owned();
    json.push(".json");
    assert!(!Path::new(&json).exists(), "JSON written despite the error");
    let leftovers: Vec<_> = out
        .parent()
        .filter(|d| d.is_dir())
        .map(|d| {
            std::fs::read_dir(d)
                .unwrap()
                .filter_map(|e| e.ok())
                .map(|e| e.file_name())
                .collect()
        })
        .unwrap_or_default();
    assert!(
        !leftovers
            .iter()
            .any(|n| n.to_string_lossy().contains(".tmp")),
        "temp files left: {leftovers:?}"
    );
}

const GOOD_OBJ: &str = "mtllib m.mtl\nusemtl light\nv 0 1 0\nv 1 1 0\nv 0 1 1\nf 1 2 3\n\
                        usemtl white\nv -5 0 -5\nv -5 0 5\nv 5 0 5\nf 4 5 6\n";
const GOOD_MTL: &str = "newmtl light\nKe 1 1 1\nnewmtl white\nKd 0.5 0.5 0.5\n";

/// A small valid scene in `dir`, with any of its three files replaced.
fn scene_with(dir: &Path, toml: Option<&str>, obj: Option<&str>, mtl: Option<&str>) -> PathBuf {
    let default_toml = common::scene_toml("s.obj", [0.0, 3.0, 3.0], [0.0, 0.0, 0.0], 8);
    common::write_files(
        dir,
        &[
            ("s.toml", toml.unwrap_or(&default_toml)),
            ("s.obj", obj.unwrap_or(GOOD_OBJ)),
            ("m.mtl", mtl.unwrap_or(GOOD_MTL)),
        ],
    )
}

#[test]
fn a_valid_small_scene_renders_with_json_beside_it() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), None, None, None);
    let out = dir.path().join("img.exr");
    let output = genpath(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--spp",
        "2",
        "--quiet",
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(out.is_file());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("img.exr.json")).unwrap())
            .unwrap();
    assert_eq!(json["settings"]["spp"], 2);
    assert!(json["rays"]["total"].as_u64().unwrap() >= 8 * 8 * 2);
}

#[test]
fn malformed_toml() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), Some("mesh = \"s.obj\"\n[camera\n"), None, None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["s.toml", "line 2"],
    );
}

#[test]
fn unknown_toml_field() {
    let dir = tempfile::tempdir().unwrap();
    let toml =
        common::scene_toml("s.obj", [0.0, 3.0, 3.0], [0.0, 0.0, 0.0], 8) + "fov_y_deg = 3.0\n";
    let scene = scene_with(dir.path(), Some(&toml), None, None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["s.toml", "unknown field", "fov_y_deg"],
    );
}

#[test]
fn bad_camera_field() {
    let dir = tempfile::tempdir().unwrap();
    let toml = common::scene_toml("s.obj", [0.0, 3.0, 3.0], [0.0, 3.0, 3.0], 8);
    let scene = scene_with(dir.path(), Some(&toml), None, None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["s.toml", "camera.target"],
    );
}

#[test]
fn missing_obj() {
    let dir = tempfile::tempdir().unwrap();
    let toml = common::scene_toml("nothere.obj", [0.0, 3.0, 3.0], [0.0, 0.0, 0.0], 8);
    let scene = scene_with(dir.path(), Some(&toml), None, None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["nothere.obj", "cannot read"],
    );
}

#[test]
fn missing_mtl() {
    let dir = tempfile::tempdir().unwrap();
    let obj = GOOD_OBJ.replace("m.mtl", "gone.mtl");
    let scene = scene_with(dir.path(), None, Some(&obj), None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["gone.mtl", "cannot read"],
    );
}

#[test]
fn undefined_material() {
    let dir = tempfile::tempdir().unwrap();
    let obj = GOOD_OBJ.replace("usemtl white", "usemtl chalk");
    let scene = scene_with(dir.path(), None, Some(&obj), None);
    assert_fails(&scene, &[], &dir.path().join("o.exr"), &["s.obj", "chalk"]);
}

#[test]
fn nan_vertex() {
    let dir = tempfile::tempdir().unwrap();
    let obj = GOOD_OBJ.replace("v 1 1 0", "v 1 NaN 0");
    let scene = scene_with(dir.path(), None, Some(&obj), None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["s.obj:4", "non-finite", "NaN"],
    );
}

#[test]
fn malformed_obj_and_mtl_lines() {
    let dir = tempfile::tempdir().unwrap();
    let obj = GOOD_OBJ.replace("f 4 5 6", "f 4 5 9");
    let scene = scene_with(dir.path(), None, Some(&obj), None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["s.obj:11", "out of range"],
    );
    let mtl = GOOD_MTL.replace("Kd 0.5 0.5 0.5", "Kd 0.5 0.5");
    let scene = scene_with(dir.path(), None, None, Some(&mtl));
    assert_fails(&scene, &[], &dir.path().join("o.exr"), &["m.mtl:4", "Kd"]);
}

#[test]
fn no_emitter() {
    let dir = tempfile::tempdir().unwrap();
    let mtl = GOOD_MTL.replace("Ke 1 1 1", "Kd 0.2 0.2 0.2");
    let scene = scene_with(dir.path(), None, None, Some(&mtl));
    assert_fails(&scene, &[], &dir.path().join("o.exr"), &["no emitter"]);
}

#[test]
fn unwritable_output() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), None, None, None);
    // A regular file used as a directory: unwritable even for root.
    std::fs::write(dir.path().join("afile"), "x").unwrap();
    assert_fails(&scene, &[], &dir.path().join("afile/o.exr"), &["afile"]);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("missing_dir/o.exr"),
        &["missing_dir"],
    );
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.unknownformat"),
        &["o.unknownformat"],
    );
}

#[test]
fn impossible_flags() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), None, None, None);
    let out = dir.path().join("o.exr");
    assert_fails(&scene, &["--spp", "0"], &out, &["--spp"]);
    assert_fails(&scene, &["--threads", "0"], &out, &["--threads"]);
    assert_fails(
        &scene,
        &["--max-bounces", "100000"],
        &out,
        &["--max-bounces"],
    );
    assert_fails(&scene, &["--accel", "optix"], &out, &["--accel"]);
    assert_fails(&scene, &["--width", "999999999"], &out, &["--width"]);
}

/// The exact bits of every pixel of an EXR (OpenImageIO stamps a capture date into the
/// header, so the files' bytes differ between runs; their pixels must not).
fn pixel_bits(path: &Path) -> Vec<u32> {
    let image = genpath::image::read_exr(path).unwrap();
    image.pixels.iter().flatten().map(|c| c.to_bits()).collect()
}

/// `genpath render` of fig5 at 48×40 and 4 spp into `out`, quietly, with `extra` flags;
/// the render must succeed.
fn render_small_fig5(out: &Path, extra: &[&str]) {
    let scene = fig5();
    let base = [
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--spp",
        "4",
        "--width",
        "48",
        "--height",
        "40",
        "--quiet",
    ];
    let output = genpath(&[&base[..], extra].concat());
    assert!(
        output.status.success(),
        "{extra:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
}

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
    assert_eq!(json["times_s"]["spatial"], 0.0, "{json}");
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
    let explain = dir.path().join("e.png");
    let explain = explain.to_str().unwrap();
    assert_fails(
        &scene,
        &["--explain", explain],
        &out,
        &["--explain is only used with --method ga or ga-pt"],
    );
    assert!(!Path::new(explain).exists());
    assert_fails(
        &scene,
        &ga(&["--explain", "/nonexistent-dir/e.png"]),
        &out,
        &["nonexistent-dir"],
    );
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
        let explain = dir.path().join(format!("ga{threads}-{seed}-{gate}.png"));
        let mut args = vec![
            "--explain",
            explain.to_str().unwrap(),
            "--method",
            "ga",
            "--ga-grid",
            "16",
            "--test-paths",
            "3000",
            "--population",
            "12",
            "--generations",
            "6",
            "--threads",
            threads,
            "--seed",
            seed,
        ];
        if !gate {
            args.push("--no-gate");
        }
        render_small_fig5(&out, &args);
        assert!(explain.exists(), "no explanation image");
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

/// `genpath reference`: an EXR, two halves with different seeds, and a noise estimate that
/// matches an independent check (a second reference with another seed).
#[test]
fn reference_has_its_own_noise_estimate() {
    let dir = tempfile::tempdir().unwrap();
    let make = |name: &str, seed: &str| {
        let out = dir.path().join(name);
        let output = genpath(&[
            "reference",
            fig5().to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--spp",
            "64",
            "--width",
            "24",
            "--height",
            "24",
            "--seed",
            seed,
            "--quiet",
        ]);
        assert!(
            output.status.success(),
            "{}",
            String::from_utf8_lossy(&output.stderr)
        );
        let mut json = out.clone().into_os_string();
        json.push(".json");
        let stats: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
        (out, stats["reference"]["relmse_estimate"].as_f64().unwrap())
    };
    let (a, estimate_a) = make("a.exr", "1");
    let (b, estimate_b) = make("b.exr", "2");
    // Two independent references differ by about the sum of their own errors.
    let a = genpath::image::read_exr(&a).unwrap();
    let b = genpath::image::read_exr(&b).unwrap();
    let between = genpath::image::metrics::compare(&a, &b).unwrap().relmse;
    let ratio = between / (estimate_a + estimate_b);
    assert!(
        (0.6..1.6).contains(&ratio),
        "between {between:.3e}, estimates {estimate_a:.3e} + {estimate_b:.3e}"
    );
    // References are float images.
    let output = genpath(&[
        "reference",
        fig5().to_str().unwrap(),
        "-o",
        dir.path().join("r.png").to_str().unwrap(),
    ]);
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("must be an EXR"));
}

/// `genpath sweep`: a CSV row per method × budget × repetition and an SVG plot; clear errors
/// for unknown methods and keys, a reference of the wrong size, and impossible budgets.
#[test]
fn sweep_writes_csv_and_plot() {
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("ref.exr");
    let size = ["--width", "16", "--height", "12", "--quiet"];
    let run = |args: &[&str]| genpath(&[args, &size[..]].concat());
    let out = run(&[
        "reference",
        fig5().to_str().unwrap(),
        "-o",
        reference.to_str().unwrap(),
        "--spp",
        "64",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let prefix = dir.path().join("sweep");
    let scene = fig5();
    let sweep = |extra: &[&str]| {
        let mut args = vec![
            "sweep",
            scene.to_str().unwrap(),
            "--ref",
            reference.to_str().unwrap(),
            "-o",
            prefix.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        run(&args)
    };
    let out = sweep(&[
        "--methods",
        "pt,srt,ga:m=500:pop=6:gen=3:grid=8",
        "--budgets",
        "1,4",
        "--reps",
        "2",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = std::fs::read_to_string(dir.path().join("sweep.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "scene,method,spp,seconds,ga_seconds,relmse,mse,seed,efficiency,budget"
    );
    assert_eq!(lines.len(), 1 + 3 * 2 * 2, "{csv}");
    for line in &lines[1..] {
        let fields: Vec<&str> = line.split(',').collect();
        assert_eq!(fields.len(), 10, "{line}");
        assert_eq!(fields[0], "fig5");
        let relmse: f64 = fields[5].parse().unwrap();
        assert!(relmse.is_finite() && relmse > 0.0, "{line}");
        let (seconds, ga): (f64, f64) = (fields[3].parse().unwrap(), fields[4].parse().unwrap());
        assert!(seconds >= ga, "{line}");
        if fields[1].starts_with("ga") {
            assert!(ga > 0.0, "GA time left out: {line}");
        }
    }
    let svg = std::fs::read_to_string(dir.path().join("sweep.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") && svg.contains("relMSE"),
        "{svg:.200}"
    );

    for (extra, needle) in [
        (vec!["--methods", "pt,bdpt"], "unknown method `bdpt`"),
        (vec!["--methods", "ga:q=3"], "unknown setting `q`"),
        (vec!["--methods", "ga:m=many"], "ga.test_paths=many"),
        (vec!["--methods", "ga-pt:gate=maybe"], "plan.gate=maybe"),
        (vec!["--methods", "ga:pop=0"], "population"),
        (vec!["--methods", "pg:sp=0"], "spatial guide passes"),
        (vec!["--budgets", "0"], "--budgets"),
        (vec!["--budgets", "1.5"], "--budgets"),
        (vec!["--budgets=-1", "--time"], "--budgets"),
        (vec!["--methods", "mixture"], "--generators"),
    ] {
        let out = sweep(&extra);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains(needle),
            "{extra:?}: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    // A reference of another size.
    let out = genpath(&[
        "sweep",
        fig5().to_str().unwrap(),
        "--ref",
        reference.to_str().unwrap(),
        "-o",
        prefix.to_str().unwrap(),
        "--width",
        "8",
        "--height",
        "8",
        "--quiet",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("16×12"),
        "{stderr}"
    );
}

/// `genpath bench` prints its tables and writes every figure to JSON.
#[test]
fn bench_reports_rates_and_scaling() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("bench.json");
    let out = genpath(&[
        "bench",
        fig5().to_str().unwrap(),
        "--rays",
        "32",
        "--passes",
        "1",
        "--threads",
        "1,2",
        "--spp",
        "1",
        "--json",
        json.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("individual evaluations/s"), "{stdout}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    let rays = v["rays"].as_array().unwrap();
    // Two ray sets per built back-end.
    assert!(rays.len() == 2 || rays.len() == 4, "{rays:?}");
    for r in rays {
        for q in [
            "closest_single",
            "closest_packet",
            "occluded_single",
            "occluded_packet",
        ] {
            assert!(r["mrays_per_s"][q].as_f64().unwrap() > 0.0, "{r}");
        }
    }
    assert!(v["fitness_evaluations_per_s"].as_f64().unwrap() > 0.0);
    assert_eq!(v["scaling"]["runs"].as_array().unwrap().len(), 2);
    let out = genpath(&["bench", "/nonexistent/scene.toml"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/scene.toml"));
}

/// `genpath check` passes on a shipped scene and writes its report; a missing scene is an
/// error.
#[test]
fn check_passes_on_fig5() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("check.json");
    let out = genpath(&[
        "check",
        fig5().to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "16",
        "--json",
        json.to_str().unwrap(),
        "--quiet",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("check passed"), "{stdout}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    // Every method of the list (pt, srt, ga, ga-pt, pg, and nee-only where the test-only
    // method is built), and ga-pt without the spatial guide.
    let names: Vec<&str> = report["methods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["method"].as_str().unwrap())
        .collect();
    let mut expected = vec!["pt", "srt", "ga", "ga-pt", "pg"];
    if cfg!(feature = "testing") {
        expected.push("nee-only");
    }
    expected.push("ga-pt:spatial=0");
    assert_eq!(names, expected);
    assert_eq!(report["pdf_bad"], 0);
    let out = genpath(&["check", "/nonexistent/scene.toml"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/scene.toml"));
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

/// The seam: a method added as one file and one line (`nee-only`, feature `testing`)
/// is run by render, reference, sweep, check (which also compares its image mean with
/// pt's) and bench, and each names it in its output.
#[cfg(feature = "testing")]
#[test]
fn a_test_only_method_runs_in_every_command() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cbox/scene.toml");
    let scene = scene.to_str().unwrap();
    let small = ["--width", "24", "--height", "24", "--quiet"];
    let run = |args: &[&str]| {
        let out = genpath(&[args, &small].concat());
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(out.status.success(), "genpath {args:?}: {text}");
        text
    };
    let image = p("bsdf.exr");
    let reference = p("ref.exr");
    run(&[
        "render", scene, "--method", "nee-only", "--spp", "8", "-o", &image,
    ]);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{image}.json")).unwrap()).unwrap();
    assert_eq!(json["settings"]["method"], "nee-only");
    run(&[
        "reference",
        scene,
        "--method",
        "nee-only",
        "--spp",
        "8",
        "-o",
        &reference,
    ]);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{reference}.json")).unwrap())
            .unwrap();
    assert_eq!(json["settings"]["method"], "nee-only");
    assert!(json["reference"]["relmse_estimate"].as_f64().unwrap() > 0.0);
    let sweep = run(&[
        "sweep",
        scene,
        "--ref",
        &reference,
        "--methods",
        "pt,nee-only",
        "--budgets",
        "2",
        "-o",
        &p("sweep"),
    ]);
    assert!(sweep.contains("| nee-only |"), "{sweep}");
    let check = run(&["check", scene, "--spp", "8", "--json", &p("check.json")]);
    assert!(check.contains("| nee-only |"), "{check}");
    let out = genpath(&[
        "bench",
        scene,
        "--rays",
        "8",
        "--passes",
        "1",
        "--threads",
        "1",
        "--spp",
        "1",
        "--method",
        "nee-only",
        "--json",
        &p("bench.json"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("bench.json")).unwrap()).unwrap();
    assert_eq!(json["scaling"]["method"], "nee-only");
}

/// A setting's one name is refused where no table has it: in `--config`, in `--set` and in a
/// sweep's method key; nothing is written.
#[test]
fn unknown_settings_are_refused_everywhere() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("settings.toml");
    std::fs::write(&config, "[ga]\ntest_pathz = 10\n").unwrap();
    let out = dir.path().join("out.exr");
    let config = config.to_str().unwrap();
    assert_fails(
        &fig5(),
        &["--config", config],
        &out,
        &["settings.toml", "test_pathz"],
    );
    assert_fails(
        &fig5(),
        &["--set", "test_pathz=10"],
        &out,
        &["unknown setting `test_pathz`"],
    );
    assert_fails(
        &fig5(),
        &["--set", "plan.test_paths=10"],
        &out,
        &["plan.test_paths"],
    );
    assert_fails(&fig5(), &["--set", "test_paths"], &out, &["not key=value"]);
    let reference = dir.path().join("ref.exr");
    let small = ["--width", "8", "--height", "6", "--quiet"];
    let reference = reference.to_str().unwrap();
    let made = genpath(
        &[
            &[
                "reference",
                fig5().to_str().unwrap(),
                "--spp",
                "2",
                "-o",
                reference,
            ][..],
            &small,
        ]
        .concat(),
    );
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let prefix = dir.path().join("s");
    let sweep = genpath(
        &[
            &["sweep", fig5().to_str().unwrap(), "--ref", reference][..],
            &[
                "--methods",
                "ga:test_pathz=10",
                "-o",
                prefix.to_str().unwrap(),
            ],
            &small,
        ]
        .concat(),
    );
    let stderr = String::from_utf8_lossy(&sweep.stderr);
    assert!(
        !sweep.status.success() && stderr.contains("unknown setting `test_pathz`"),
        "{stderr}"
    );
    assert!(!dir.path().join("s.csv").exists());
}

/// Settings apply in order: defaults, `--config`, the flags given, `--set`; the JSON records
/// each by its one name.
#[test]
fn settings_apply_config_then_flags_then_set() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("settings.toml");
    std::fs::write(
        &config,
        "[ga]\ntest_paths = 300\npopulation = 5\ngenerations = 2\n[plan]\nga_grid = 8\ngate = false\n",
    )
    .unwrap();
    let out = dir.path().join("ga.exr");
    render_small_fig5(
        &out,
        &[
            "--method",
            "ga",
            "--config",
            config.to_str().unwrap(),
            "--population",
            "4",
            "--set",
            "generations=3",
            "--set",
            "ga.population=6",
        ],
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("ga.exr.json")).unwrap())
            .unwrap();
    let (ga, plan) = (&json["ga"]["config"], &json["ga"]["plan"]);
    assert_eq!(ga["test_paths"], 300, "from --config");
    assert_eq!(ga["generations"], 3, "--set after --config");
    assert_eq!(ga["population"], 6, "--set after the flag");
    assert_eq!(plan["ga_grid"], 8);
    assert_eq!(plan["gate"], false);
}

/// docs/settings.md is `genpath settings`'s output (regenerate it with
/// `genpath settings > docs/settings.md`), and `settings --toml`'s defaults read back as a
/// `--config` file.
#[test]
fn settings_documentation_is_generated_from_the_code() {
    let out = genpath(&["settings"]);
    assert!(out.status.success());
    let docs =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/settings.md"))
            .unwrap();
    assert!(
        String::from_utf8_lossy(&out.stdout) == docs,
        "docs/settings.md is stale: run `genpath settings > docs/settings.md`"
    );
    assert!(
        docs.contains("| `ga.test_paths` | `--test-paths` | `10000` |"),
        "{docs}"
    );
    let toml = genpath(&["settings", "--toml"]);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("defaults.toml");
    std::fs::write(&file, &toml.stdout).unwrap();
    render_small_fig5(
        &dir.path().join("a.exr"),
        &["--config", file.to_str().unwrap()],
    );
}
