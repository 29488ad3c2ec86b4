//! The command line on good and bad input: clear errors, non-zero exit, no panic, no output
//! file; and determinism across thread counts. This file holds the helpers; the tests are in
//! `bad_input.rs` (malformed scenes and flags), `methods.rs` (each method's renders) and
//! `commands.rs` (reference, sweep, bench, check, settings and the test-only method) and
//! `shards.rs` (`--shard` and `merge`), `resume.rs` (stopped, killed and resumed renders),
//! `plan.rs` (`learn` and `render --plan`) and `learning.rs` (the GA split over jobs, and
//! stopped learning).

#[path = "../common/mod.rs"]
mod common;

mod bad_input;
mod commands;
mod learning;
mod methods;
#[cfg(feature = "testing")]
mod pixel_constant;
mod plan;
mod resume;
mod shards;
#[cfg(feature = "testing")]
mod splats;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// fig5 at 48×40 and 8 spp, quietly (the shard, plan and resume tests' size).
const SMALL: [&str; 7] = ["--spp", "8", "--width", "48", "--height", "40", "--quiet"];

/// A small GA: 16-pixel grid, 3000 test paths, 12 individuals, 6 generations.
const SMALL_GA: [&str; 8] = [
    "--ga-grid",
    "16",
    "--test-paths",
    "3000",
    "--population",
    "12",
    "--generations",
    "6",
];

/// Runs genpath in the repository's root, where relative paths such as
/// `scenes/fig5/scene.toml` resolve.
/// A command's standard error, as text.
fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

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

/// Waits until `ready` (at most a minute; the process must not end before), then sends
/// `signal` (a `kill` name) to `child`: the ended process. `what` names what it waits for.
fn signal_when(
    mut child: std::process::Child,
    ready: impl Fn() -> bool,
    signal: &str,
    what: &str,
) -> Output {
    let start = std::time::Instant::now();
    while !ready() {
        assert!(
            start.elapsed() < std::time::Duration::from_secs(60),
            "no {what} within a minute"
        );
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the process ended ({status}) before its {what}");
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    // The shell's own `kill`: a minimal system (CI's Debian 13 root) has no kill program.
    let killed = Command::new("sh")
        .args(["-c", &format!("kill -{signal} {}", child.id())])
        .status()
        .expect("run sh");
    assert!(killed.success());
    child.wait_with_output().unwrap()
}
