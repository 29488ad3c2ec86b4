//! `genpath learn` and `render --plan`: a render with a saved plan is the render that learns
//! in-process, bit for bit (ga, pg, ga-pt); shards of it merged with the learn job's
//! training shard are that render too, and a merge without the training shard is partial;
//! plans of other renders, of other methods, and damaged plan files are refused. The same
//! for a reference (`learn --for-reference`, `reference --plan`): its shards with the
//! training shard merge to the in-process reference and its noise estimate, bit for bit.

use super::*;
use std::process::Output;

/// Each method that learns with small settings: ga without the gate (so that its GA pixels
/// render), whose image keeps its baseline's 4 of the 8 samples per pixel; pg and ga-pt
/// with 2 spatial passes (3 of them).
fn methods() -> Vec<(&'static str, Vec<&'static str>)> {
    vec![
        (
            "ga",
            [
                &[
                    "--method",
                    "ga",
                    "--no-gate",
                    "--baseline-keep-ratio",
                    "inf",
                ][..],
                &SMALL_GA,
            ]
            .concat(),
        ),
        ("pg", vec!["--method", "pg", "--spatial-passes", "2"]),
        (
            "ga-pt",
            [
                &["--method", "ga-pt", "--no-gate", "--spatial-passes", "2"][..],
                &SMALL_GA,
            ]
            .concat(),
        ),
    ]
}

/// `genpath COMMAND fig5 -o dir/name` at [`SMALL`] with `extra` flags (which replace
/// [`SMALL`]'s of the same name).
fn run_in(command: &str, dir: &Path, name: &str, extra: &[&str]) -> (PathBuf, Output) {
    let out = dir.join(name);
    let scene = fig5();
    let mut args = vec![
        command,
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    for pair in SMALL[..6].chunks(2) {
        if !extra.contains(&pair[0]) {
            args.extend_from_slice(pair);
        }
    }
    args.push("--quiet");
    args.extend_from_slice(extra);
    let output = genpath(&args);
    (out, output)
}

/// As [`run_in`], which must succeed: the output's path.
fn ok_in(command: &str, dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let (out, output) = run_in(command, dir, name, extra);
    assert!(
        output.status.success(),
        "{command} {extra:?}: {}",
        stderr(&output)
    );
    out
}

/// As [`run_in`], which must fail naming every one of `needles`, writing no output.
fn fails_in(command: &str, dir: &Path, extra: &[&str], needles: &[&str]) {
    let (out, output) = run_in(command, dir, "refused.exr", extra);
    let err = stderr(&output);
    assert!(!output.status.success(), "{extra:?} succeeded");
    assert!(!err.contains("panicked"), "panic: {err}");
    for needle in needles {
        assert!(
            err.contains(needle),
            "{extra:?}: stderr lacks `{needle}`: {err}"
        );
    }
    assert!(!out.exists(), "{extra:?}: output written despite the error");
}

/// `<path>.<suffix>`.
fn beside(path: &Path, suffix: &str) -> PathBuf {
    let mut p = path.as_os_str().to_owned();
    p.push(suffix);
    PathBuf::from(p)
}

fn json_of(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(beside(path, ".json")).unwrap()).unwrap()
}

fn merge(files: &[PathBuf], out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["merge"];
    args.extend(files.iter().map(|p| p.to_str().unwrap()));
    args.extend_from_slice(&["-o", out.to_str().unwrap(), "--quiet"]);
    args.extend_from_slice(extra);
    genpath(&args)
}

/// For ga, pg and ga-pt: the render with a saved plan has the in-process render's bits; the
/// plan's training samples (ga's baseline, pg's and ga-pt's passes) are in the training
/// shard;
/// the JSON names the plan file and its hash and leaves the pixels' mixtures to the file.
/// Shards 0/2 and 1/2 rendered with the plan, merged with the training shard, are the
/// in-process render bit for bit; without the training shard the merge is partial (and
/// refused with `--complete`).
#[test]
fn saved_plans_render_and_shard_to_the_in_process_render_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (method, flags) in methods() {
        let inline = ok_in("render", d, &format!("{method}-inline.exr"), &flags);
        let plan = ok_in("learn", d, &format!("{method}.plan"), &flags);
        // Every one keeps samples of preparing: ga its plan's baseline, pg and ga-pt their
        // spatial training passes'.
        let training = beside(&plan, ".shard");
        assert!(training.exists(), "{method}: no training shard");
        let with = [&flags[..], &["--plan", plan.to_str().unwrap()]].concat();
        let saved = ok_in("render", d, &format!("{method}-saved.exr"), &with);
        assert_eq!(
            pixel_bits(&saved),
            pixel_bits(&inline),
            "{method}: the saved plan's render differs from the in-process render"
        );
        let json = json_of(&saved);
        let learned = json_of(&plan);
        assert_eq!(json["plan_file"]["hash"], learned["plan_file"]["hash"]);
        assert!(json["plan_file"]["file"]
            .as_str()
            .unwrap()
            .ends_with(".plan"));
        if method != "pg" {
            assert!(json["ga"]["pixels"].is_string(), "{method}: {}", json["ga"]);
            assert!(json_of(&inline)["ga"]["pixels"].is_array());
        }

        let mut files: Vec<PathBuf> = (0..2)
            .map(|k| {
                let shard = format!("{k}/2");
                let name = format!("{method}-s{k}.exr");
                beside(
                    &ok_in(
                        "render",
                        d,
                        &name,
                        &[&with[..], &["--shard", &shard]].concat(),
                    ),
                    ".shard",
                )
            })
            .collect();
        let merged = d.join(format!("{method}-merged.exr"));
        let output = merge(&files, &merged, &["--complete"]);
        let err = stderr(&output);
        assert!(
            !output.status.success() && err.contains("training shard"),
            "{err}"
        );
        assert!(!merged.exists());
        let partial = merge(&files, &merged, &[]);
        assert!(partial.status.success(), "{}", stderr(&partial));
        files.push(training.clone());
        // Twice the training shard is refused.
        let twice = [&files[..], std::slice::from_ref(&training)].concat();
        let output = merge(&twice, &d.join("twice.exr"), &[]);
        assert!(stderr(&output).contains("both hold the learn job's training samples"));
        let output = merge(&files, &merged, &["--complete"]);
        assert!(output.status.success(), "{method}: {}", stderr(&output));
        assert_eq!(
            pixel_bits(&merged),
            pixel_bits(&inline),
            "{method}: the merged shards differ from the in-process render"
        );
    }
}

/// A plan learned for another render is refused naming what differs: seed, size, spp, a
/// setting, the scene, the method; and `--plan` of a method that learns nothing, `learn` of
/// one, and a split into more shards than samples after the training.
#[test]
fn plans_of_other_renders_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, ga) = methods().swap_remove(0);
    let plan = ok_in("learn", d, "ga.plan", &ga);
    let with =
        |extra: &[&'static str]| [&ga[..], &["--plan", plan.to_str().unwrap()], extra].concat();
    fails_in(
        "render",
        d,
        &with(&["--seed", "2"]),
        &["ga.plan", "another render", "seed is 1 there and 2 here"],
    );
    fails_in(
        "render",
        d,
        &with(&["--width", "32"]),
        &["width is 48 there and 32 here"],
    );
    fails_in(
        "render",
        d,
        &with(&["--spp", "16"]),
        &["spp is 8 there and 16 here"],
    );
    fails_in(
        "render",
        d,
        &with(&["--set", "test_paths=2000"]),
        &["settings.ga.test_paths"],
    );
    // Another scene (cbox), at the same size.
    let cbox = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cbox/scene.toml");
    let out = d.join("cbox.exr");
    let mut args = vec![
        "render",
        cbox.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(&SMALL);
    let flags = with(&[]);
    args.extend_from_slice(&flags);
    let output = genpath(&args);
    assert!(
        !output.status.success() && stderr(&output).contains("scene is"),
        "{}",
        stderr(&output)
    );
    assert!(!out.exists());
    let pg = [
        "--method",
        "pg",
        "--spatial-passes",
        "2",
        "--plan",
        plan.to_str().unwrap(),
    ];
    fails_in(
        "render",
        d,
        &pg,
        &["method is \"ga\" there and \"pg\" here"],
    );
    let pt = ["--method", "pt", "--plan", plan.to_str().unwrap()];
    fails_in("render", d, &pt, &["--method pt learns nothing"]);
    fails_in(
        "learn",
        d,
        &["--method", "srt"],
        &["--method srt learns nothing"],
    );
    let (_, pg) = methods().swap_remove(1);
    let pg_plan = ok_in("learn", d, "pg.plan", &pg);
    let split = [
        &pg[..],
        &["--plan", pg_plan.to_str().unwrap(), "--shard", "0/6"],
    ]
    .concat();
    fails_in(
        "render",
        d,
        &split,
        &["5 samples per pixel left after the plan's 3 training samples"],
    );
}

/// Damaged plan files are refused, naming the file: truncated, a byte flipped, a file of
/// another kind, a missing file.
#[test]
fn damaged_plan_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, pg) = methods().swap_remove(1);
    let plan = ok_in("learn", d, "pg.plan", &pg);
    let bytes = std::fs::read(&plan).unwrap();
    let damaged = |name: &str, bytes: &[u8]| {
        let path = d.join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    };
    let mut flipped = bytes.clone();
    let middle = flipped.len() / 2;
    flipped[middle] ^= 0x10;
    let shard = beside(&plan, ".shard");
    let missing = d.join("missing.plan");
    for (path, needle) in [
        (
            damaged("cut.plan", &bytes[..bytes.len() - 100]),
            "truncated or padded",
        ),
        (
            damaged("long.plan", &[&bytes[..], b"x"].concat()),
            "truncated or padded",
        ),
        (damaged("flip.plan", &flipped), "corrupted"),
        (shard, "not a genpath plan file"),
        (missing.clone(), "missing.plan"),
    ] {
        let with = [&pg[..], &["--plan", path.to_str().unwrap()]].concat();
        fails_in(
            "render",
            d,
            &with,
            &[path.file_name().unwrap().to_str().unwrap(), needle],
        );
    }
}

/// pg, and ga-pt with its GA, for a reference of 16 spp (two halves of 8, each with 3
/// training samples per pixel).
fn reference_methods() -> Vec<(&'static str, Vec<&'static str>)> {
    methods()
        .into_iter()
        .filter(|(method, _)| *method != "ga")
        .map(|(method, flags)| (method, [&flags[..], &["--spp", "16"]].concat()))
        .collect()
}

/// For pg and ga-pt: `learn --for-reference` learns each half of a reference as the
/// reference does; `reference --plan` is the in-process reference bit for bit, and so are
/// its shards 0/2 and 1/2 merged with the learn job's training shard (two layers, one per
/// half), the JSON's noise estimate included. The twins: the shards merged without the
/// training shard, and one shard with it, are other images.
#[test]
fn reference_plans_shard_and_merge_to_the_in_process_reference_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (method, flags) in reference_methods() {
        let inline = ok_in("reference", d, &format!("{method}-inline.exr"), &flags);
        let learn = [&flags[..], &["--for-reference"]].concat();
        let plan = ok_in("learn", d, &format!("{method}-ref.plan"), &learn);
        let training = beside(&plan, ".shard");
        let (header, layers) = genpath::shard::file::read(&training).unwrap();
        assert_eq!(header.identity.command, "reference");
        assert_eq!(layers.len(), 2, "{method}: a training layer per half");
        assert!(layers.iter().all(|l| l.fewest() == 3), "{method}");
        let with = [&flags[..], &["--plan", plan.to_str().unwrap()]].concat();
        let saved = ok_in("reference", d, &format!("{method}-saved.exr"), &with);
        assert_eq!(
            pixel_bits(&saved),
            pixel_bits(&inline),
            "{method}: saved plan"
        );
        let noise = json_of(&inline)["reference"].clone();
        assert!(noise["relmse_estimate"].as_f64().unwrap() > 0.0, "{noise}");
        assert_eq!(json_of(&saved)["reference"], noise, "{method}");
        assert_eq!(
            json_of(&saved)["plan_file"]["hash"],
            json_of(&plan)["plan_file"]["hash"]
        );

        let shards: Vec<PathBuf> = (0..2)
            .map(|k| {
                let spec = format!("{k}/2");
                let shard = [&with[..], &["--shard", &spec]].concat();
                beside(
                    &ok_in("reference", d, &format!("{method}-s{k}.exr"), &shard),
                    ".shard",
                )
            })
            .collect();
        let merged = d.join(format!("{method}-merged.exr"));
        let all = [&shards[..], std::slice::from_ref(&training)].concat();
        let output = merge(&all, &merged, &["--complete"]);
        assert!(output.status.success(), "{method}: {}", stderr(&output));
        assert_eq!(pixel_bits(&merged), pixel_bits(&inline), "{method}: merged");
        assert_eq!(
            json_of(&merged)["reference"],
            noise,
            "{method}: noise estimate"
        );

        // The twins: without the training shard, or without a shard, another image.
        let partial = d.join(format!("{method}-partial.exr"));
        let output = merge(&shards, &partial, &["--complete"]);
        assert!(!output.status.success() && stderr(&output).contains("training shard"));
        assert!(merge(&shards, &partial, &[]).status.success());
        assert_ne!(pixel_bits(&partial), pixel_bits(&inline), "{method}");
        let one = [shards[0].clone(), training.clone()];
        assert!(merge(&one, &partial, &[]).status.success());
        assert_ne!(pixel_bits(&partial), pixel_bits(&inline), "{method}");
    }
}

/// A reference refuses a plan learned for another reference (another seed, another --spp)
/// or for a render, and a render refuses a reference's plan, each naming what differs;
/// `reference --shard` of a method that learns needs a plan. A learning folder's file of
/// one half is refused by the other (its identity names the half).
#[test]
fn reference_plans_of_other_renders_and_halves_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (_, pg) = reference_methods().swap_remove(0);
    let folder = d.join("learning");
    let keep = ["--for-reference", "--learn-dir", folder.to_str().unwrap()];
    let plan = ok_in("learn", d, "ref.plan", &[&pg[..], &keep].concat());
    let render_plan = ok_in("learn", d, "render.plan", &pg);
    // pg's flags but for --spp 32 where `extra` names --spp.
    let with = |plan: &Path, extra: &[&'static str]| -> Vec<String> {
        let plan = ["--plan", plan.to_str().unwrap()];
        let flags = pg
            .iter()
            .filter(|&&a| !extra.contains(&"--spp") || a != "--spp" && a != "16");
        let flags: Vec<&str> = flags.copied().collect();
        [&flags[..], &plan, extra]
            .concat()
            .iter()
            .map(|s| s.to_string())
            .collect()
    };
    let refused = |command: &str, args: Vec<String>, needles: &[&str]| {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        fails_in(command, d, &args, needles);
    };
    refused(
        "reference",
        with(&plan, &["--seed", "2"]),
        &["ref.plan", "another render", "seed is 1 there and 2 here"],
    );
    refused(
        "reference",
        with(&plan, &["--spp", "32"]),
        &["spp is 8 there and 16 here"],
    );
    refused(
        "reference",
        with(&render_plan, &[]),
        &[
            "command is \"render\" there and \"reference\" here",
            "--for-reference",
        ],
    );
    refused(
        "render",
        with(&plan, &[]),
        &["command is \"reference\" there and \"render\" here"],
    );
    // And the check can pass: the same plan with the same flags renders.
    let args = with(&plan, &["--shard", "1/2"]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    ok_in("reference", d, "accepted.exr", &args);
    fails_in(
        "reference",
        d,
        &[&pg[..], &["--shard", "0/2"]].concat(),
        &[
            "--method pg learns in every reference",
            "learn --for-reference",
        ],
    );
    // Half 1's kept training where half 2's belongs.
    let training = |half: u32| folder.join(format!("half-{half}/training.bin"));
    assert!(training(1).exists() && training(2).exists());
    std::fs::copy(training(1), training(2)).unwrap();
    let (out, output) = run_in("learn", d, "swapped.plan", &[&pg[..], &keep].concat());
    let err = stderr(&output);
    assert!(!output.status.success(), "{err}");
    assert!(err.contains("half is 1 there and 2 here"), "{err}");
    assert!(!out.exists());
}
