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

/// A small valid Mitsuba scene with `shapes` added, `film` as its film's content; written
/// into `dir` as `s.xml`.
fn xml_scene(dir: &Path, film: &str, shapes: &str) -> PathBuf {
    let text = format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm">{film}</film>
    </sensor>
    <shape type="rectangle">
        <emitter type="area"><rgb name="radiance" value="1"/></emitter>
    </shape>
    {shapes}
</scene>
"#
    );
    let path = dir.join("s.xml");
    std::fs::write(&path, text).unwrap();
    path
}

const BOX_FILM: &str =
    r#"<integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/>"#;

#[test]
fn a_small_xml_scene_renders() {
    let dir = tempfile::tempdir().unwrap();
    let scene = xml_scene(dir.path(), BOX_FILM, "");
    let out = dir.path().join("img.exr");
    let output = genpath(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--spp",
        "2",
        "-q",
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert!(out.is_file());
}

/// Each hostile XML scene: its file's content (or the shapes it adds), what the error must
/// name.
#[test]
fn hostile_xml_scenes_fail_clearly() {
    let cases: &[(&str, &str, &[&str])] = &[
        ("malformed", "<shape type=\"cube\">", &["s.xml", "malformed XML"]),
        ("unknown plugin", "<bsdf type=\"principled\" id=\"p\"/><shape type=\"cube\"><ref id=\"p\"/></shape>", &["s.xml:", "principled"]),
        ("unknown shape", "<shape type=\"instance\"/>", &["s.xml:", "instance"]),
        ("missing ref", "<shape type=\"cube\"><ref id=\"nowhere\"/></shape>", &["s.xml:", "nowhere"]),
        ("NaN in a transform", "<shape type=\"cube\"><transform name=\"to_world\"><translate x=\"NaN\"/></transform></shape>", &["s.xml:", "NaN"]),
        ("text in a float", "<shape type=\"cube\"><transform name=\"to_world\"><scale value=\"big\"/></transform></shape>", &["s.xml:", "big"]),
        ("unknown parameter", "<shape type=\"cube\"><float name=\"radius\" value=\"2\"/></shape>", &["s.xml:", "radius"]),
        ("analytic cylinder", "<shape type=\"cylinder\"/>", &["s.xml:", "cylinder"]),
        ("negative radius", "<shape type=\"sphere\"><float name=\"radius\" value=\"-1\"/></shape>", &["s.xml:", "radius", "-1"]),
        ("zero radius", "<shape type=\"sphere\"><float name=\"radius\" value=\"0\"/></shape>", &["s.xml:", "radius"]),
        ("NaN radius", "<shape type=\"sphere\"><float name=\"radius\" value=\"NaN\"/></shape>", &["s.xml:", "NaN"]),
        ("infinite center", "<shape type=\"sphere\"><point name=\"center\" x=\"inf\" y=\"0\" z=\"0\"/></shape>", &["s.xml:", "inf"]),
        ("huge sphere", "<shape type=\"sphere\"><float name=\"radius\" value=\"1e30\"/></shape>", &["s.xml:", "sphere"]),
        ("mirrored sphere", "<shape type=\"sphere\"><transform name=\"to_world\"><scale x=\"-1\"/></transform></shape>", &["s.xml:", "mirrors"]),
        ("center as a float", "<shape type=\"sphere\"><float name=\"center\" value=\"1\"/></shape>", &["s.xml:", "center"]),
        ("degenerate disk", "<shape type=\"disk\"><transform name=\"to_world\"><scale x=\"0\"/></transform></shape>", &["s.xml:", "disk"]),
        ("disk squashed to a segment", "<shape type=\"disk\"><transform name=\"to_world\"><matrix value=\"1 2 0 0  2 4 0 0  0 0 1 0  0 0 0 1\"/></transform></shape>", &["s.xml:", "disk"]),
        ("face_normals on a sphere", "<shape type=\"sphere\"><boolean name=\"face_normals\" value=\"true\"/></shape>", &["s.xml:", "face_normals"]),
        ("rough glass of equal indices", "<shape type=\"cube\"><bsdf type=\"roughdielectric\"><float name=\"int_ior\" value=\"1.2\"/><float name=\"ext_ior\" value=\"1.2\"/></bsdf></shape>", &["s.xml:", "must differ"]),
        ("rough glass in twosided", "<shape type=\"cube\"><bsdf type=\"twosided\"><bsdf type=\"roughdielectric\"/></bsdf></shape>", &["s.xml:", "transmission"]),
        ("unknown index of refraction", "<shape type=\"cube\"><bsdf type=\"dielectric\"><string name=\"int_ior\" value=\"unobtainium\"/></bsdf></shape>", &["s.xml:", "unobtainium", "bk7"]),
        ("negative index of refraction", "<shape type=\"cube\"><bsdf type=\"thindielectric\"><float name=\"ext_ior\" value=\"-1\"/></bsdf></shape>", &["s.xml:", "ext_ior"]),
        ("glass with a transmittance texture above 1", "<shape type=\"cube\"><bsdf type=\"dielectric\"><texture name=\"specular_transmittance\" type=\"checkerboard\"><rgb name=\"color0\" value=\"1.5\"/></texture></bsdf></shape>", &["s.xml:", "specular_transmittance", "beyond 1"]),
        ("glass in twosided", "<shape type=\"cube\"><bsdf type=\"twosided\"><bsdf type=\"dielectric\"/></bsdf></shape>", &["s.xml:", "transmission"]),
        ("glass that creates energy", "<shape type=\"cube\"><bsdf type=\"dielectric\"><rgb name=\"specular_reflectance\" value=\"1.5\"/></bsdf></shape>", &["s.xml:", "specular_reflectance"]),
        ("undefined parameter", "<shape type=\"cube\"><boolean name=\"flip_normals\" value=\"$flip\"/></shape>", &["s.xml:", "$flip"]),
    ];
    for (what, shapes, needles) in cases {
        let dir = tempfile::tempdir().unwrap();
        let scene = xml_scene(dir.path(), BOX_FILM, shapes);
        eprintln!("case: {what}");
        assert_fails(&scene, &[], &dir.path().join("o.exr"), needles);
    }
}

#[test]
fn xml_films_genpath_cannot_render_fail_clearly() {
    let cases: &[(&str, &[&str])] = &[
        (
            r#"<integer name="width" value="200000"/><integer name="height" value="200000"/><rfilter type="box"/>"#,
            &["s.xml:", "200000"],
        ),
        (
            r#"<integer name="width" value="8"/><integer name="height" value="8"/>"#,
            &["s.xml:", "gaussian"],
        ),
        (
            r#"<integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="gaussian"/>"#,
            &["s.xml:", "gaussian"],
        ),
    ];
    for (film, needles) in cases {
        let dir = tempfile::tempdir().unwrap();
        let scene = xml_scene(dir.path(), film, "");
        assert_fails(&scene, &[], &dir.path().join("o.exr"), needles);
    }
}

#[test]
fn recursive_xml_include_fails() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("loop.xml"),
        "<scene version=\"3.0.0\"><include filename=\"loop.xml\"/></scene>",
    )
    .unwrap();
    let scene = xml_scene(dir.path(), BOX_FILM, "<include filename=\"loop.xml\"/>");
    assert_fails(
        &scene,
        &[],
        &dir.path().join("o.exr"),
        &["loop.xml", "include"],
    );
}

#[test]
fn bad_ply_meshes_fail_clearly() {
    let header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let cases: &[(&str, &str, &[&str])] = &[
        ("truncated", "0 0 0\n1 0 0\n", &["m.ply"]),
        (
            "index out of range",
            "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
            &["m.ply", "7", "out of range"],
        ),
        (
            "text in a coordinate",
            "0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n",
            &["m.ply"],
        ),
    ];
    for (what, body, needles) in cases {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("m.ply"), format!("{header}{body}")).unwrap();
        let scene = xml_scene(
            dir.path(),
            BOX_FILM,
            r#"<shape type="ply"><string name="filename" value="m.ply"/></shape>"#,
        );
        eprintln!("case: {what}");
        assert_fails(&scene, &[], &dir.path().join("o.exr"), needles);
    }
    // A binary PLY cut short.
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = header.replace("ascii", "binary_little_endian").into_bytes();
    bytes.extend_from_slice(&[0u8; 20]);
    std::fs::write(dir.path().join("m.ply"), bytes).unwrap();
    let scene = xml_scene(
        dir.path(),
        BOX_FILM,
        r#"<shape type="ply"><string name="filename" value="m.ply"/></shape>"#,
    );
    assert_fails(&scene, &[], &dir.path().join("o.exr"), &["m.ply"]);
}

#[test]
fn defines_are_only_for_xml_scenes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene_with(dir.path(), None, None, None);
    assert_fails(
        &scene,
        &["-D", "res=8"],
        &dir.path().join("o.exr"),
        &["-D", "res"],
    );
}
