//! Images in memory and on disk.
//!
//! [`write()`] picks the format from the file extension and writes through OpenImageIO
//! (feature `oiio`, `oiio.rs` + `shim/oiio_shim.cpp`) or through the pure-Rust `exr`/`png`
//! crates (`rust_writers.rs`). Every file is written under a temporary name in the target
//! directory and renamed into place, so a failed write never leaves a partial file.

use std::fs::{self, File, OpenOptions};
use std::io::ErrorKind;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

pub mod metrics;
// The only unsafe code outside the Embree back-end: the FFI calls into the OIIO shim.
#[cfg(feature = "oiio")]
#[allow(unsafe_code)]
pub mod oiio;
pub mod rust_writers;
pub mod srgb;
pub mod svg;

/// A linear-RGB float image, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// `width × height` pixels, row-major.
    pub pixels: Vec<[f32; 3]>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![[0.0; 3]; width as usize * height as usize],
        }
    }

    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[(y * self.width + x) as usize]
    }

    pub fn set(&mut self, x: u32, y: u32, rgb: [f32; 3]) {
        self.pixels[(y * self.width + x) as usize] = rgb;
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{path}: unsupported image format (use .exr or .png{extra})")]
    UnsupportedFormat { path: PathBuf, extra: &'static str },
    #[error("{path}: {message}")]
    Write { path: PathBuf, message: String },
    #[error("{path}: {message}")]
    Read { path: PathBuf, message: String },
}

/// Writes `img` to `path`, the format chosen by the extension: `.exr` (float32 linear) and `.png`
/// (8-bit sRGB) always, and with feature `oiio` any format OpenImageIO writes (`.tif`, `.hdr`,
/// `.jpg`...). Atomic: on failure no file is left at `path` and an existing one is untouched.
pub fn write(path: &Path, img: &Image) -> Result<(), ImageError> {
    check_dims(path, img)?;
    let writer = writer_for(path)?;
    write_atomic(path, |tmp| writer(tmp, img))
}

/// Fails when `path` names a format that [`write()`] cannot write, before any work is done.
pub fn check_format(path: &Path) -> Result<(), ImageError> {
    writer_for(path).map(|_| ())
}

type Writer = fn(&Path, &Image) -> Result<(), ImageError>;

#[cfg(feature = "oiio")]
fn writer_for(path: &Path) -> Result<Writer, ImageError> {
    if oiio::can_write(path) {
        Ok(oiio::write)
    } else {
        Err(ImageError::UnsupportedFormat {
            path: path.to_owned(),
            extra: " or another format OpenImageIO writes",
        })
    }
}

#[cfg(not(feature = "oiio"))]
fn writer_for(path: &Path) -> Result<Writer, ImageError> {
    match extension(path).as_deref() {
        Some("exr") => Ok(rust_writers::write_exr),
        Some("png") => Ok(rust_writers::write_png),
        _ => Err(ImageError::UnsupportedFormat {
            path: path.to_owned(),
            extra: "",
        }),
    }
}

/// Reads an image as linear RGB: `.exr` through the `exr` crate and `.png` through the `png`
/// crate always, any other format OpenImageIO reads with feature `oiio`.
pub fn read(path: &Path) -> Result<Image, ImageError> {
    match extension(path).as_deref() {
        Some("exr") => read_exr(path),
        Some("png") => rust_writers::read_png(path),
        #[cfg(feature = "oiio")]
        _ => oiio::read(path),
        #[cfg(not(feature = "oiio"))]
        _ => Err(ImageError::UnsupportedFormat {
            path: path.to_owned(),
            extra: "",
        }),
    }
}

/// Reads an image as its file stores its values: `true` with integer formats' (8-bit PNG,
/// and with feature `oiio` JPEG, TGA, BMP …), normalised to [0, 1] but still sRGB-encoded;
/// `false` with float formats' (EXR, HDR), linear. What [`read()`] decodes; what a `raw`
/// texture reads.
pub fn read_encoded(path: &Path) -> Result<(Image, bool), ImageError> {
    match extension(path).as_deref() {
        Some("exr") => Ok((read_exr(path)?, false)),
        Some("png") => Ok((rust_writers::read_png_encoded(path)?, true)),
        #[cfg(feature = "oiio")]
        _ => oiio::read_encoded(path),
        #[cfg(not(feature = "oiio"))]
        _ => Err(ImageError::UnsupportedFormat {
            path: path.to_owned(),
            extra: "",
        }),
    }
}

/// Reads the first RGB(A) layer of an EXR file (alpha ignored), at full float precision.
pub fn read_exr(path: &Path) -> Result<Image, ImageError> {
    let file = exr::prelude::read_first_rgba_layer_from_file(
        path,
        // EXR sizes are i32 in the file format, so they fit in u32.
        |size, _| Image::new(size.width() as u32, size.height() as u32),
        |img: &mut Image, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let width = img.width as usize;
            img.pixels[pos.y() * width + pos.x()] = [r, g, b];
        },
    )
    .map_err(|e| ImageError::Read {
        path: path.to_owned(),
        message: e.to_string(),
    })?;
    Ok(file.layer_data.channel_data.pixels)
}

/// Lower-case file extension, if any.
fn extension(path: &Path) -> Option<String> {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
}

/// Rejects images the writers cannot describe: an empty image, a pixel buffer that does not
/// match `width × height` (the fields are public), or sizes beyond the C API's `int`.
pub(crate) fn check_dims(path: &Path, img: &Image) -> Result<(), ImageError> {
    let message = if img.width == 0 || img.height == 0 {
        format!("cannot write an empty {}×{} image", img.width, img.height)
    } else if img.width > i32::MAX as u32 || img.height > i32::MAX as u32 {
        format!("{}×{} is too large to write", img.width, img.height)
    } else if img.pixels.len() as u64 != u64::from(img.width) * u64::from(img.height) {
        format!(
            "{}×{} image holds {} pixels",
            img.width,
            img.height,
            img.pixels.len()
        )
    } else {
        return Ok(());
    };
    Err(ImageError::Write {
        path: path.to_owned(),
        message,
    })
}

/// Writes `path` atomically: `write_tmp` writes a temporary file in the same directory (its name
/// keeps `path`'s extension, so writers that pick the format by extension still work), which is
/// then flushed to disk and renamed over `path`. On any failure the temporary file is removed,
/// `path` is left as it was, and a `Write` error names `path`.
pub fn write_atomic(
    path: &Path,
    write_tmp: impl FnOnce(&Path) -> Result<(), ImageError>,
) -> Result<(), ImageError> {
    let write_err = |message: String| ImageError::Write {
        path: path.to_owned(),
        message,
    };
    let tmp = TempFile::create(path).map_err(|e| write_err(e.to_string()))?;
    // Writers name the path they were given; the caller knows only the final one.
    write_tmp(&tmp.path).map_err(|e| match e {
        ImageError::Write { message, .. } => write_err(message),
        other => other,
    })?;
    // Without the flush a crash soon after the rename could leave an empty file at `path`.
    File::open(&tmp.path)
        .and_then(|f| f.sync_all())
        .map_err(|e| write_err(format!("cannot flush {}: {e}", tmp.path.display())))?;
    tmp.persist(path)
        .map_err(|e| write_err(format!("cannot rename the finished file into place: {e}")))
}

/// [`write_atomic`] for bytes already in memory (e.g. a JSON sidecar).
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> Result<(), ImageError> {
    write_atomic(path, |tmp| {
        fs::write(tmp, bytes).map_err(|e| ImageError::Write {
            path: tmp.to_owned(),
            message: e.to_string(),
        })
    })
}

/// Why no temporary file was made beside a destination.
#[derive(Debug, thiserror::Error)]
enum TempFileError {
    #[error("not a file name")]
    NotAFileName,
    #[error("cannot create a file in directory {}: {source}", dir.display())]
    Create {
        dir: PathBuf,
        source: std::io::Error,
    },
}

/// A temporary file next to its destination, removed on drop unless persisted (so also when the
/// writer panics).
struct TempFile {
    path: PathBuf,
    persisted: bool,
}

impl TempFile {
    /// Reserves `.NAME.tmp-<pid>-<n>.EXT` beside `dest` (created exclusively, so two writers
    /// never share one; the process-wide counter only makes the first try succeed).
    fn create(dest: &Path) -> Result<Self, TempFileError> {
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        let stem = dest
            .file_stem()
            .ok_or(TempFileError::NotAFileName)?
            .to_string_lossy();
        let dir = match dest.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let ext = dest
            .extension()
            .map(|e| format!(".{}", e.to_string_lossy()))
            .unwrap_or_default();
        let pid = std::process::id();
        loop {
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let path = dir.join(format!(".{stem}.tmp-{pid}-{n}{ext}"));
            match OpenOptions::new().write(true).create_new(true).open(&path) {
                Ok(_) => {
                    return Ok(Self {
                        path,
                        persisted: false,
                    })
                }
                Err(e) if e.kind() == ErrorKind::AlreadyExists => continue,
                Err(source) => {
                    return Err(TempFileError::Create {
                        dir: dir.to_path_buf(),
                        source,
                    })
                }
            }
        }
    }

    fn persist(mut self, dest: &Path) -> std::io::Result<()> {
        fs::rename(&self.path, dest)?;
        self.persisted = true;
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if !self.persisted {
            // Best effort: the error being reported matters more than a failed cleanup.
            let _ = fs::remove_file(&self.path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temp_file_keeps_directory_and_extension() {
        let dir = tempfile::tempdir().expect("tempdir");
        let dest = dir.path().join("render.final.exr");
        let tmp = TempFile::create(&dest).expect("create");
        assert_eq!(tmp.path.parent(), Some(dir.path()));
        assert_eq!(tmp.path.extension().and_then(|e| e.to_str()), Some("exr"));
        let name = tmp
            .path
            .file_name()
            .and_then(|n| n.to_str())
            .expect("utf-8 name");
        assert!(name.starts_with(".render.final.tmp-"), "{name}");
        assert!(tmp.path.exists());
        let path = tmp.path.clone();
        drop(tmp);
        assert!(!path.exists(), "an unpersisted temp file must be removed");
    }

    #[test]
    fn temp_names_are_unique() {
        let dir = tempfile::tempdir().expect("tempdir");
        let dest = dir.path().join("x.png");
        let a = TempFile::create(&dest).expect("a");
        let b = TempFile::create(&dest).expect("b");
        assert_ne!(a.path, b.path);
    }

    #[test]
    fn bad_dimensions_are_rejected() {
        let p = Path::new("x.exr");
        assert!(check_dims(p, &Image::new(2, 3)).is_ok());
        assert!(check_dims(p, &Image::new(0, 3)).is_err());
        let mut short = Image::new(2, 3);
        short.pixels.pop();
        assert!(check_dims(p, &short).is_err());
    }
}
