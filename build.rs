//! Build script: with feature `oiio`, compiles the OpenImageIO C++ shim and links OIIO.
//!
//! Without the feature nothing is compiled or linked, so the pure-Rust build needs no C++
//! toolchain. OIIO is found through pkg-config (`OpenImageIO.pc`); point `PKG_CONFIG_PATH` at a
//! custom installation to use it instead of the system one.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if std::env::var_os("CARGO_FEATURE_OIIO").is_some() {
        build_oiio_shim();
    }
}

fn build_oiio_shim() {
    println!("cargo:rerun-if-changed=shim/oiio_shim.cpp");
    // 2.2 is the oldest API the shim is written against (Debian 12 ships 2.4, Debian 13 2.5).
    let oiio = match pkg_config::Config::new()
        .atleast_version("2.2")
        .probe("OpenImageIO")
    {
        Ok(lib) => lib,
        Err(e) => {
            // One actionable sentence, without a panic's backtrace noise.
            eprintln!("{e}");
            eprintln!(
                "error: OpenImageIO (>= 2.2) was not found by pkg-config: install it \
                 (`apt-get install libopenimageio-dev`), set PKG_CONFIG_PATH to a directory \
                 holding OpenImageIO.pc, or build without it \
                 (`cargo build --no-default-features --features obvhs`)"
            );
            std::process::exit(1);
        }
    };
    cc::Build::new()
        .cpp(true)
        .std("c++17")
        .includes(&oiio.include_paths)
        .file("shim/oiio_shim.cpp")
        .compile("genpath_oiio_shim");
}
