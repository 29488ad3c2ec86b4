//! Image files: exact EXR round trips and identical PNG bytes for every back-end, and atomic
//! writes that leave nothing behind when they fail.

use std::fs;
use std::path::{Path, PathBuf};

use genpath::image::{self, rust_writers, srgb, Image, ImageError};

/// 4×2 pixels with awkward values: negative, above 1, huge, tiny, infinite, NaN, the sRGB knee.
fn awkward_image() -> Image {
    let mut img = Image::new(4, 2);
    let values = [
        [0.0, 0.5, 1.0],
        [-1.0, 2.0, 0.003_130_8],
        [f32::NAN, 0.18, 1e30],
        [1e-40, f32::INFINITY, f32::NEG_INFINITY],
        [0.25, 0.75, 0.999],
        [1.0 / 3.0, 0.001, 0.9],
        [-0.0, 0.04, 65504.0],
        [0.123_456_79, 7.0, 0.000_01],
    ];
    img.pixels.copy_from_slice(&values);
    img
}

/// What every back-end must store in an 8-bit file for `awkward_image`.
const AWKWARD_SRGB8: [u8; 24] = [
    0, 188, 255, //
    0, 255, 10, //
    0, 118, 255, //
    0, 255, 0, //
    137, 225, 255, //
    156, 3, 243, //
    0, 56, 255, //
    99, 255, 0,
];

fn files_in(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<_> = fs::read_dir(dir)
        .expect("read_dir")
        .map(|e| e.expect("entry").path())
        .collect();
    v.sort();
    v
}

fn assert_bit_exact(a: &Image, b: &Image) {
    assert_eq!((a.width, a.height), (b.width, b.height));
    for (i, (pa, pb)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        let bits = |p: &[f32; 3]| p.map(f32::to_bits);
        assert_eq!(bits(pa), bits(pb), "pixel {i}: {pa:?} vs {pb:?}");
    }
}

/// Decodes a PNG with the `png` crate, asserting it is 8-bit RGB; returns the raw bytes.
fn png_bytes(path: &Path) -> Vec<u8> {
    let decoder = png::Decoder::new(fs::File::open(path).expect("open png"));
    let mut reader = decoder.read_info().expect("png header");
    let mut buf = vec![0; reader.output_buffer_size()];
    let frame = reader.next_frame(&mut buf).expect("png data");
    assert_eq!(frame.color_type, png::ColorType::Rgb, "{}", path.display());
    assert_eq!(frame.bit_depth, png::BitDepth::Eight, "{}", path.display());
    buf.truncate(frame.buffer_size());
    buf
}

#[test]
fn expected_png_bytes_follow_the_srgb_curve() {
    let expected: Vec<u8> = awkward_image()
        .pixels
        .as_flattened()
        .iter()
        .map(|&v| srgb::encode_u8(v))
        .collect();
    assert_eq!(expected, AWKWARD_SRGB8);
}

#[test]
fn exr_round_trip_is_bit_exact_pure_rust() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("a.exr");
    let img = awkward_image();
    rust_writers::write_exr(&path, &img).expect("write");
    assert_bit_exact(&img, &image::read_exr(&path).expect("read"));
}

#[test]
fn exr_round_trip_is_bit_exact_through_write() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("b.EXR");
    let img = awkward_image();
    image::write(&path, &img).expect("write");
    assert_bit_exact(&img, &image::read_exr(&path).expect("read"));
    assert_eq!(
        files_in(dir.path()),
        vec![path],
        "temporary file left behind"
    );
}

#[test]
fn png_bytes_are_clamped_rounded_srgb() {
    let dir = tempfile::tempdir().expect("tempdir");
    let direct = dir.path().join("direct.png");
    let via_write = dir.path().join("via_write.png");
    let img = awkward_image();
    rust_writers::write_png(&direct, &img).expect("write direct");
    image::write(&via_write, &img).expect("write");
    assert_eq!(png_bytes(&direct), AWKWARD_SRGB8);
    assert_eq!(png_bytes(&via_write), AWKWARD_SRGB8);
}

#[test]
fn png_reads_back_as_decoded_srgb() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("r.png");
    image::write(&path, &awkward_image()).expect("write");
    let back = image::read(&path).expect("read");
    let expected: Vec<f32> = AWKWARD_SRGB8.iter().map(|&b| srgb::decode_u8(b)).collect();
    for (i, (&got, &want)) in back.pixels.as_flattened().iter().zip(&expected).enumerate() {
        assert!((got - want).abs() <= 1e-6, "value {i}: {got} vs {want}");
    }
}

/// Asserts that writing to `path` fails with a `Write` error naming it, and leaves no file there.
fn assert_write_fails_cleanly(path: &Path) {
    for ext in ["exr", "png"] {
        let path = path.with_extension(ext);
        match image::write(&path, &awkward_image()) {
            Err(e @ ImageError::Write { .. }) => {
                let text = e.to_string();
                assert!(
                    text.contains(&path.display().to_string()),
                    "error must name the path: {text}"
                );
            }
            other => panic!("{}: expected a write error, got {other:?}", path.display()),
        }
        assert!(!path.exists());
    }
}

#[test]
fn nonexistent_directory_is_an_error() {
    assert_write_fails_cleanly(Path::new("/nonexistent/dir/x.exr"));
}

#[test]
fn file_used_as_directory_is_an_error_and_leaves_nothing() {
    // Tests may run as root, who can write into read-only directories; a regular file as the
    // "directory" fails for everyone.
    let dir = tempfile::tempdir().expect("tempdir");
    let afile = dir.path().join("afile");
    fs::write(&afile, b"not a directory").expect("write afile");
    assert_write_fails_cleanly(&afile.join("x.exr"));
    assert_eq!(files_in(dir.path()), vec![afile]);
}

#[test]
fn unsupported_extension_is_an_error() {
    let dir = tempfile::tempdir().expect("tempdir");
    for name in ["x.notanimageformat", "no_extension"] {
        let path = dir.path().join(name);
        let result = image::write(&path, &awkward_image());
        assert!(
            matches!(result, Err(ImageError::UnsupportedFormat { .. })),
            "{name}: {result:?}"
        );
    }
    assert!(files_in(dir.path()).is_empty());
}

#[cfg(not(feature = "oiio"))]
#[test]
fn without_oiio_only_exr_and_png_are_written() {
    let dir = tempfile::tempdir().expect("tempdir");
    let result = image::write(&dir.path().join("x.tif"), &awkward_image());
    assert!(
        matches!(result, Err(ImageError::UnsupportedFormat { .. })),
        "{result:?}"
    );
}

#[test]
fn inconsistent_image_is_an_error_and_leaves_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut img = awkward_image();
    img.pixels.pop();
    assert!(image::write(&dir.path().join("x.exr"), &img).is_err());
    assert!(files_in(dir.path()).is_empty());
}

#[test]
fn failed_atomic_write_keeps_the_old_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("out.exr.json");
    image::write_bytes_atomic(&path, b"old").expect("first write");
    let result = image::write_atomic(&path, |tmp| {
        fs::write(tmp, b"half written").expect("write tmp");
        Err(ImageError::Write {
            path: tmp.to_owned(),
            message: "simulated failure".into(),
        })
    });
    match result {
        Err(ImageError::Write { path: p, message }) => {
            assert_eq!(
                p, path,
                "the error must name the destination, not the temporary file"
            );
            assert_eq!(message, "simulated failure");
        }
        other => panic!("expected the writer's error, got {other:?}"),
    }
    assert_eq!(fs::read(&path).expect("read"), b"old");
    assert_eq!(files_in(dir.path()), vec![path]);
}

#[test]
fn atomic_write_replaces_via_a_sibling_with_the_same_extension() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("out.json");
    image::write_bytes_atomic(&path, b"old").expect("first write");
    image::write_atomic(&path, |tmp| {
        assert_eq!(tmp.parent(), path.parent());
        assert_eq!(tmp.extension(), path.extension());
        assert_ne!(tmp, path);
        fs::write(tmp, b"new").map_err(|e| ImageError::Write {
            path: tmp.to_owned(),
            message: e.to_string(),
        })
    })
    .expect("second write");
    assert_eq!(fs::read(&path).expect("read"), b"new");
    assert_eq!(files_in(dir.path()), vec![path]);
}

#[cfg(feature = "oiio")]
mod oiio {
    use super::*;
    use genpath::image::oiio;

    #[test]
    fn exr_round_trip_is_bit_exact() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("o.exr");
        let img = awkward_image();
        oiio::write(&path, &img).expect("write");
        assert_bit_exact(&img, &image::read_exr(&path).expect("read_exr"));
        assert_bit_exact(&img, &oiio::read(&path).expect("oiio read"));
    }

    #[test]
    fn png_matches_the_pure_rust_writer() {
        let dir = tempfile::tempdir().expect("tempdir");
        let (a, b) = (dir.path().join("oiio.png"), dir.path().join("rust.png"));
        let img = awkward_image();
        oiio::write(&a, &img).expect("oiio write");
        rust_writers::write_png(&b, &img).expect("rust write");
        assert_eq!(png_bytes(&a), png_bytes(&b));
        assert_eq!(png_bytes(&a), AWKWARD_SRGB8);
    }

    #[test]
    fn float_tiff_round_trips_and_jpeg_is_written() {
        let dir = tempfile::tempdir().expect("tempdir");
        let img = awkward_image();
        let tif = dir.path().join("x.tif");
        image::write(&tif, &img).expect("write tif");
        assert_bit_exact(&img, &image::read(&tif).expect("read tif"));

        // JPEG is lossy: compare a mid-grey, far from clamping, with a loose tolerance.
        let mut grey = Image::new(8, 8);
        grey.pixels.fill([0.2, 0.2, 0.2]);
        let jpg = dir.path().join("x.jpg");
        image::write(&jpg, &grey).expect("write jpg");
        let back = image::read(&jpg).expect("read jpg");
        for v in back.pixels.as_flattened() {
            assert!((v - 0.2).abs() < 0.01, "{v}");
        }
    }

    #[test]
    fn can_write_knows_formats() {
        assert!(oiio::can_write(Path::new("a.exr")));
        assert!(oiio::can_write(Path::new("a.png")));
        assert!(!oiio::can_write(Path::new("a.notanimageformat")));
    }

    #[test]
    fn missing_file_is_a_read_error() {
        let result = oiio::read(Path::new("/nonexistent/x.tif"));
        assert!(matches!(result, Err(ImageError::Read { .. })), "{result:?}");
    }
}
