//! Finds the Embree headers, generates bindings for them and links the matching library.
//!
//! Probe order: `$EMBREE_DIR/include/embree4`, `$EMBREE_DIR/include/embree3`,
//! `/usr/include/embree4`, `/usr/include/embree3`. The major version comes from
//! `RTC_VERSION_MAJOR` in `rtcore_config.h` and becomes `cfg(embree4)` or `cfg(embree3)`.

use std::env;
use std::fs;
use std::path::{Path, PathBuf};
use std::process;

/// Where the headers were found and which major version they declare.
struct Embree {
    include_dir: PathBuf,
    lib_dir: Option<PathBuf>,
    major: u32,
}

fn main() {
    println!("cargo::rustc-check-cfg=cfg(embree3)");
    println!("cargo::rustc-check-cfg=cfg(embree4)");
    println!("cargo:rerun-if-changed=build.rs");

    let embree = probe().unwrap_or_else(|| {
        eprintln!(
            "error: Embree 3 or 4 headers not found: install them (`apt-get install \
             libembree-dev`), or set EMBREE_DIR to an Embree install prefix, or build without \
             Embree (`cargo build --no-default-features --features obvhs`)."
        );
        process::exit(1);
    });

    println!("cargo:rustc-cfg=embree{}", embree.major);
    if let Some(lib_dir) = &embree.lib_dir {
        println!("cargo:rustc-link-search=native={}", lib_dir.display());
    }
    println!("cargo:rustc-link-lib=dylib=embree{}", embree.major);
    // Dependents see these as DEP_EMBREE_INCLUDE and DEP_EMBREE_VERSION_MAJOR.
    println!("cargo:include={}", embree.include_dir.display());
    println!("cargo:version_major={}", embree.major);

    generate_bindings(&embree);
}

/// The first candidate directory that holds `rtcore.h` with a readable major version.
fn probe() -> Option<Embree> {
    println!("cargo:rerun-if-env-changed=EMBREE_DIR");
    let prefix = env::var_os("EMBREE_DIR").map(PathBuf::from);

    let mut candidates: Vec<(PathBuf, Option<PathBuf>)> = Vec::new();
    if let Some(prefix) = &prefix {
        for sub in ["include/embree4", "include/embree3"] {
            candidates.push((prefix.join(sub), Some(prefix.join("lib"))));
        }
    }
    for dir in ["/usr/include/embree4", "/usr/include/embree3"] {
        candidates.push((PathBuf::from(dir), None));
    }

    let found = candidates.into_iter().find_map(|(include_dir, lib_dir)| {
        if !include_dir.join("rtcore.h").is_file() {
            return None;
        }
        println!(
            "cargo:rerun-if-changed={}",
            include_dir.join("rtcore_config.h").display()
        );
        let major = read_major(&include_dir.join("rtcore_config.h"))?;
        match major {
            3 | 4 => Some(Embree {
                include_dir,
                lib_dir,
                major,
            }),
            _ => {
                println!(
                    "cargo:warning=skipping {}: Embree {major} is not supported (need 3 or 4)",
                    include_dir.display()
                );
                None
            }
        }
    });
    if let (Some(prefix), Some(found)) = (&prefix, &found) {
        if found.lib_dir.is_none() {
            println!(
                "cargo:warning=EMBREE_DIR={} has no include/embree4 or include/embree3; using {}",
                prefix.display(),
                found.include_dir.display()
            );
        }
    }
    found
}

/// `RTC_VERSION_MAJOR` from `rtcore_config.h`, e.g. `#define RTC_VERSION_MAJOR 3`.
fn read_major(config: &Path) -> Option<u32> {
    let text = fs::read_to_string(config).ok()?;
    text.lines().find_map(|line| {
        let mut words = line.split_whitespace();
        match (words.next(), words.next(), words.next()) {
            (Some("#define"), Some("RTC_VERSION_MAJOR"), Some(value)) => value.parse().ok(),
            _ => None,
        }
    })
}

fn generate_bindings(embree: &Embree) {
    let include_dir = &embree.include_dir;
    let header = include_dir.join("rtcore.h");
    let mut builder = bindgen::Builder::default()
        .header(header.to_string_lossy())
        .clang_arg(format!("-I{}", include_dir.display()))
        .allowlist_function("rtc.*")
        .allowlist_type("RTC.*")
        .allowlist_var("RTC.*")
        // Plain integer constants: Embree's enums are bit flags that get or-ed together.
        .default_enum_style(bindgen::EnumVariation::Consts)
        .prepend_enum_name(false)
        .layout_tests(true)
        .derive_default(true)
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()));
    if embree.major == 3 {
        // lib.rs wraps rtcIntersect1/8/16 and rtcOccluded1/8/16 in Embree 4's signatures; the
        // other query entry points keep Embree 3's argument order, so they are left out rather
        // than exported under an Embree 4 name with an Embree 3 signature.
        builder = builder.blocklist_function("rtc(Intersect|Occluded)(4|1M|1Mp|NM|Np)");
    }
    let bindings = builder.generate().unwrap_or_else(|err| {
        eprintln!("error: bindgen failed on {}: {err}", header.display());
        process::exit(1);
    });

    let out =
        PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR")).join("bindings.rs");
    if let Err(err) = bindings.write_to_file(&out) {
        eprintln!("error: cannot write {}: {err}", out.display());
        process::exit(1);
    }
}
