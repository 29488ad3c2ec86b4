//! Helpers shared by the integration tests: scenes written into temporary directories.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// Writes `files` (name, contents) into `dir` and returns the path of the first one.
pub fn write_files(dir: &Path, files: &[(&str, &str)]) -> PathBuf {
    for (name, text) in files {
        std::fs::write(dir.join(name), text).expect("write test file");
    }
    dir.join(files[0].0)
}

/// A scene TOML around `obj`, with the camera at `origin` looking at `target`.
pub fn scene_toml(obj: &str, origin: [f32; 3], target: [f32; 3], size: u32) -> String {
    format!(
        "mesh = \"{obj}\"\n[camera]\norigin = {origin:?}\ntarget = {target:?}\nup = [0.0, 1.0, 0.0]\n\
         fov_x_deg = 60.0\nwidth = {size}\nheight = {size}\n"
    )
}

/// A closed cube `[-1, 1]³` whose six faces all use material `box` and face inwards.
pub fn closed_box_obj() -> String {
    let mut obj = String::from("mtllib box.mtl\nusemtl box\n");
    for z in [-1.0, 1.0] {
        for y in [-1.0, 1.0] {
            for x in [-1.0, 1.0] {
                obj += &format!("v {x} {y} {z}\n");
            }
        }
    }
    // Vertex (x, y, z) has index 1 + (x>0) + 2(y>0) + 4(z>0). Quads wound so that
    // cross(v1 − v0, v2 − v0) points into the box.
    obj += "f 1 2 4 3\n"; // z = -1, normal +z
    obj += "f 5 7 8 6\n"; // z = +1, normal -z
    obj += "f 1 5 6 2\n"; // y = -1, normal +y
    obj += "f 3 4 8 7\n"; // y = +1, normal -y
    obj += "f 1 3 7 5\n"; // x = -1, normal +x
    obj += "f 2 6 8 4\n"; // x = +1, normal -x
    obj
}
