//! Safe wrappers around the OpenImageIO shim (`shim/oiio_shim.cpp`, compiled by `build.rs`).
//!
//! The shim never lets a C++ exception escape; failures come back as a status code plus text.
//! These functions write straight to `path`; [`super::write`] wraps them in
//! [`super::write_atomic`].

use std::ffi::{c_char, c_int, CStr, CString};
use std::path::Path;

use super::{check_dims, srgb, Image, ImageError};

extern "C" {
    fn genpath_oiio_can_write(path: *const c_char) -> c_int;
    fn genpath_oiio_write_rgb(
        path: *const c_char,
        w: c_int,
        h: c_int,
        linear: *const f32,
        srgb8: *const u8,
        err: *mut c_char,
        errlen: usize,
    ) -> c_int;
    fn genpath_oiio_read_rgb(
        path: *const c_char,
        out: *mut f32,
        out_len: usize,
        w: *mut c_int,
        h: *mut c_int,
        is_float: *mut c_int,
        err: *mut c_char,
        errlen: usize,
    ) -> c_int;
}

/// Room for OIIO's error text; longer messages are truncated by the shim.
const ERR_LEN: usize = 1024;

/// Whether OpenImageIO has a writer for this file name's extension.
pub fn can_write(path: &Path) -> bool {
    let Ok(c_path) = c_path(path) else {
        return false;
    };
    // SAFETY: `c_path` is a NUL-terminated string that outlives the call; the shim only reads it.
    unsafe { genpath_oiio_can_write(c_path.as_ptr()) == 1 }
}

/// Writes `img` in the format named by the extension: float formats get the linear values,
/// integer formats get [`srgb::encode_u8`] bytes.
pub fn write(path: &Path, img: &Image) -> Result<(), ImageError> {
    check_dims(path, img)?;
    let write_err = |message: String| ImageError::Write {
        path: path.to_owned(),
        message,
    };
    let c_path = c_path(path).map_err(|e| write_err(e.to_string()))?;
    // check_dims guarantees both fit in an i32.
    let (w, h) = (img.width as c_int, img.height as c_int);
    let linear = img.pixels.as_flattened();
    let srgb8 = srgb::encode_image_u8(img);
    let mut err = [0u8; ERR_LEN];
    // SAFETY: `c_path` is NUL-terminated and outlives the call. check_dims verified
    // pixels.len() == w·h, so `linear` holds w·h·3 floats and `srgb8` w·h·3 bytes, exactly what
    // the shim reads for a w×h RGB image. `err` is writable for the ERR_LEN bytes we pass.
    let rc = unsafe {
        genpath_oiio_write_rgb(
            c_path.as_ptr(),
            w,
            h,
            linear.as_ptr(),
            srgb8.as_ptr(),
            err.as_mut_ptr().cast(),
            ERR_LEN,
        )
    };
    if rc == 0 {
        Ok(())
    } else {
        Err(write_err(err_text(&err)))
    }
}

/// Reads any image OpenImageIO can read as linear RGB (integer files are sRGB-decoded).
pub fn read(path: &Path) -> Result<Image, ImageError> {
    let (mut img, encoded) = read_encoded(path)?;
    if encoded {
        decode(&mut img);
    }
    Ok(img)
}

/// The image's sRGB-encoded values decoded to linear ones.
fn decode(img: &mut Image) {
    for px in &mut img.pixels {
        *px = px.map(srgb::decode);
    }
}

/// Reads any image OpenImageIO can read as it stores its values: integer files' values
/// normalised to [0, 1] but not decoded (`true` with them), float files' as they are.
pub fn read_encoded(path: &Path) -> Result<(Image, bool), ImageError> {
    let read_err = |message: String| ImageError::Read {
        path: path.to_owned(),
        message,
    };
    let c_path = c_path(path).map_err(|e| read_err(e.to_string()))?;
    let (mut w, mut h, mut is_float): (c_int, c_int, c_int) = (0, 0, 0);
    let mut err = [0u8; ERR_LEN];
    let mut buf: Vec<f32> = Vec::new();
    // The first call only learns the size (the buffer is empty); the second fills the buffer.
    for _ in 0..2 {
        // SAFETY: `c_path` is NUL-terminated and outlives the call; `buf` is writable for
        // `buf.len()` floats, the length we pass, and the shim writes no more than that; the
        // three out-pointers are valid `c_int`s; `err` is writable for ERR_LEN bytes.
        let rc = unsafe {
            genpath_oiio_read_rgb(
                c_path.as_ptr(),
                buf.as_mut_ptr(),
                buf.len(),
                &mut w,
                &mut h,
                &mut is_float,
                err.as_mut_ptr().cast(),
                ERR_LEN,
            )
        };
        match rc {
            0 => return Ok((to_image(w, h, &buf), is_float == 0)),
            1 => {
                let len = usize::try_from(w)
                    .ok()
                    .zip(usize::try_from(h).ok())
                    .and_then(|(w, h)| w.checked_mul(h)?.checked_mul(3))
                    .ok_or_else(|| read_err(format!("bad image size {w}×{h}")))?;
                buf = vec![0.0; len];
            }
            _ => return Err(read_err(err_text(&err))),
        }
    }
    Err(read_err("the file changed size while being read".into()))
}

/// Packs the shim's RGB floats; `w` and `h` were validated when the buffer was sized.
/// Integer files hold display values, float files linear values already.
fn to_image(w: c_int, h: c_int, rgb: &[f32]) -> Image {
    let mut img = Image::new(w as u32, h as u32);
    for (px, c) in img.pixels.iter_mut().zip(rgb.chunks_exact(3)) {
        *px = [c[0], c[1], c[2]];
    }
    img
}

/// Why a path cannot be handed to OpenImageIO's C API.
#[derive(Debug, thiserror::Error)]
enum CPathError {
    #[cfg(not(unix))]
    #[error("path is not valid UTF-8")]
    NotUtf8,
    #[error("path contains a NUL byte")]
    Nul,
}

fn c_path(path: &Path) -> Result<CString, CPathError> {
    #[cfg(unix)]
    let bytes = std::os::unix::ffi::OsStrExt::as_bytes(path.as_os_str()).to_vec();
    #[cfg(not(unix))]
    let bytes = path
        .to_str()
        .ok_or(CPathError::NotUtf8)?
        .as_bytes()
        .to_vec();
    CString::new(bytes).map_err(|_| CPathError::Nul)
}

fn err_text(err: &[u8]) -> String {
    let text = CStr::from_bytes_until_nul(err).map(|s| s.to_string_lossy().into_owned());
    match text {
        Ok(t) if !t.is_empty() => t,
        _ => "OpenImageIO failed without a message".into(),
    }
}
