//! Stopped renders lose nothing: SIGTERM or SIGINT mid-render writes a shard file with the
//! true per-pixel sample counts and exits non-zero, `--checkpoint` writes one while the
//! render runs (so that even SIGKILL loses at most that much), and `--resume` continues
//! from either to the uninterrupted render's image, bit for bit; a file of another render
//! is refused.

use super::*;
use std::process::{Child, Stdio};

/// fig5 at 32×32, 1024 spp, one thread (`--method pt` unless `extra` names one): about a
/// second, four tiles one after another.
fn args<'a>(command: &'a str, out: &'a Path, extra: &[&'a str]) -> Vec<String> {
    let scene = fig5();
    let mut args: Vec<String> = [
        command,
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--spp",
        "1024",
        "--width",
        "32",
        "--height",
        "32",
        "--threads",
        "1",
        "--quiet",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    if !extra.contains(&"--method") {
        args.extend(["--method".to_string(), "pt".to_string()]);
    }
    args.extend(extra.iter().map(|s| s.to_string()));
    args
}

fn run(args: &[String]) -> Output {
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    genpath(&args)
}

fn spawn(args: &[String]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_genpath"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run genpath")
}

fn shard_file(image: &Path) -> PathBuf {
    let mut path = image.as_os_str().to_owned();
    path.push(".shard");
    PathBuf::from(path)
}

/// Starts `args` with a checkpoint after every tile, waits for the first checkpoint (a
/// quarter of the image rendered), then sends `signal` (a `kill` name): the ended process.
fn stop_mid_render(args: &[String], out: &Path, signal: &str) -> Output {
    let shard = shard_file(out);
    signal_when(spawn(args), || shard.exists(), signal, "first checkpoint")
}

/// The fewest and most samples any pixel holds in the shard file beside `image`, over its
/// layers.
fn counts(image: &Path) -> (u32, u32) {
    let (_, layers) = genpath::shard::file::read(&shard_file(image)).unwrap();
    let all = || layers.iter().flat_map(|l| l.counts.iter().copied());
    (all().min().unwrap(), all().max().unwrap())
}

fn assert_ok(output: &Output) {
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// SIGTERM (`render`) and SIGINT (`reference`): exit 128 + signal, no image, a shard with
/// some pixels done and some not; `--resume` ends with the uninterrupted image's bits, and
/// refuses another render's file (the must-reject twin: another seed).
#[test]
fn a_stopped_render_resumes_to_the_uninterrupted_image() {
    let dir = tempfile::tempdir().unwrap();
    for (command, signal, code, extra) in [
        ("render", "TERM", 143, &[][..]),
        ("render", "INT", 130, &["--method", "srt"][..]),
        ("reference", "INT", 130, &[][..]),
    ] {
        let whole = dir.path().join(format!("{command}-{signal}-whole.exr"));
        assert_ok(&run(&args(command, &whole, extra)));
        let out = dir.path().join(format!("{command}-{signal}.exr"));
        let every_tile = [extra, &["--checkpoint", "0"]].concat();
        let stopped = stop_mid_render(&args(command, &out, &every_tile), &out, signal);
        let err = String::from_utf8_lossy(&stopped.stderr);
        assert_eq!(stopped.status.code(), Some(code), "{command}: {err}");
        assert!(err.contains("--resume"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(
            !out.exists(),
            "{command}: an image was written by a stopped render"
        );
        // Samples per pixel (per half for a reference) of the whole render.
        let full = if command == "render" { 1024 } else { 512 };
        let (fewest, most) = counts(&out);
        assert!(
            fewest < full && most > 0,
            "{command}: counts {fewest}..{most}"
        );

        let file = shard_file(&out);
        let other_seed = [extra, &["--seed", "99", "--resume", file.to_str().unwrap()]].concat();
        let refused = run(&args(command, &out, &other_seed));
        let err = String::from_utf8_lossy(&refused.stderr);
        assert_eq!(refused.status.code(), Some(1), "{err}");
        assert!(
            err.contains("another render") && err.contains("seed"),
            "{err}"
        );
        assert!(!out.exists());

        let resume = [extra, &["--resume", file.to_str().unwrap()]].concat();
        assert_ok(&run(&args(command, &out, &resume)));
        assert_eq!(pixel_bits(&out), pixel_bits(&whole), "{command} {signal}");
        assert_eq!(counts(&out), (full, full));
    }
}

/// SIGKILL leaves only the last checkpoint: resumed from it, the render still ends with the
/// uninterrupted image; a shard of a split render, stopped and resumed, merges with the
/// others to the whole render.
#[test]
fn a_killed_render_resumes_from_its_checkpoint() {
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole.exr");
    assert_ok(&run(&args("render", &whole, &[])));

    let out = dir.path().join("killed.exr");
    let killed = stop_mid_render(&args("render", &out, &["--checkpoint", "0"]), &out, "KILL");
    assert!(!killed.status.success());
    let (fewest, _) = counts(&out);
    assert!(fewest < 1024);
    let file = shard_file(&out);
    assert_ok(&run(&args(
        "render",
        &out,
        &["--resume", file.to_str().unwrap()],
    )));
    assert_eq!(pixel_bits(&out), pixel_bits(&whole));

    // Shard 1 of 2 stopped and resumed, merged with shard 0.
    let part = |k: u32| dir.path().join(format!("s{k}.exr"));
    assert_ok(&run(&args("render", &part(0), &["--shard", "0/2"])));
    let one = ["--shard", "1/2", "--checkpoint", "0"];
    let stopped = stop_mid_render(&args("render", &part(1), &one), &part(1), "TERM");
    assert_eq!(stopped.status.code(), Some(143));
    let merged = dir.path().join("merged.exr");
    let shards = [shard_file(&part(0)), shard_file(&part(1))];
    let merge = |out: &Path| {
        run(&[
            "merge".to_string(),
            shards[0].to_str().unwrap().to_string(),
            shards[1].to_str().unwrap().to_string(),
            "-o".to_string(),
            out.to_str().unwrap().to_string(),
            "--complete".to_string(),
        ])
    };
    // Before the resume the shards do not hold every sample.
    let refused = merge(&merged);
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(
        !refused.status.success() && err.contains("--complete"),
        "{err}"
    );
    let resume = ["--shard", "1/2", "--resume", shards[1].to_str().unwrap()];
    assert_ok(&run(&args("render", &part(1), &resume)));
    assert_ok(&merge(&merged));
    assert_eq!(pixel_bits(&merged), pixel_bits(&whole));
}

/// A method that learns cannot be resumed without a plan file, and a missing file is named.
#[test]
fn resume_refuses_learning_methods_and_missing_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.exr");
    for (extra, needle) in [
        (
            &["--method", "pg", "--checkpoint", "1"][..],
            "--checkpoint: --method pg learns",
        ),
        (
            &["--method", "ga", "--resume", "x.shard"][..],
            "--resume: --method ga learns",
        ),
        (
            &["--resume", "/nonexistent/x.shard"][..],
            "/nonexistent/x.shard: no such file",
        ),
        (&["--checkpoint=-1"][..], "must be a number of seconds"),
    ] {
        let output = run(&args("render", &out, extra));
        let err = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{extra:?}: {err}");
        assert!(err.contains(needle), "{extra:?}: {err}");
        assert!(!out.exists());
    }
}

/// A method that learns resumes with a saved plan (`learn`, then `render --plan`): pg, whole
/// (its shard file holds the training samples too) and as shard 1 of 2, stopped by SIGTERM
/// after a checkpoint and resumed, ends with the in-process render's bits, and the shard
/// merges with shard 0 and the training shard to it.
#[test]
fn a_stopped_render_with_a_plan_resumes_to_the_uninterrupted_image() {
    let dir = tempfile::tempdir().unwrap();
    let pg = ["--method", "pg", "--spatial-passes", "3"];
    let whole = dir.path().join("whole.exr");
    assert_ok(&run(&args("render", &whole, &pg)));
    let plan = dir.path().join("pg.plan");
    assert_ok(&run(&args("learn", &plan, &pg)));
    let with: Vec<&str> = [&pg[..], &["--plan", plan.to_str().unwrap()]].concat();

    let out = dir.path().join("stopped.exr");
    let every_tile = [&with[..], &["--checkpoint", "0"]].concat();
    let stopped = stop_mid_render(&args("render", &out, &every_tile), &out, "TERM");
    assert_eq!(stopped.status.code(), Some(143));
    let (fewest, most) = counts(&out);
    // Every pixel holds the 7 training samples.
    assert!(
        (7..1024).contains(&fewest) && most > fewest,
        "{fewest}..{most}"
    );
    let file = shard_file(&out);
    let resume = [&with[..], &["--resume", file.to_str().unwrap()]].concat();
    assert_ok(&run(&args("render", &out, &resume)));
    assert_eq!(pixel_bits(&out), pixel_bits(&whole));

    let part = |k: u32| dir.path().join(format!("s{k}.exr"));
    let zero = [&with[..], &["--shard", "0/2"]].concat();
    assert_ok(&run(&args("render", &part(0), &zero)));
    let one = [&with[..], &["--shard", "1/2", "--checkpoint", "0"]].concat();
    let stopped = stop_mid_render(&args("render", &part(1), &one), &part(1), "TERM");
    assert_eq!(stopped.status.code(), Some(143));
    let file = shard_file(&part(1));
    let resume = [
        &with[..],
        &["--shard", "1/2", "--resume", file.to_str().unwrap()],
    ]
    .concat();
    assert_ok(&run(&args("render", &part(1), &resume)));
    let merged = dir.path().join("merged.exr");
    let files = [shard_file(&plan), shard_file(&part(0)), file];
    let mut merge = vec!["merge".to_string(), "--complete".to_string()];
    merge.extend(files.iter().map(|f| f.to_str().unwrap().to_string()));
    merge.extend(["-o".to_string(), merged.to_str().unwrap().to_string()]);
    assert_ok(&run(&merge));
    assert_eq!(pixel_bits(&merged), pixel_bits(&whole));
}

/// A reference of a method that learns resumes with a saved plan too (`learn
/// --for-reference`, then `reference --plan`): pg, stopped by SIGTERM after a checkpoint,
/// keeps both halves' training samples in its shard file (the half not yet rendered
/// starts from them) and, resumed, ends with the in-process reference's bits; the twin:
/// another seed's resume is refused.
#[test]
fn a_stopped_reference_with_a_plan_resumes_to_the_in_process_reference() {
    let dir = tempfile::tempdir().unwrap();
    let pg = ["--method", "pg", "--spatial-passes", "3"];
    let whole = dir.path().join("whole.exr");
    assert_ok(&run(&args("reference", &whole, &pg)));
    let plan = dir.path().join("pg.plan");
    let learn = [&pg[..], &["--for-reference"]].concat();
    assert_ok(&run(&args("learn", &plan, &learn)));
    let with: Vec<&str> = [&pg[..], &["--plan", plan.to_str().unwrap()]].concat();

    let out = dir.path().join("stopped.exr");
    let every_tile = [&with[..], &["--checkpoint", "0"]].concat();
    let stopped = stop_mid_render(&args("reference", &out, &every_tile), &out, "TERM");
    let err = String::from_utf8_lossy(&stopped.stderr);
    assert_eq!(stopped.status.code(), Some(143), "{err}");
    assert!(!out.exists());
    let (_, layers) = genpath::shard::file::read(&shard_file(&out)).unwrap();
    // Every pixel of both halves holds its 7 training samples, and not all 512.
    for layer in &layers {
        assert!(layer.fewest() >= 7, "a half lost its training samples");
    }
    let (fewest, most) = counts(&out);
    assert!(fewest < 512 && most > 7, "{fewest}..{most}");
    let file = shard_file(&out);
    let other_seed = [
        &with[..],
        &["--seed", "2", "--resume", file.to_str().unwrap()],
    ]
    .concat();
    let refused = run(&args("reference", &out, &other_seed));
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(
        !refused.status.success() && err.contains("seed") && !out.exists(),
        "{err}"
    );
    let resume = [&with[..], &["--resume", file.to_str().unwrap()]].concat();
    assert_ok(&run(&args("reference", &out, &resume)));
    assert_eq!(pixel_bits(&out), pixel_bits(&whole));
    assert_eq!(counts(&out), (512, 512));
}
