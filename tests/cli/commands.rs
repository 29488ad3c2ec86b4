//! `reference`, `sweep`, `bench`, `check` and `settings`, and the test-only method in every
//! command.

use super::*;

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
        "scene,method,spp,seconds,ga_seconds,relmse,mse,seed,efficiency,budget,bad_fraction"
    );
    assert_eq!(lines.len(), 1 + 3 * 2 * 2, "{csv}");
    for line in &lines[1..] {
        let fields: Vec<&str> = line.split(',').collect();
        assert_eq!(fields.len(), 11, "{line}");
        assert_eq!(fields[10], "0", "no bad pixels in these renders: {line}");
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

    // The comparison picture: the last budget's renders of the first repetition.
    let picture = dir.path().join("pic.svg");
    let out = sweep(&[
        "--methods",
        "pt,srt",
        "--budgets",
        "1,4",
        "--reps",
        "2",
        "--picture",
        picture.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let svg = std::fs::read_to_string(&picture).unwrap();
    // Per method its render and its error map, and the reference.
    assert_eq!(svg.matches("<image ").count(), 2 * 2 + 1, "{svg:.300}");
    assert!(
        svg.contains(", 4 spp, relMSE") && !svg.contains(", 1 spp,"),
        "{svg:.600}"
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("srt: relMSE") && stdout.contains("× pt's at equal time"),
        "{stdout}"
    );
    let plot = dir.path().join("sweep.svg");
    let plot = plot.to_str().unwrap();
    let shard = ["--picture", picture.to_str().unwrap(), "--shard", "0/2"];
    for (extra, needle) in [
        (
            vec!["--picture", plot],
            "that is where the sweep writes its plot",
        ),
        (shard.to_vec(), "a part of a sweep may not hold"),
    ] {
        let out = sweep(&extra);
        assert!(
            !out.status.success() && stderr(&out).contains(needle),
            "{extra:?}: {}",
            stderr(&out)
        );
    }

    for (extra, needle) in [
        (vec!["--methods", "pt,bdpt"], "unknown method `bdpt`"),
        (vec!["--methods", "ga:q=3"], "unknown setting `q`"),
        (vec!["--methods", "ga:m=many"], "ga.test_paths=many"),
        (vec!["--methods", "ga-pt:gate=maybe"], "gate.gate=maybe"),
        (vec!["--methods", "ga:pop=0"], "population"),
        (vec!["--methods", "pg:sp=0"], "spatial_passes 0 is not in"),
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
    // Every method that renders the scene's image (pt, srt, ga, ga-pt, pg, lt, and the
    // test-only ones where they are built; mixture needs a file), `pt` restricted to what
    // `lt` reaches (its reference) before the first method that cannot see through a delta
    // lobe, ga-pt without the spatial guide, and srt and ga with the end-only estimator.
    let names: Vec<&str> = report["methods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["method"].as_str().unwrap())
        .collect();
    use clap::ValueEnum;
    let methods = genpath::integrators::Method::value_variants().iter();
    let mut expected: Vec<String> = Vec::new();
    for m in methods.filter(|m| m.info().renders_the_scene && m.name() != "mixture") {
        let restricted = "pt:no-delta-first".to_string();
        if !m.info().sees_through_delta && !expected.contains(&restricted) {
            expected.push(restricted);
        }
        expected.push(m.name());
    }
    assert!(expected.len() >= 5, "{expected:?}");
    expected.extend(["ga-pt:spatial=0", "srt:nee=end", "ga:nee=end"].map(String::from));
    assert_eq!(names, expected);
    assert_eq!(report["pdf_bad"], 0);
    let out = genpath(&["check", "/nonexistent/scene.toml"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/scene.toml"));
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
        "[ga]\ntest_paths = 300\npopulation = 5\ngenerations = 2\n[plan]\nga_grid = 8\n[gate]\ngate = false\n",
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
    assert_eq!(json["ga"]["gate"]["gate"], false, "from --config");
    let tables = &json["method_settings"];
    assert_eq!(tables["gate"]["gate"], false);
    assert_eq!(tables["ga"]["population"], 6);
    assert_eq!(tables["spatial"]["spatial_guide"], true, "a default");
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

/// Every setting's range is the one its table declares, and it is enforced the same way,
/// in the same words, through its flag, `--set` and a `--config` file: a value just outside
/// it is refused by all three with `KEY VALUE is not in RANGE`, and nothing is written.
/// Every flag is tried on the command line; `--set` and `--config` read through the same
/// library calls for every setting, and on the command line for the first one.
#[test]
fn a_declared_range_is_enforced_by_flag_set_and_config() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.exr");
    let config = dir.path().join("settings.toml");
    let mut ranged = 0;
    for setting in genpath::integrators::settings::declarations() {
        let Some(range) = setting.range else {
            continue;
        };
        ranged += 1;
        // Just above the top where there is one, else just below the bottom.
        let value = match (range.hi.is_finite(), range.hi_open) {
            (true, true) => range.hi,
            (true, false) => range.hi + 1.0,
            (false, true) => f64::INFINITY,
            (false, false) => range.lo - 1.0,
        };
        assert!(
            !range.contains(value),
            "{}: {value} in {range}",
            setting.key
        );
        let message = format!("{} {value} is not in {range}", setting.key);
        let flag = format!("--{}={value}", setting.key.replace('_', "-"));
        let set = format!("{}={value}", setting.key);
        std::fs::write(
            &config,
            format!("[{}]\n{} = {value}\n", setting.table, setting.key),
        )
        .unwrap();
        let mut settings = genpath::integrators::Settings::default();
        let refused = settings.set(setting.key, &value.to_string()).unwrap_err();
        assert!(refused.to_string().contains(&message), "--set: {refused}");
        let toml = std::fs::read_to_string(&config).unwrap();
        let refused = genpath::integrators::Settings::from_toml(&toml, "t").unwrap_err();
        assert!(
            refused.to_string().contains(&message),
            "--config: {refused}"
        );
        let config = config.to_str().unwrap();
        assert_fails(&fig5(), &[flag.as_str()], &out, &[message.as_str()]);
        if ranged == 1 {
            for extra in [&["--set", set.as_str()][..], &["--config", config]] {
                assert_fails(&fig5(), extra, &out, &[message.as_str()]);
            }
        }
    }
    assert!(ranged >= 20, "only {ranged} settings declare a range");
    // Inside the range, the same three ways are accepted: the top of `--population`'s.
    let population = genpath::integrators::settings::declarations()
        .into_iter()
        .find(|s| s.key == "population")
        .and_then(|s| s.range)
        .unwrap();
    let top = population.hi.to_string();
    let mut settings = genpath::integrators::Settings::default();
    settings.set("population", &top).unwrap();
    assert_eq!(settings.ga.population as f64, population.hi);
    let toml = format!("[ga]\npopulation = {top}\n");
    let read = genpath::integrators::Settings::from_toml(&toml, "t").unwrap();
    assert_eq!(read.ga.population as f64, population.hi);
}
