//! genpath's `bitmap` and `checkerboard` lookups against Mitsuba 3.9.1's own
//! (scenes/mitsuba/textures/lookups.tsv, written by scripts/texture_lookups.py): every
//! texture file (8-bit RGB, grey, 1×1, float EXR), filter, wrap mode, `raw` on and off and
//! `to_uv`, at texture coordinates inside and outside [0, 1]², to 1e-5. Twins that must be
//! told apart from Mitsuba's values: nearest lookups where bilinear ones were asked, `v`
//! not flipped (row 0 at `v = 1`), sRGB decoding skipped, mirror read as repeat.

use genpath::scene::texture::{Bitmap, Checkerboard, Filter, Wrap};
use glam::{Affine2, Vec2, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

const TOLERANCE: f32 = 1e-5;

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mitsuba/textures")
}

struct Row {
    file: String,
    filter: String,
    wrap: String,
    raw: bool,
    to_uv: String,
    uv: Vec2,
    rgb: Vec3,
}

fn rows() -> Vec<Row> {
    let text = std::fs::read_to_string(dir().join("lookups.tsv")).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("file\t"))
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            let x = |i: usize| f[i].parse::<f32>().unwrap();
            Row {
                file: f[0].into(),
                filter: f[1].into(),
                wrap: f[2].into(),
                raw: f[3] == "1",
                to_uv: f[4].into(),
                uv: Vec2::new(x(5), x(6)),
                rgb: Vec3::new(x(7), x(8), x(9)),
            }
        })
        .collect()
}

/// The script's `st`: scale (2, 3), then translate (0.25, 0.1).
fn to_uv(name: &str) -> Affine2 {
    match name {
        "none" => Affine2::IDENTITY,
        "st" => {
            Affine2::from_scale_angle_translation(Vec2::new(2.0, 3.0), 0.0, Vec2::new(0.25, 0.1))
        }
        other => panic!("{other}"),
    }
}

/// How a lookup is deliberately got wrong.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Twin {
    None,
    NearestForBilinear,
    VNotFlipped,
    NoSrgbDecoding,
    MirrorAsRepeat,
}

/// genpath's lookup for `row`, got wrong as `twin` says; bitmaps are read once per
/// (file, options).
fn lookup(row: &Row, twin: Twin, cache: &mut HashMap<String, Bitmap>) -> Vec3 {
    let t = to_uv(&row.to_uv);
    if row.file == "checkerboard" {
        let c = Checkerboard {
            color0: Vec3::new(0.9, 0.5, 0.1),
            color1: Vec3::new(0.05, 0.2, 0.7),
            to_uv: t,
        };
        return c.eval(row.uv);
    }
    let filter = match (row.filter.as_str(), twin) {
        ("nearest", _) | ("bilinear", Twin::NearestForBilinear) => Filter::Nearest,
        _ => Filter::Bilinear,
    };
    let wrap = match (row.wrap.as_str(), twin) {
        ("repeat", _) | ("mirror", Twin::MirrorAsRepeat) => Wrap::Repeat,
        ("mirror", _) => Wrap::Mirror,
        _ => Wrap::Clamp,
    };
    let raw = row.raw || twin == Twin::NoSrgbDecoding;
    let key = format!("{} {filter:?} {wrap:?} {raw} {}", row.file, row.to_uv);
    let b = cache
        .entry(key)
        .or_insert_with(|| Bitmap::read(&dir().join(&row.file), raw, (filter, wrap, t)).unwrap());
    let uv = match twin {
        // Row 0 of the image at v = 1: the texture read upside down.
        Twin::VNotFlipped => Vec2::new(row.uv.x, 1.0 - row.uv.y),
        _ => row.uv,
    };
    b.eval(uv)
}

/// The largest difference from Mitsuba's values over the rows `select` keeps, and how many
/// rows differ by more than the tolerance.
fn compare(twin: Twin, select: impl Fn(&Row) -> bool) -> (f32, usize, usize) {
    let mut cache = HashMap::new();
    let (mut worst, mut bad, mut n) = (0.0f32, 0, 0);
    for row in rows().iter().filter(|r| select(r)) {
        let got = lookup(row, twin, &mut cache);
        let err = (got - row.rgb).abs().max_element();
        // Relative beyond 1 (the float texture's texels reach 3).
        let err = err / row.rgb.max_element().max(1.0);
        if err > TOLERANCE {
            bad += 1;
            if twin == Twin::None {
                eprintln!(
                    "{} {} {} raw {} {} at {}: {got} against Mitsuba's {}",
                    row.file, row.filter, row.wrap, row.raw, row.to_uv, row.uv, row.rgb
                );
            }
        }
        worst = worst.max(err);
        n += 1;
    }
    (worst, bad, n)
}

#[test]
fn lookups_agree_with_mitsuba() {
    let (worst, bad, n) = compare(Twin::None, |_| true);
    println!("{n} lookups, largest difference {worst:e}");
    assert!(n > 1400, "{n}");
    assert_eq!(bad, 0, "{bad} of {n} lookups differ (largest {worst:e})");
}

/// Which rows a twin is compared on.
type Select = dyn Fn(&Row) -> bool;

#[test]
fn wrong_lookups_are_told_apart() {
    let cases: [(Twin, &Select); 4] = [
        (Twin::NearestForBilinear, &|r: &Row| {
            r.filter == "bilinear" && r.file == "grid.png"
        }),
        (Twin::VNotFlipped, &|r: &Row| r.file == "grid.png"),
        (Twin::NoSrgbDecoding, &|r: &Row| {
            !r.raw && r.file.ends_with(".png")
        }),
        (Twin::MirrorAsRepeat, &|r: &Row| {
            r.wrap == "mirror" && r.file == "small.png"
        }),
    ];
    for (twin, select) in cases {
        let (worst, bad, n) = compare(twin, select);
        println!("{twin:?}: {bad} of {n} lookups differ, largest {worst:e}");
        assert!(bad * 4 > n, "{twin:?}: only {bad} of {n} lookups differ");
    }
}

/// A 1×1 texture is a constant, whatever the filter, wrap and coordinates (Mitsuba pads it
/// to 2×2 with its one texel).
#[test]
fn a_single_texel_is_a_constant() {
    let (worst, bad, n) = compare(Twin::None, |r| r.file == "one.png");
    assert!(n >= 100 && bad == 0, "{bad} of {n}, {worst:e}");
}
