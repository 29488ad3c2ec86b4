//! Malformed scenes, missing files and impossible flags: a clear error and no output.

use super::*;

#[test]
fn a_valid_small_scene_renders_with_json_beside_it() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), None, None, None);
    let out = dir.path().join("img.exr");
    let output = genpath(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--spp",
        "2",
        "--quiet",
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(out.is_file());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("img.exr.json")).unwrap())
            .unwrap();
    assert_eq!(json["settings"]["spp"], 2);
    assert!(json["rays"]["total"].as_u64().unwrap() >= 8 * 8 * 2);
}

#[test]
fn malformed_toml() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), Some("mesh = \"s.obj\"\n[camera\n"), None, None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["s.toml", "line 2"],
    );
}

#[test]
fn unknown_toml_field() {
    let dir = tempfile::tempdir().unwrap();
    let toml =
        common::scene_toml("s.obj", [0.0, 3.0, 3.0], [0.0, 0.0, 0.0], 8) + "fov_y_deg = 3.0\n";
    let scene = scene_with(dir.path(), Some(&toml), None, None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["s.toml", "unknown field", "fov_y_deg"],
    );
}

#[test]
fn bad_camera_field() {
    let dir = tempfile::tempdir().unwrap();
    let toml = common::scene_toml("s.obj", [0.0, 3.0, 3.0], [0.0, 3.0, 3.0], 8);
    let scene = scene_with(dir.path(), Some(&toml), None, None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["s.toml", "camera.target"],
    );
}

#[test]
fn missing_obj() {
    let dir = tempfile::tempdir().unwrap();
    let toml = common::scene_toml("nothere.obj", [0.0, 3.0, 3.0], [0.0, 0.0, 0.0], 8);
    let scene = scene_with(dir.path(), Some(&toml), None, None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["nothere.obj", "cannot read"],
    );
}

#[test]
fn missing_mtl() {
    let dir = tempfile::tempdir().unwrap();
    let obj = GOOD_OBJ.replace("m.mtl", "gone.mtl");
    let scene = scene_with(dir.path(), None, Some(&obj), None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["gone.mtl", "cannot read"],
    );
}

#[test]
fn undefined_material() {
    let dir = tempfile::tempdir().unwrap();
    let obj = GOOD_OBJ.replace("usemtl white", "usemtl chalk");
    let scene = scene_with(dir.path(), None, Some(&obj), None);
    assert_fails(&scene, &[], &dir.path().join("o.exr"), &["s.obj", "chalk"]);
}

#[test]
fn nan_vertex() {
    let dir = tempfile::tempdir().unwrap();
    let obj = GOOD_OBJ.replace("v 1 1 0", "v 1 NaN 0");
    let scene = scene_with(dir.path(), None, Some(&obj), None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["s.obj:4", "non-finite", "NaN"],
    );
}

#[test]
fn malformed_obj_and_mtl_lines() {
    let dir = tempfile::tempdir().unwrap();
    let obj = GOOD_OBJ.replace("f 4 5 6", "f 4 5 9");
    let scene = scene_with(dir.path(), None, Some(&obj), None);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["s.obj:11", "out of range"],
    );
    let mtl = GOOD_MTL.replace("Kd 0.5 0.5 0.5", "Kd 0.5 0.5");
    let scene = scene_with(dir.path(), None, None, Some(&mtl));
    assert_fails(&scene, &[], &dir.path().join("o.exr"), &["m.mtl:4", "Kd"]);
}

#[test]
fn no_emitter() {
    let dir = tempfile::tempdir().unwrap();
    let mtl = GOOD_MTL.replace("Ke 1 1 1", "Kd 0.2 0.2 0.2");
    let scene = scene_with(dir.path(), None, None, Some(&mtl));
    assert_fails(&scene, &[], &dir.path().join("o.exr"), &["no emitter"]);
}

#[test]
fn unwritable_output() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), None, None, None);
    // A regular file used as a directory: unwritable even for root.
    std::fs::write(dir.path().join("afile"), "x").unwrap();
    assert_fails(&scene, &[], &dir.path().join("afile/o.exr"), &["afile"]);
    assert_fails(
        &scene,
        &[],
        &dir.path().join("missing_dir/o.exr"),
        &["missing_dir"],
    );
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.unknownformat"),
        &["o.unknownformat"],
    );
}

#[test]
fn impossible_flags() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), None, None, None);
    let out = dir.path().join("o.exr");
    assert_fails(&scene, &["--spp", "0"], &out, &["--spp"]);
    assert_fails(&scene, &["--threads", "0"], &out, &["--threads"]);
    assert_fails(
        &scene,
        &["--max-bounces", "100000"],
        &out,
        &["--max-bounces"],
    );
    assert_fails(&scene, &["--accel", "optix"], &out, &["--accel"]);
    assert_fails(&scene, &["--width", "999999999"], &out, &["--width"]);
}
