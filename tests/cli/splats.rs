//! The film takes splats: the test-only method `splat-mirror` (feature `testing`) splats
//! `pt`'s samples onto the pixel mirrored left to right, one light path each, so that its
//! image is `pt`'s mirrored, bit for bit at 32 × 16 pixels (a power of two: the splats'
//! scale and the layer's division by its light paths are exact). It must stay so with one
//! thread or two, merged from shards, and stopped and resumed; `pt`'s image of another
//! seed, mirrored, must not match (the comparison's must-reject twin).

use super::*;
use std::process::Stdio;

const WIDTH: usize = 32;
const HEIGHT: usize = 16;

/// fig5 at 32 × 16 with `spp` samples per pixel into `out`, with `extra` flags.
fn render(out: &Path, spp: u32, extra: &[&str]) -> Vec<String> {
    let scene = fig5();
    let spp = spp.to_string();
    let mut args: Vec<String> = [
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--spp",
        &spp,
        "--width",
        "32",
        "--height",
        "16",
        "--quiet",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    args.extend(extra.iter().map(|s| s.to_string()));
    args
}

fn run_ok(args: &[String]) {
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let output = genpath(&args);
    assert!(output.status.success(), "{args:?}: {}", stderr(&output));
}

/// The pixels' bits of the EXR at `path`, each row mirrored left to right.
fn mirrored_bits(path: &Path) -> Vec<u32> {
    let bits = pixel_bits(path);
    let mut out = Vec::with_capacity(bits.len());
    for row in bits.chunks(3 * WIDTH) {
        for pixel in row.chunks(3).rev() {
            out.extend_from_slice(pixel);
        }
    }
    assert_eq!(out.len(), 3 * WIDTH * HEIGHT);
    out
}

fn shard_file(image: &Path) -> PathBuf {
    let mut path = image.as_os_str().to_owned();
    path.push(".shard");
    PathBuf::from(path)
}

#[test]
fn the_splat_layer_is_pts_image_mirrored_for_any_threads_shards_and_resume() {
    let dir = tempfile::tempdir().unwrap();
    let at = |name: &str| dir.path().join(name);
    let splat = ["--method", "splat-mirror"];

    run_ok(&render(
        &at("pt.exr"),
        64,
        &["--method", "pt", "--threads", "1"],
    ));
    run_ok(&render(
        &at("pt-2.exr"),
        64,
        &["--method", "pt", "--seed", "2"],
    ));
    run_ok(&render(
        &at("one.exr"),
        64,
        &[&splat[..], &["--threads", "1"]].concat(),
    ));
    run_ok(&render(
        &at("two.exr"),
        64,
        &[&splat[..], &["--threads", "2"]].concat(),
    ));
    let one = pixel_bits(&at("one.exr"));
    assert_eq!(
        one,
        mirrored_bits(&at("pt.exr")),
        "splats are not pt mirrored"
    );
    assert_ne!(
        one,
        mirrored_bits(&at("pt-2.exr")),
        "another seed's image matched"
    );
    assert_eq!(one, pixel_bits(&at("two.exr")), "one thread and two differ");

    // Two shards, each holding half the light paths, merge to the whole render.
    for k in 0..2 {
        let shard = format!("{k}/2");
        run_ok(&render(
            &at(&format!("s{k}.exr")),
            64,
            &[&splat[..], &["--shard", &shard]].concat(),
        ));
        let (_, layers) =
            genpath::shard::file::read(&shard_file(&at(&format!("s{k}.exr")))).unwrap();
        let splats = layers[0]
            .splats
            .as_ref()
            .expect("a shard of a splatting render has its splat layer");
        assert_eq!(splats.light_paths, (WIDTH * HEIGHT * 32) as u64);
    }
    let shards = [0, 1].map(|k| shard_file(&at(&format!("s{k}.exr"))));
    let merged = at("merged.exr");
    let output = genpath(&[
        "merge",
        shards[0].to_str().unwrap(),
        shards[1].to_str().unwrap(),
        "-o",
        merged.to_str().unwrap(),
        "--complete",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(
        pixel_bits(&merged),
        one,
        "merged shards differ from the whole render"
    );

    // Stopped at a checkpoint (between passes of one sample per pixel), then resumed.
    let stopped_at = at("stopped.exr");
    let args = render(
        &stopped_at,
        1024,
        &[&splat[..], &["--threads", "1", "--checkpoint", "0"]].concat(),
    );
    let child = Command::new(env!("CARGO_BIN_EXE_genpath"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(&args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run genpath");
    let file = shard_file(&stopped_at);
    let stopped = signal_when(child, || file.exists(), "TERM", "first checkpoint");
    assert_eq!(stopped.status.code(), Some(143), "{}", stderr(&stopped));
    let (_, layers) = genpath::shard::file::read(&file).unwrap();
    let counts = &layers[0].counts;
    assert!(
        counts.iter().all(|&c| c == counts[0]),
        "a stop within a pass"
    );
    assert!(
        counts[0] < 1024,
        "the render was not stopped: {}",
        counts[0]
    );
    let splats = layers[0].splats.as_ref().unwrap();
    assert_eq!(
        splats.light_paths,
        (WIDTH * HEIGHT) as u64 * u64::from(counts[0])
    );
    run_ok(&render(
        &stopped_at,
        1024,
        &[&splat[..], &["--resume", file.to_str().unwrap()]].concat(),
    ));
    run_ok(&render(&at("whole.exr"), 1024, &splat));
    assert_eq!(
        pixel_bits(&stopped_at),
        pixel_bits(&at("whole.exr")),
        "the resumed render differs"
    );
}

/// `lt`, light tracing, whose light paths are drawn from the streams of the pixel samples
/// that own them: the same image for one thread or two, from two shards merged, and
/// stopped and resumed; another seed's image differs (the twin).
#[test]
fn lt_is_one_image_for_any_threads_shards_and_resume() {
    let dir = tempfile::tempdir().unwrap();
    let at = |name: &str| dir.path().join(name);
    let lt = ["--method", "lt"];
    for (name, extra) in [
        ("one.exr", vec!["--threads", "1"]),
        ("two.exr", vec!["--threads", "2"]),
        ("seed2.exr", vec!["--seed", "2"]),
        ("s0.exr", vec!["--shard", "0/2"]),
        ("s1.exr", vec!["--shard", "1/2"]),
    ] {
        run_ok(&render(&at(name), 16, &[&lt[..], &extra].concat()));
    }
    let one = pixel_bits(&at("one.exr"));
    assert_eq!(one, pixel_bits(&at("two.exr")), "one thread and two differ");
    assert_ne!(
        one,
        pixel_bits(&at("seed2.exr")),
        "another seed's image matched"
    );
    let shards = [0, 1].map(|k| shard_file(&at(&format!("s{k}.exr"))));
    let merged = at("merged.exr");
    let output = genpath(&[
        "merge",
        shards[0].to_str().unwrap(),
        shards[1].to_str().unwrap(),
        "-o",
        merged.to_str().unwrap(),
        "--complete",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(
        pixel_bits(&merged),
        one,
        "merged shards differ from the whole render"
    );

    let stopped_at = at("stopped.exr");
    let args = render(
        &stopped_at,
        1024,
        &[&lt[..], &["--threads", "1", "--checkpoint", "0"]].concat(),
    );
    let child = Command::new(env!("CARGO_BIN_EXE_genpath"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(&args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run genpath");
    let file = shard_file(&stopped_at);
    let stopped = signal_when(child, || file.exists(), "TERM", "first checkpoint");
    assert_eq!(stopped.status.code(), Some(143), "{}", stderr(&stopped));
    let (_, layers) = genpath::shard::file::read(&file).unwrap();
    assert!(layers[0].counts[0] < 1024, "the render was not stopped");
    run_ok(&render(
        &stopped_at,
        1024,
        &[&lt[..], &["--resume", file.to_str().unwrap()]].concat(),
    ));
    run_ok(&render(&at("whole.exr"), 1024, &lt));
    assert_eq!(
        pixel_bits(&stopped_at),
        pixel_bits(&at("whole.exr")),
        "the resumed render differs"
    );
}
