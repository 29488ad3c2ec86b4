//! The commands of the `genpath` command line, one file each, and what they share.

pub mod args;
pub mod bench;
pub mod check;
pub mod compare;
pub mod learn;
pub mod merge;
pub mod reference;
pub mod render;
pub mod resume;
pub mod saved_plan;
pub mod session;
pub mod settings;
pub mod sweep;

use anyhow::{bail, Result};
use std::path::Path;

/// Fails before any work when an output cannot possibly be written.
pub fn check_output(path: &Path) -> Result<()> {
    genpath::image::check_format(path)?;
    check_dir(path)
}

/// Fails when the directory `path` would be written into does not exist.
pub fn check_dir(path: &Path) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        bail!(
            "{}: directory {} does not exist",
            path.display(),
            dir.display()
        );
    }
    Ok(())
}
