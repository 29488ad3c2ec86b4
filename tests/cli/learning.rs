//! Learning kept between processes (`learn --learn-dir`): `learn --shard K/N` split over
//! three jobs, one step per wave of the GA, then `learn` without `--shard`, builds the plan
//! that renders the in-process plan's image bit for bit (ga without the gate, whose first
//! and warm-started waves it splits; ga-pt with the gate, whose pilot waves it splits too);
//! a learn stopped by SIGTERM in the GA, or by SIGINT in the spatial guide's training, goes
//! on to the uninterrupted plan; kept files of another render, or damaged, are refused. A
//! reference's GA (`learn --for-reference`) splits the same way.

use super::*;
use std::process::Stdio;

/// fig5 at 8 spp with the small GA: ga without the gate at 48×40, and ga-pt with it (2
/// spatial passes) at 64×48, where its pilot passes (at 48×40 one of its seven pixels'
/// gains clears the margin one standard error below its estimate) so that the waves past it
/// split too.
fn methods() -> Vec<(&'static str, Vec<&'static str>)> {
    let small = [&SMALL[..6], &SMALL_GA[..]].concat();
    let spp = &SMALL[..2];
    let guide_size = ["--width", "64", "--height", "48"];
    vec![
        (
            "ga",
            [&["--method", "ga", "--no-gate"][..], &small].concat(),
        ),
        (
            "ga-pt",
            [
                &["--method", "ga-pt", "--spatial-passes", "2"][..],
                spp,
                &guide_size,
                &SMALL_GA,
            ]
            .concat(),
        ),
    ]
}

/// `genpath COMMAND fig5 -o OUT --quiet FLAGS…`'s arguments.
fn args(command: &str, out: &Path, flags: &[&str]) -> Vec<String> {
    let scene = fig5();
    let head = [
        command,
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--quiet",
    ];
    head.iter().chain(flags).map(|s| s.to_string()).collect()
}

/// Runs `genpath COMMAND fig5 -o OUT --quiet FLAGS…`.
fn run(command: &str, out: &Path, flags: &[&str]) -> Output {
    let args = args(command, out, flags);
    genpath(&args.iter().map(String::as_str).collect::<Vec<_>>())
}

fn ok(command: &str, out: &Path, flags: &[&str]) -> Output {
    let output = run(command, out, flags);
    assert!(
        output.status.success(),
        "{command} {flags:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

/// The wave files in `dir`, by name.
fn wave_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| d.map(|e| e.unwrap().path()).collect())
        .unwrap_or_default();
    files.sort();
    files
}

/// The GA split over three jobs, four steps (one per wave), then the plan built from the
/// waves: its render is the in-process render's, bit for bit. A job run again (a requeued
/// array task) changes nothing.
#[test]
fn a_split_ga_builds_the_in_process_plan() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (method, flags) in methods() {
        let inline = d.join(format!("{method}-inline.exr"));
        ok("render", &inline, &flags);
        let waves = d.join(format!("{method}.learning"));
        let plan = d.join(format!("{method}.plan"));
        let with_waves = [&flags[..], &["--learn-dir", waves.to_str().unwrap()]].concat();
        for step in 0..4 {
            for k in 0..3 {
                let shard = format!("{k}/3");
                let split = [&with_waves[..], &["--shard", &shard]].concat();
                ok("learn", &plan, &split);
                assert!(!plan.exists(), "{method}: a split job wrote the plan");
                if (step, k) == (1, 0) {
                    // Requeued: the same job again.
                    ok("learn", &plan, &split);
                }
            }
        }
        let files = wave_files(&waves);
        assert!(
            files.len() >= 4,
            "{method}: the waves were not split: {files:?}"
        );
        ok("learn", &plan, &with_waves);
        let saved = d.join(format!("{method}-saved.exr"));
        ok(
            "render",
            &saved,
            &[&flags[..], &["--plan", plan.to_str().unwrap()]].concat(),
        );
        assert_eq!(
            pixel_bits(&saved),
            pixel_bits(&inline),
            "{method}: the plan built from split waves renders another image"
        );
        assert!(waves.is_dir(), "--learn-dir DIR given: the folder stays");
    }
}

/// A reference's GA split too: `learn --for-reference --shard K/2`, four steps, evolves each
/// step's share of both halves' wave (each half in its own folder), and the plan built from
/// them renders the in-process reference bit for bit (ga-pt with the gate). The
/// must-reject twin: the build with another seed refuses the kept waves, naming the seed.
#[test]
fn a_split_ga_builds_the_in_process_reference_plan() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, flags) = methods().swap_remove(1);
    let inline = d.join("inline.exr");
    ok("reference", &inline, &flags);
    let waves = d.join("ref.learning");
    let plan = d.join("ref.plan");
    let learn = ["--for-reference", "--learn-dir", waves.to_str().unwrap()];
    let with_waves = [&flags[..], &learn].concat();
    for _step in 0..4 {
        for k in 0..2 {
            let shard = format!("{k}/2");
            ok(
                "learn",
                &plan,
                &[&with_waves[..], &["--shard", &shard]].concat(),
            );
            assert!(!plan.exists(), "a split job wrote the plan");
        }
    }
    // Both jobs evolved GA pixels of each half (at least of the gate's pilot, which may
    // close the GA).
    for half in ["half-1", "half-2"] {
        let files = wave_files(&waves.join(half));
        let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
        for job in [".0-of-2.bin", ".1-of-2.bin"] {
            assert!(names.iter().any(|n| n.ends_with(job)), "{half}: {names:?}");
        }
    }
    let other_seed = run(
        "learn",
        &plan,
        &[&with_waves[..], &["--seed", "2"]].concat(),
    );
    let err = String::from_utf8_lossy(&other_seed.stderr);
    assert!(
        !other_seed.status.success() && err.contains("seed"),
        "{err}"
    );
    assert!(!plan.exists());
    ok("learn", &plan, &with_waves);
    let saved = d.join("saved.exr");
    let with_plan = [&flags[..], &["--plan", plan.to_str().unwrap()]].concat();
    ok("reference", &saved, &with_plan);
    assert_eq!(
        pixel_bits(&saved),
        pixel_bits(&inline),
        "the reference plan built from split waves renders another reference"
    );
}

/// Starts `learn` of fig5 with `flags` into `plan`, waits until its learning folder holds a
/// file (its first chunk of GA pixels, or its first training pass, kept), then sends
/// `signal`: the ended process.
fn stop_mid_learning(plan: &Path, flags: &[&str], signal: &str) -> Output {
    let dir = plan.with_extension("plan.learning");
    let child = Command::new(env!("CARGO_BIN_EXE_genpath"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args("learn", plan, flags))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run genpath");
    let kept = || !wave_files(&dir).is_empty();
    signal_when(child, kept, signal, "first kept file")
}

/// SIGTERM mid-GA: exit 143, no plan, the finished GA pixels kept in the default learning
/// folder; the same command goes on to the uninterrupted plan's image and removes the
/// folder. The must-reject twin: the command with another seed refuses the kept waves,
/// naming the seed.
#[test]
fn a_stopped_learn_goes_on_to_the_uninterrupted_plan() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // fig5 at 96×80 with an 8-pixel grid on one thread: about 120 GA pixels, kept four at
    // a time.
    let flags: Vec<&str> = [
        &["--method", "ga", "--no-gate", "--threads", "1"][..],
        &["--spp", "8", "--width", "96", "--height", "80"],
        &["--ga-grid", "8", "--test-paths", "3000"],
        &["--population", "12", "--generations", "6"],
    ]
    .concat();
    let inline = d.join("inline.exr");
    ok("render", &inline, &flags);

    let plan = d.join("ga.plan");
    let waves = d.join("ga.plan.learning");
    let stopped = stop_mid_learning(&plan, &flags, "TERM");
    let err = String::from_utf8_lossy(&stopped.stderr);
    assert_eq!(stopped.status.code(), Some(143), "{err}");
    assert!(err.contains("stopped by SIGTERM in wave"), "{err}");
    assert!(!plan.exists(), "a stopped learn wrote the plan");
    assert!(!wave_files(&waves).is_empty());

    let other_seed = [&flags[..], &["--seed", "9"]].concat();
    let refused = run("learn", &plan, &other_seed);
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success(), "another seed took the waves");
    assert!(
        err.contains("learned for another render") && err.contains("seed"),
        "{err}"
    );
    assert!(!plan.exists());

    ok("learn", &plan, &flags);
    assert!(
        !waves.exists(),
        "the default learning folder stays after the plan"
    );
    let saved = d.join("saved.exr");
    ok(
        "render",
        &saved,
        &[&flags[..], &["--plan", plan.to_str().unwrap()]].concat(),
    );
    assert_eq!(pixel_bits(&saved), pixel_bits(&inline));
}

/// SIGINT in pg's training: exit 130, no plan, the finished passes kept; the same command
/// goes on to the plan of the uninterrupted command (the same image with `--plan`, training
/// samples included, bit for bit). The must-reject twin: the kept training of another
/// render (another size) is refused.
#[test]
fn a_stopped_training_goes_on_to_the_uninterrupted_guide() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // fig5 at 96×80, 1024 spp on one thread: training passes of 1, 2, … 256 samples per
    // pixel, the last ones seconds long.
    let flags: Vec<&str> = vec![
        "--method",
        "pg",
        "--threads",
        "1",
        "--spp",
        "1024",
        "--width",
        "96",
        "--height",
        "80",
    ];
    let plan = d.join("pg.plan");
    let kept = d.join("pg.plan.learning");
    let stopped = stop_mid_learning(&plan, &flags, "INT");
    let err = String::from_utf8_lossy(&stopped.stderr);
    assert_eq!(stopped.status.code(), Some(130), "{err}");
    assert!(err.contains("in the spatial guide's training"), "{err}");
    assert!(!plan.exists() && kept.join("training.bin").exists());

    let smaller = [&flags[..8], &["--height", "72"]].concat();
    let refused = run("learn", &plan, &smaller);
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success(), "another size took the training");
    assert!(
        err.contains("learned for another render") && err.contains("height"),
        "{err}"
    );

    ok("learn", &plan, &flags);
    let whole = d.join("whole.plan");
    ok("learn", &whole, &flags);
    let image = |plan: &Path, name: &str| {
        let out = d.join(name);
        ok(
            "render",
            &out,
            &[&flags[..], &["--plan", plan.to_str().unwrap()]].concat(),
        );
        pixel_bits(&out)
    };
    assert_eq!(image(&plan, "resumed.exr"), image(&whole, "whole.exr"));
}

/// A truncated wave file and a file that is not one are refused, naming the file; `pg`
/// refuses `--shard`; a time limit on the GA is refused (its waves are kept).
#[test]
fn damaged_wave_files_and_impossible_splits_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, flags) = methods().remove(0);
    let waves = d.join("w");
    let plan = d.join("ga.plan");
    let with_waves = [&flags[..], &["--learn-dir", waves.to_str().unwrap()]].concat();
    ok(
        "learn",
        &plan,
        &[&with_waves[..], &["--shard", "0/2"]].concat(),
    );
    let file = wave_files(&waves).remove(0);
    let bytes = std::fs::read(&file).unwrap();
    for (damage, needle) in [
        (bytes[..bytes.len() - 9].to_vec(), "truncated"),
        (
            b"not a wave file at all".to_vec(),
            "not a genpath GA wave file",
        ),
    ] {
        std::fs::write(&file, &damage).unwrap();
        let output = run("learn", &plan, &with_waves);
        let err = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{needle}: accepted");
        assert!(err.contains(needle) && err.contains("wave-"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(!plan.exists());
    }

    let pg = [
        "--method", "pg", "--spp", "8", "--width", "48", "--height", "40",
    ];
    let output = run("learn", &plan, &[&pg[..], &["--shard", "1/2"]].concat());
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success() && err.contains("pg learns no GA plan to split"),
        "{err}"
    );

    let timed = [&flags[..], &["--ga-time-limit", "5"]].concat();
    let output = run("learn", &d.join("timed.plan"), &timed);
    let err = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success() && err.contains("must not depend on time"),
        "{err}"
    );
}
