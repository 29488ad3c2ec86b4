//! Images in memory and on disk.
//!
//! [`write`] picks the format from the file extension and writes through OpenImageIO
//! (feature `oiio`, `oiio.rs` + `shim/oiio_shim.cpp`) or through the pure-Rust `exr`/`png`
//! crates (`rust_writers.rs`). Every file is written under a temporary name in the target
//! directory and renamed into place, so a failed write never leaves a partial file.

use std::path::{Path, PathBuf};

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
        Self { width, height, pixels: vec![[0.0; 3]; width as usize * height as usize] }
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
