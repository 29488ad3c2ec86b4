//! `render --shard K/N`, `reference --shard K/N` and `merge`: shards merge to the render on
//! one machine bit for bit, any subset merges to an image with fewer samples, and shards of
//! different renders, duplicates, overlaps and damaged files are refused.

use super::*;
use std::process::Output;

/// `genpath render` of `scene` (fig5 if `None`) at [`SMALL`] into `dir/name` with `extra`
/// flags; must succeed. The image's path.
fn render_in(dir: &Path, name: &str, scene: Option<&Path>, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let scene = scene.map_or_else(fig5, Path::to_path_buf);
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(&SMALL);
    if !extra.contains(&"--method") {
        // Not `render`'s default (the GA's best method, which learns in every render).
        args.extend_from_slice(&["--method", "pt"]);
    }
    args.extend_from_slice(extra);
    let output = genpath(&args);
    assert!(output.status.success(), "{extra:?}: {}", stderr(&output));
    out
}

/// The shard file beside `image`.
fn shard_of(image: &Path) -> PathBuf {
    let mut path = image.as_os_str().to_owned();
    path.push(".shard");
    PathBuf::from(path)
}

/// Shards `0/n … (n-1)/n` of fig5 in `dir`, with `extra` flags: their shard files.
fn shards(dir: &Path, n: u32, extra: &[&str]) -> Vec<PathBuf> {
    (0..n)
        .map(|k| {
            let spec = format!("{k}/{n}");
            let image = render_in(
                dir,
                &format!("s{k}of{n}.exr"),
                None,
                &[extra, &["--shard", &spec]].concat(),
            );
            shard_of(&image)
        })
        .collect()
}

/// `genpath merge SHARDS -o out` (quiet unless `loud`).
fn merge(shards: &[PathBuf], out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["merge"];
    args.extend(shards.iter().map(|p| p.to_str().unwrap()));
    args.extend_from_slice(&["-o", out.to_str().unwrap()]);
    args.extend_from_slice(extra);
    genpath(&args)
}

fn json_of(image: &Path) -> serde_json::Value {
    let mut path = image.as_os_str().to_owned();
    path.push(".json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A merge that must fail with every one of `needles` in its message, leaving no output.
fn assert_merge_fails(shards: &[PathBuf], out: &Path, extra: &[&str], needles: &[&str]) {
    let output = merge(shards, out, extra);
    let err = stderr(&output);
    assert!(!output.status.success(), "merged: {err}");
    assert!(!err.contains("panicked"), "panic: {err}");
    for needle in needles {
        assert!(err.contains(needle), "stderr lacks `{needle}`: {err}");
    }
    assert!(!out.exists(), "output written despite the error");
}

/// Four shards, given in any order, merge to the image of the render on one machine, bit
/// for bit (pt and srt); three of them do not; one shard of one is that render itself.
#[test]
fn shards_merge_to_the_single_machine_render_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for method in ["pt", "srt"] {
        let extra = ["--method", method];
        let whole = render_in(d, &format!("whole-{method}.exr"), None, &extra);
        let mut files = shards(d, 4, &extra);
        files.reverse();
        let merged = d.join(format!("merged-{method}.exr"));
        let output = merge(&files, &merged, &["--quiet"]);
        assert!(output.status.success(), "{}", stderr(&output));
        assert_eq!(pixel_bits(&merged), pixel_bits(&whole), "{method}");
        let stats = json_of(&merged);
        assert_eq!(stats["merged"]["samples_per_pixel"], 8);
        assert_eq!(stats["merged"]["coverage"], "complete");
        // The check can fail: three of the four shards are another image.
        let partial = d.join(format!("partial-{method}.exr"));
        assert!(merge(&files[..3], &partial, &["--quiet"]).status.success());
        assert_ne!(pixel_bits(&partial), pixel_bits(&whole), "{method}");
        std::fs::remove_dir_all(d).unwrap();
        std::fs::create_dir(d).unwrap();
    }
    let whole = render_in(d, "whole.exr", None, &[]);
    let one = render_in(d, "one.exr", None, &["--shard", "0/1"]);
    let merged = d.join("merged.exr");
    assert!(merge(&[shard_of(&one)], &merged, &["-q"]).status.success());
    assert_eq!(pixel_bits(&one), pixel_bits(&whole));
    assert_eq!(pixel_bits(&merged), pixel_bits(&whole));
}

/// The two halves of a reference shard too: two shards of it merge to the reference; a
/// reference's shards merge only into an EXR.
#[test]
fn reference_shards_merge_to_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let reference = |name: &str, extra: &[&str]| {
        let out = d.join(name);
        let mut args = vec!["reference", fig5_str(), "-o", out.to_str().unwrap()];
        args.extend_from_slice(&["--spp", "16", "--width", "24", "--height", "20", "-q"]);
        args.extend_from_slice(extra);
        let output = genpath(&args);
        assert!(output.status.success(), "{}", stderr(&output));
        out
    };
    let whole = reference("whole.exr", &[]);
    let files =
        ["0/2", "1/2"].map(|s| shard_of(&reference(&format!("r{}.exr", &s[..1]), &["--shard", s])));
    let merged = d.join("merged.exr");
    let output = merge(&files, &merged, &["-q"]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(pixel_bits(&merged), pixel_bits(&whole));
    let (a, b) = (json_of(&merged), json_of(&whole));
    assert_eq!(
        a["reference"], b["reference"],
        "the noise estimate is the reference's"
    );
    assert_merge_fails(&files, &d.join("merged.png"), &[], &["must be an EXR"]);
    // The check can fail: one half's shard alone is another image.
    let one = d.join("one.exr");
    assert!(merge(&files[..1], &one, &["-q"]).status.success());
    assert_ne!(pixel_bits(&one), pixel_bits(&whole));
}

fn fig5_str() -> &'static str {
    concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/fig5/scene.toml")
}

/// Any subset of the shards is an image with the samples it holds: a merge reports the
/// missing shards, `--complete` refuses it, and one shard merged alone is its own image.
#[test]
fn a_subset_of_shards_merges_to_an_image_with_fewer_samples() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let files = shards(d, 4, &[]);
    let subset = [files[2].clone(), files[0].clone()];
    let merged = d.join("subset.exr");
    let output = merge(&subset, &merged, &[]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("2 of 4 shards missing (1/4, 3/4)"),
        "{}",
        stderr(&output)
    );
    let stats = json_of(&merged);
    assert_eq!(stats["merged"]["samples_per_pixel"], 4);
    assert_eq!(
        stats["merged"]["coverage"]["missing"]["first"],
        serde_json::json!([1, 3])
    );
    // Shards 0/4 and 2/4 hold the samples of shard 0/2 (summed in another order).
    let half = render_in(d, "half.exr", None, &["--shard", "0/2"]);
    let a = genpath::image::read_exr(&merged).unwrap();
    let b = genpath::image::read_exr(&half).unwrap();
    for (p, q) in a.pixels.iter().flatten().zip(b.pixels.iter().flatten()) {
        assert!((p - q).abs() <= 1e-6 * q.abs(), "{p} against {q}");
    }
    assert_ne!(pixel_bits(&merged), pixel_bits(&d.join("s0of4.exr")));
    let alone = d.join("alone.exr");
    assert!(merge(&files[1..2], &alone, &["-q"]).status.success());
    assert_eq!(pixel_bits(&alone), pixel_bits(&d.join("s1of4.exr")));
    let complete = d.join("complete.exr");
    assert_merge_fails(
        &subset,
        &complete,
        &["--complete"],
        &["--complete", "missing"],
    );
}

/// Shards of renders with another seed, scene file, method setting or number of bounces,
/// or from another genpath binary, are refused with what differs; the same shards of one
/// render merge.
#[test]
fn shards_of_different_renders_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let base = shards(d, 2, &["--method", "srt"]);
    let out = d.join("out.exr");
    assert!(merge(&base, &out, &["-q"]).status.success());
    std::fs::remove_file(&out).unwrap();
    let other = |name: &str, scene: Option<&Path>, extra: &[&str]| {
        let flags = [&["--method", "srt", "--shard", "1/2"][..], extra].concat();
        shard_of(&render_in(d, name, scene, &flags))
    };
    let seed = other("seed.exr", None, &["--seed", "2"]);
    assert_merge_fails(
        &[base[0].clone(), seed],
        &out,
        &[],
        &[
            "not shards of one render",
            "seed differs (1 in the first, 2 in the second)",
        ],
    );
    let setting = other("setting.exr", None, &["--set", "srt_absorption=0.25"]);
    assert_merge_fails(
        &[base[0].clone(), setting],
        &out,
        &[],
        &["settings.srt.srt_absorption differs"],
    );
    let bounces = other("bounces.exr", None, &["--max-bounces", "2"]);
    assert_merge_fails(
        &[base[0].clone(), bounces],
        &out,
        &[],
        &["max_bounces differs"],
    );
    // The same scene with one material's colour changed in its MTL file.
    let copy = d.join("fig5");
    std::fs::create_dir(&copy).unwrap();
    for entry in std::fs::read_dir(fig5().parent().unwrap()).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, copy.join(path.file_name().unwrap())).unwrap();
    }
    let mtl = std::fs::read_dir(&copy)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "mtl"))
        .expect("fig5 has an MTL file");
    let text = std::fs::read_to_string(&mtl).unwrap();
    let kd = text.find("Kd ").expect("a Kd line");
    std::fs::write(
        &mtl,
        format!("{}Kd 0.123 0.5 0.5\n# {}", &text[..kd], &text[kd..]),
    )
    .unwrap();
    let scene = other("scene.exr", Some(&copy.join("scene.toml")), &[]);
    assert_merge_fails(&[base[0].clone(), scene], &out, &[], &["scene differs"]);
    // The same shard as written by another build: its header says so, with a valid checksum.
    let (mut header, layers) = genpath::shard::file::read(&base[1]).unwrap();
    let forged = d.join("forged.shard");
    genpath::shard::file::write(&forged, &header, &layers).unwrap();
    assert!(merge(&[base[0].clone(), forged.clone()], &out, &["-q"])
        .status
        .success());
    std::fs::remove_file(&out).unwrap();
    header.identity.build = "0123456789abcdef".into();
    genpath::shard::file::write(&forged, &header, &layers).unwrap();
    assert_merge_fails(&[base[0].clone(), forged], &out, &[], &["build differs"]);
}

/// A shard given twice, or rendered twice, and shards of different splits that share
/// samples are refused; shards of different splits that share none merge.
#[test]
fn duplicate_and_overlapping_shards_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let quarters = shards(d, 4, &[]);
    let out = d.join("out.exr");
    assert_merge_fails(
        &[quarters[1].clone(), quarters[1].clone()],
        &out,
        &[],
        &["both shard 1/4"],
    );
    let again = shard_of(&render_in(d, "again.exr", None, &["--shard", "1/4"]));
    assert_merge_fails(
        &[quarters[0].clone(), quarters[1].clone(), again],
        &out,
        &[],
        &["both shard 1/4"],
    );
    let half = shard_of(&render_in(d, "half.exr", None, &["--shard", "0/2"]));
    assert_merge_fails(
        &[quarters[2].clone(), half.clone()],
        &out,
        &[],
        &["overlap", "s mod 4 = 2"],
    );
    // 0/2 holds the even samples, 1/4 and 3/4 the odd ones: the whole render.
    let output = merge(
        &[half, quarters[1].clone(), quarters[3].clone()],
        &out,
        &["-q"],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    assert_eq!(json_of(&out)["merged"]["coverage"], "complete");
}

/// A truncated, corrupted or foreign file is refused, not merged.
#[test]
fn damaged_shard_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let files = shards(d, 2, &[]);
    let bytes = std::fs::read(&files[1]).unwrap();
    let out = d.join("out.exr");
    let damaged = d.join("damaged.shard");
    for (cut, needle) in [
        (1, "truncated"),
        (bytes.len() / 2, "truncated"),
        (bytes.len() - 12, "truncated"),
        (bytes.len() - 5, "not a genpath shard"),
    ] {
        std::fs::write(&damaged, &bytes[..bytes.len() - cut]).unwrap();
        assert_merge_fails(
            &[files[0].clone(), damaged.clone()],
            &out,
            &[],
            &[needle, "damaged.shard"],
        );
    }
    let mut flipped = bytes.clone();
    let at = bytes.len() - 100;
    flipped[at] ^= 0x10;
    std::fs::write(&damaged, &flipped).unwrap();
    assert_merge_fails(
        &[files[0].clone(), damaged.clone()],
        &out,
        &[],
        &["corrupted", "checksum"],
    );
    let mut padded = bytes.clone();
    padded.push(0);
    std::fs::write(&damaged, &padded).unwrap();
    assert_merge_fails(&[files[0].clone(), damaged.clone()], &out, &[], &["padded"]);
    let image = d.join("s0of2.exr");
    assert_merge_fails(
        &[files[0].clone(), image],
        &out,
        &[],
        &["not a genpath shard file"],
    );
    // The check can fail: the undamaged bytes merge.
    std::fs::write(&damaged, &bytes).unwrap();
    assert!(merge(&[files[0].clone(), damaged], &out, &["-q"])
        .status
        .success());
}

/// Bad `--shard` values and methods that learn are refused before anything is written.
#[test]
fn bad_shard_flags_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.exr");
    for (value, needle) in [
        ("3/2", "shard K must be below N"),
        ("2/2", "shard K must be below N"),
        ("0/0", "at least 1"),
        ("x/y", "is not K/N"),
        ("1", "is not K/N"),
        ("-1/2", "is not K/N"),
        ("0/99999999999", "is not K/N"),
        ("0/2", "leave some shards without a sample"),
    ] {
        let flag = format!("--shard={value}");
        assert_fails(&fig5(), &[&flag, "--method", "pt"], &out, &[needle]);
    }
    for method in ["pg", "ga", "ga-pt"] {
        let needle = format!("--method {method} learns in every render");
        assert_fails(
            &fig5(),
            &["--shard", "0/1", "--method", method],
            &out,
            &[&needle, "shared"],
        );
    }
    let output = genpath(&["merge", "-o", out.to_str().unwrap()]);
    assert!(!output.status.success());
}

/// Embree's kernels for different instruction sets round hits differently (on cbox at 16
/// spp, AVX2's and AVX-512's images differ in 65 % of the pixels), so shards traced with
/// different ones are refused, naming the kernels; shards pinned to the same merge. A pin
/// for the pure-Rust back-end is refused.
#[cfg(feature = "embree")]
#[test]
fn shards_of_different_embree_kernels_are_refused() {
    use genpath::accel::EmbreeIsa;
    let Some(best) = EmbreeIsa::best_here().filter(|&isa| isa > EmbreeIsa::Sse2) else {
        eprintln!("skipped: this CPU runs no Embree kernels but SSE2's");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let pinned = shards(d, 2, &["--embree-isa", best.name()]);
    let out = d.join("out.exr");
    assert!(merge(&pinned, &out, &["-q"]).status.success());
    std::fs::remove_file(&out).unwrap();
    let flags = ["--shard", "1/2", "--embree-isa", "sse2"];
    let sse2 = shard_of(&render_in(d, "sse2.exr", None, &flags));
    let differs = format!("\"embree ({} kernels)\" in the first", best.name());
    assert_merge_fails(
        &[pinned[0].clone(), sse2],
        &out,
        &[],
        &[
            "accel differs",
            &differs,
            "\"embree (sse2 kernels)\" in the second",
        ],
    );
    // Without the flag, the best kernels are the ones pinned above.
    let unpinned = shard_of(&render_in(d, "best.exr", None, &["--shard", "1/2"]));
    assert!(merge(&[pinned[0].clone(), unpinned], &out, &["-q"])
        .status
        .success());
    assert_fails(
        &fig5(),
        &["--accel", "bvh", "--embree-isa", "sse2"],
        &d.join("bvh.exr"),
        &["--embree-isa sse2", "not Embree"],
    );
}

/// `sweep --shard K/N` runs part of a sweep's runs; `merge PARTS.csv -o PREFIX` puts the
/// parts' rows in the order of the whole sweep, whose rows (but their timings) they equal.
/// A missing part is reported (and refused with `--complete`); a part given twice, parts of
/// another sweep (other budgets) and a mix of sweep parts and render shards are refused.
#[test]
fn sweep_parts_merge_to_the_whole_sweep() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let size = ["--width", "16", "--height", "12", "--quiet"];
    let reference = d.join("ref.exr");
    let scene = fig5();
    let scene = scene.to_str().unwrap();
    let r = [
        &["reference", scene, "--spp", "64", "-o"][..],
        &[reference.to_str().unwrap()],
        &size,
    ]
    .concat();
    assert!(genpath(&r).status.success());
    let sweep = |prefix: &str, budgets: &str, extra: &[&str]| {
        let out = d.join(prefix);
        let args = [
            &[
                "sweep",
                scene,
                "--ref",
                reference.to_str().unwrap(),
                "--methods",
                "pt,srt,ga:m=300:pop=4:gen=2:grid=8",
            ][..],
            &[
                "--budgets",
                budgets,
                "--reps",
                "2",
                "-o",
                out.to_str().unwrap(),
            ],
            &size,
            extra,
        ]
        .concat();
        let output = genpath(&args);
        assert!(output.status.success(), "{}", stderr(&output));
        d.join(format!("{prefix}.csv"))
    };
    // Everything but the timings (seconds, ga_seconds, efficiency).
    let rows = |csv: &Path| -> Vec<String> {
        std::fs::read_to_string(csv)
            .unwrap()
            .lines()
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                [f[0], f[1], f[2], f[5], f[6], f[7], f[9]].join(",")
            })
            .collect()
    };
    let whole = sweep("whole", "1,4", &[]);
    let parts: Vec<PathBuf> = (0..3)
        .map(|k| sweep(&format!("part{k}"), "1,4", &["--shard", &format!("{k}/3")]))
        .collect();
    let merged = d.join("merged");
    let out = merge(&parts, &merged, &["-q"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let merged_csv = d.join("merged.csv");
    assert_eq!(rows(&merged_csv), rows(&whole));
    assert_eq!(rows(&whole).len(), 1 + 3 * 2 * 2);
    assert!(d.join("merged.svg").exists());

    // Two of three parts: reported, and refused with --complete.
    let out = merge(&parts[..2], &d.join("two"), &[]);
    assert!(
        out.status.success() && stderr(&out).contains("1 of 3 parts missing (2/3)"),
        "{}",
        stderr(&out)
    );
    assert_merge_fails(
        &parts[..2],
        &d.join("none"),
        &["--complete"],
        &["--complete", "1 of 3 parts missing"],
    );
    assert_merge_fails(
        &[parts[0].clone(), parts[0].clone()],
        &d.join("none"),
        &[],
        &["both part 0/3"],
    );
    let other = sweep("other", "1,8", &["--shard", "1/3"]);
    assert_merge_fails(
        &[parts[0].clone(), other],
        &d.join("none"),
        &[],
        &["not parts of one sweep", "budgets"],
    );
    let shard = shard_of(&render_in(d, "s.exr", None, &["--shard", "0/2"]));
    assert_merge_fails(
        &[parts[0].clone(), shard],
        &d.join("none"),
        &[],
        &["do not merge together"],
    );
}
