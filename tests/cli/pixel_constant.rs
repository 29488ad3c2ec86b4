//! The test-only method `pixel-constant` (feature `testing`), a method that learns one
//! number per pixel, added by docs/architecture.md's recipe alone: `learn` keeps what it
//! learned, `render --plan` renders with it to the in-process image bit for bit, shards of
//! that render merged with the learn job's training shard are that image too, and
//! `--explain` draws it. The twins: a plan of it refused by `pt`, and by a render with
//! another seed.

use super::*;

/// `genpath COMMAND fig5 -o DIR/NAME` at 48 × 40, 8 spp, with `--method METHOD` and `extra`.
fn run_with(
    command: &str,
    dir: &Path,
    (name, method): (&str, &str),
    extra: &[&str],
) -> (PathBuf, Output) {
    let scene = fig5();
    let out = dir.join(name);
    let base = [
        command,
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--spp",
        "8",
        "--width",
        "48",
        "--height",
        "40",
        "--quiet",
        "--method",
        method,
    ];
    let output = genpath(&[&base[..], extra].concat());
    (out, output)
}

fn ok(command: &str, dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let (out, output) = run_with(command, dir, (name, "pixel-constant"), extra);
    assert!(
        output.status.success(),
        "{command} {extra:?}: {}",
        stderr(&output)
    );
    out
}

fn beside(path: &Path, suffix: &str) -> PathBuf {
    let mut p = path.as_os_str().to_owned();
    p.push(suffix);
    PathBuf::from(p)
}

#[test]
fn a_method_added_by_the_recipe_learns_plans_shards_and_explains() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let svg = d.join("constants.svg");
    let inline = ok(
        "render",
        d,
        "inline.exr",
        &["--explain", svg.to_str().unwrap()],
    );
    let picture = std::fs::read_to_string(&svg).unwrap();
    assert!(picture.starts_with("<svg") && picture.matches("<rect").count() == 48 * 40);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(beside(&inline, ".json")).unwrap()).unwrap();
    assert_eq!(json["pixel_constant"]["pixels"], 48 * 40, "{json}");
    assert!(
        json["times_s"]["pixel_constant"].as_f64().is_some(),
        "{json}"
    );

    let plan = ok("learn", d, "constant.plan", &[]);
    let training = beside(&plan, ".shard");
    assert!(training.exists(), "no training shard");
    let with = ["--plan", plan.to_str().unwrap()];
    let saved = ok("render", d, "saved.exr", &with);
    assert_eq!(
        pixel_bits(&saved),
        pixel_bits(&inline),
        "the plan's render differs"
    );

    let mut files: Vec<PathBuf> = (0..2)
        .map(|k| {
            let shard = format!("{k}/2");
            let out = ok(
                "render",
                d,
                &format!("s{k}.exr"),
                &[&with[..], &["--shard", &shard]].concat(),
            );
            beside(&out, ".shard")
        })
        .collect();
    files.push(training);
    let merged = d.join("merged.exr");
    let mut args = vec!["merge"];
    args.extend(files.iter().map(|p| p.to_str().unwrap()));
    args.extend_from_slice(&["-o", merged.to_str().unwrap(), "--quiet", "--complete"]);
    let output = genpath(&args);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(
        pixel_bits(&merged),
        pixel_bits(&inline),
        "the merged shards differ"
    );

    // Another method, or another render (another seed), refuses the plan.
    let (out, output) = run_with("render", d, ("pt.exr", "pt"), &with);
    assert!(!output.status.success() && !out.exists());
    assert!(
        stderr(&output).contains("learns nothing"),
        "{}",
        stderr(&output)
    );
    let other = [&with[..], &["--seed", "2"]].concat();
    let (out, output) = run_with("render", d, ("other.exr", "pixel-constant"), &other);
    assert!(!output.status.success() && !out.exists());
    assert!(stderr(&output).contains("seed"), "{}", stderr(&output));
}
