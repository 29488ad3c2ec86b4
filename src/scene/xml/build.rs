//! A parsed Mitsuba document as a genpath [`Scene`]: the sensor, film, sampler and
//! integrator as the camera and render defaults, the shapes as triangles, the BSDFs and
//! area emitters as materials, the `constant` or `envmap` emitter as the environment, the
//! `point` and `directional` emitters as delta lights. Every plugin and parameter genpath
//! does not implement is
//! refused with its file and line ([`Props::finish`]).

use super::emitters::SceneLights;
use super::parse::Doc;
use super::props::Props;
use super::shapes::{self, Placement};
use super::spectrum::ColorUse;
use super::textures::{material_textures, Textures};
use crate::accel::{Analytic, TriangleMesh};
use crate::math::triangle_area;
use crate::scene::{
    Camera, Dielectric, Emitters, Glossy, Material, MaterialTextures, RenderDefaults, Scene,
    SceneError, Shading, MAX_BOUNCES_LIMIT, MAX_IMAGE_SIDE, RR_START,
};
use glam::{DMat3, DVec3, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Geometry and materials gathered from the shapes.
#[derive(Default)]
struct Geometry {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    shading: Shading,
    material_of: Vec<u32>,
    materials: Vec<Material>,
    /// Spheres and disks, with their materials: primitives after the triangles.
    shapes: Vec<Analytic>,
    shape_material: Vec<u32>,
    /// Material index of each (BSDF object, emitter object) pair already made.
    made: HashMap<(Option<usize>, Option<usize>), u32>,
    degenerate: usize,
    /// The mesh and texture files the shapes were read from.
    files: Vec<PathBuf>,
    /// The BSDFs' textures, and the files they were read from.
    textures: Textures,
}

pub fn build(doc: &Doc, path: &Path) -> Result<Scene, SceneError> {
    let mut warnings = doc.warnings.clone();
    let root = Props::new(doc, 0);
    let mut sensor = None;
    let mut integrator = None;
    let mut lights = SceneLights::default();
    let mut geometry = Geometry::default();
    for (prop, i) in root.children() {
        let p = Props::new(doc, i);
        match p.object().tag.as_str() {
            "sensor" if sensor.is_some() => {
                return Err(p.error("a second sensor (genpath renders one)"))
            }
            "sensor" => sensor = Some(i),
            "integrator" if integrator.is_some() => return Err(p.error("a second integrator")),
            "integrator" => integrator = Some(i),
            "shape" => shape(&p, &mut geometry, &mut warnings)?,
            // Defined for reference by id: built where they are used.
            "bsdf" | "texture" => {}
            "emitter" => {
                if !lights.add(&p, &mut geometry.files, &mut warnings)? {
                    return Err(emitter_refusal(&p));
                }
            }
            _ => return Err(p.error("genpath does not implement this plugin")),
        }
        prop.used.set(true);
    }
    root.finish()?;
    let Some(sensor) = sensor else {
        return Err(doc.error(root.loc(), "the scene has no <sensor>"));
    };
    let (camera, spp) = self::sensor(&Props::new(doc, sensor), &mut warnings)?;
    let (max_bounces, hide_emitters) = match integrator {
        Some(i) => self::integrator(&Props::new(doc, i), &mut warnings)?,
        None => (MAX_BOUNCES_LIMIT, false),
    };
    if geometry.degenerate > 0 {
        warnings.push(format!(
            "{}: {} degenerate (zero-area) triangles dropped",
            path.display(),
            geometry.degenerate
        ));
    }
    let Geometry {
        positions,
        triangles,
        shading,
        mut material_of,
        materials,
        shapes,
        shape_material,
        files,
        ..
    } = geometry;
    if triangles.is_empty() && shapes.is_empty() {
        return Err(doc.error(root.loc(), "the scene has no shapes"));
    }
    let mut mesh = TriangleMesh::new(positions, triangles);
    mesh.shapes = shapes;
    material_of.extend(shape_material);
    let emitters = Emitters::new(&mesh, |prim| {
        materials[material_of[prim as usize] as usize].is_emitter()
    });
    let SceneLights {
        environment,
        delta_lights,
    } = lights;
    if (emitters.prims.is_empty() || emitters.total_area <= 0.0)
        && environment.is_none()
        && delta_lights.is_empty()
    {
        return Err(doc.error(
            root.loc(),
            "the scene has no emitter (genpath needs an `area` emitter on some shape, or a `constant`, `envmap`, `point`, `spot` or `directional` one)",
        ));
    }
    let extent = extent(&mesh);
    Ok(Scene {
        path: path.to_path_buf(),
        camera,
        mesh,
        shading,
        materials,
        material_of,
        emitters,
        environment,
        delta_lights,
        lights: Default::default(),
        hide_emitters,
        render: RenderDefaults { max_bounces, spp },
        extent,
        warnings,
        files: doc.files.iter().cloned().chain(files).collect(),
    })
}

/// The largest absolute coordinate of the mesh's vertices and analytic shapes.
fn extent(mesh: &TriangleMesh) -> f32 {
    mesh.shapes.iter().fold(
        mesh.positions
            .iter()
            .fold(0.0f32, |m, p| m.max(p.abs().max_element())),
        |m, s| {
            let (lo, hi) = s.bounds();
            m.max(lo.abs().max(hi.abs()).max_element() as f32)
        },
    )
}

fn emitter_refusal(p: &Props) -> SceneError {
    match p.object().plugin.as_str() {
        "constant" | "envmap" => p.error("an environment emitter belongs in the scene, not in a shape"),
        "point" | "spot" | "directional" => p.error("a delta light belongs in the scene, not in a shape"),
        "area" => p.error("an area emitter must be nested in a shape"),
        other => p.error(format!(
            "genpath does not implement the `{other}` emitter (supported: area, nested in a shape; constant, envmap, point, spot, directional)"
        )),
    }
}

/// One shape's triangles, or its analytic shape, with its material.
fn shape(p: &Props, g: &mut Geometry, warnings: &mut Vec<String>) -> Result<(), SceneError> {
    if let Some(shape) = shapes::analytic(p, warnings)? {
        let material = shape_material(p, g, warnings)?;
        p.finish()?;
        if g.materials[material as usize].glossy.is_anisotropic() {
            return Err(p.error("an anisotropic BSDF on an analytic shape: genpath reads the tangent of anisotropic roughness from triangles only"));
        }
        if g.materials[material as usize].perturbation().is_some() {
            return Err(p.error("a normalmap or bumpmap on an analytic shape: genpath reads the tangents (dp/du, dp/dv) that they follow from triangles only"));
        }
        g.shapes.push(shape);
        g.shape_material.push(material);
        return Ok(());
    }
    let how = Placement {
        to_world: p.transform("to_world")?,
        flip_normals: p.bool("flip_normals", false)?,
        face_normals: p.bool("face_normals", false)?,
    };
    let raw = shapes::load(p, &mut g.files)?;
    raw.check_indices(&p.what())
        .map_err(|e| p.error(e.to_string()))?;
    let material = shape_material(p, g, warnings)?;
    p.finish()?;
    let placed = shapes::place(raw, &how, p.loc(), p)?;
    let m = &g.materials[material as usize];
    if m.glossy.is_anisotropic() || m.perturbation().is_some() {
        tangents_kept(p, &how, placed.uvs.is_some())?;
    }
    if placed.normals.is_some() && g.materials[material as usize].is_emitter() {
        // Mitsuba's area emitter then emits, and converts its light samples' densities, by
        // the shading normal, while a ray that finds it converts by the geometric one.
        return Err(p.error(
            "an area emitter on a shape shaded with vertex normals that differ from its faces' normals: genpath emits by the faces' normals, where Mitsuba mixes both; add <boolean name=\"face_normals\" value=\"true\"/>",
        ));
    }
    if placed.zero_normals > 0 {
        warnings.push(format!(
            "{}: {} vertices have no usable normal (zero, or around degenerate faces only); their triangles shade flat",
            p.what(),
            placed.zero_normals
        ));
    }
    let base = g.positions.len() as u32;
    g.shading.push_shape(
        g.positions.len(),
        placed.positions.len(),
        placed.normals.as_deref(),
        placed.uvs.as_deref(),
    );
    g.positions.extend(placed.positions);
    for t in placed.triangles {
        let t = t.map(|i| base + i);
        if triangle_area(t.map(|i| g.positions[i as usize])) > 0.0 {
            g.triangles.push(t);
            g.material_of.push(material);
        } else {
            g.degenerate += 1;
        }
    }
    Ok(())
}

/// Refuses the triangle shapes whose tangents (Mitsuba's `dp/du` and `dp/dv`, which
/// anisotropic roughness and normal and bump maps follow) genpath cannot reproduce: a mesh
/// without texture coordinates under `flip_normals` (whose `p1 − p0` and `p2 − p0` genpath's
/// reversed winding changes). A `cube` has Mitsuba's texture coordinates, affine over each
/// face, so its tangents are Mitsuba's whatever the triangulation.
fn tangents_kept(p: &Props, how: &Placement, has_uvs: bool) -> Result<(), SceneError> {
    if !has_uvs && how.flip_normals {
        return Err(p.error("an anisotropic, normal-mapped or bump-mapped BSDF on a mesh without texture coordinates and with `flip_normals`: Mitsuba's tangents p1 − p0 and p2 − p0 follow a vertex order genpath's flipped winding does not keep"));
    }
    Ok(())
}

/// The material of shape `p`: its BSDF (Mitsuba's default diffuse without one) and area
/// emitter, made once per pair.
fn shape_material(
    p: &Props,
    g: &mut Geometry,
    warnings: &mut Vec<String>,
) -> Result<u32, SceneError> {
    let bsdfs = p.children_of("bsdf");
    let emitters = p.children_of("emitter");
    if bsdfs.len() > 1 || emitters.len() > 1 {
        return Err(p.error("a shape takes at most one BSDF and one emitter"));
    }
    let key = (bsdfs.first().copied(), emitters.first().copied());
    let material = match g.made.get(&key) {
        Some(&m) => m,
        None => {
            let mut m = match key.0 {
                Some(b) => {
                    let m = bsdf(&Props::new(p.doc, b), &mut g.textures, warnings)?;
                    g.files.append(&mut g.textures.files);
                    m
                }
                // Mitsuba's default BSDF: diffuse 0.5, black on an emitter.
                None if key.1.is_some() => diffuse(DVec3::ZERO, "default black diffuse".into()),
                None => diffuse(DVec3::splat(0.5), "default diffuse".into()),
            };
            if let Some(e) = key.1 {
                m.ke = area_emitter(&Props::new(p.doc, e), warnings)?;
                if m.opacity().is_some() {
                    return Err(p.error("a `mask` on an area emitter: genpath's rays pass through a masked surface before it could emit (Mitsuba counts its emission, then passes); put the mask on another shape"));
                }
            }
            g.materials.push(m);
            let index = g.materials.len() as u32 - 1;
            g.made.insert(key, index);
            index
        }
    };
    Ok(material)
}

fn diffuse(kd: DVec3, name: String) -> Material {
    Material {
        name,
        kd: kd.as_vec3(),
        ks: Vec3::ZERO,
        glossy: Glossy::None,
        mirror: false,
        ke: Vec3::ZERO,
        two_sided: false,
        conductor: None,
        dielectric: None,
        textures: None,
    }
}

/// A BSDF as a material (one-sided unless `twosided`), its textures built through `tex`.
pub(super) fn bsdf(
    p: &Props,
    tex: &mut Textures,
    warnings: &mut Vec<String>,
) -> Result<Material, SceneError> {
    let name = p
        .object()
        .id
        .clone()
        .unwrap_or_else(|| format!("{} at {}", p.what(), p.doc.at(p.loc())));
    let m = match p.object().plugin.as_str() {
        "diffuse" => {
            let kd = tex.reflectance(p, "reflectance", 0.5, warnings)?;
            let mut m = diffuse(kd.constant, name);
            m.textures = material_textures(MaterialTextures { kd: kd.texture, ..Default::default() });
            m
        }
        "twosided" => {
            let inner = p.children_of("bsdf");
            let [only] = inner[..] else {
                return Err(p.error("genpath's twosided takes exactly one nested BSDF (different front and back BSDFs are not supported)"));
            };
            let q = Props::new(p.doc, only);
            match q.object().plugin.as_str() {
                "twosided" => return Err(q.error("a twosided BSDF inside a twosided BSDF")),
                // As Mitsuba's twosided refuses them.
                "dielectric" | "thindielectric" | "roughdielectric" => return Err(q.error("only materials without a transmission component can be nested in twosided (a dielectric is two-sided already)")),
                "mask" => return Err(q.error("only materials without a transmission component can be nested in twosided (a mask transmits: put the twosided inside the mask)")),
                _ => {}
            }
            let mut m = match q.object().plugin.as_str() {
                // The map sees `wo` mirrored where it is behind the surface.
                "normalmap" | "bumpmap" => {
                    let m = super::maps::adapter(&q, name.clone(), tex, warnings, true, bsdf)?;
                    q.finish()?;
                    m
                }
                _ => bsdf(&q, tex, warnings)?,
            };
            m.two_sided = true;
            m.name = name;
            m
        }
        "conductor" => conductor(p, name, tex, warnings)?,
        "roughconductor" => super::rough::rough_conductor(p, name, tex, warnings)?,
        "roughplastic" => super::rough::rough_plastic(p, name, tex, warnings)?,
        "roughdielectric" => super::rough::rough_dielectric(p, name, tex, warnings)?,
        "plastic" => super::rough::smooth_plastic(p, name, tex, warnings)?,
        "dielectric" => dielectric(p, name, false, tex, warnings)?,
        "thindielectric" => dielectric(p, name, true, tex, warnings)?,
        "normalmap" | "bumpmap" => super::maps::adapter(p, name, tex, warnings, false, bsdf)?,
        "mask" => super::mask::mask(p, name, tex, warnings, bsdf)?,
        other => return Err(p.error(format!("genpath does not implement the `{other}` BSDF (supported: diffuse, twosided, conductor, roughconductor, plastic, roughplastic, dielectric, roughdielectric, thindielectric, normalmap, bumpmap, mask)"))),
    };
    p.finish()?;
    Ok(m)
}

/// Mitsuba's smooth `conductor`: a mirror with the Fresnel reflectance of (η, k), from a
/// named preset or given; η = 0, k = 1 (a perfect mirror) for `material="none"`, the default.
fn conductor(
    p: &Props,
    name: String,
    tex: &mut Textures,
    warnings: &mut Vec<String>,
) -> Result<Material, SceneError> {
    let ks = tex.reflectance(p, "specular_reflectance", 1.0, warnings)?;
    let (eta, k) = super::ior::complex_ior(p, warnings)?;
    Ok(Material {
        name,
        kd: Vec3::ZERO,
        ks: ks.constant.as_vec3(),
        glossy: Glossy::None,
        mirror: true,
        ke: Vec3::ZERO,
        two_sided: false,
        conductor: Some([eta.as_vec3(), k.as_vec3()]),
        dielectric: None,
        textures: material_textures(MaterialTextures {
            ks: ks.texture,
            ..Default::default()
        }),
    })
}

/// Mitsuba's smooth `dielectric` (or, `thin`, its `thindielectric`): a two-sided delta BSDF
/// of η = `int_ior` / `ext_ior` (numbers or Mitsuba's names; bk7 in air by default) that
/// reflects with `specular_reflectance` and transmits with `specular_transmittance` (each 1
/// by default, or a texture).
fn dielectric(
    p: &Props,
    name: String,
    thin: bool,
    tex: &mut Textures,
    warnings: &mut Vec<String>,
) -> Result<Material, SceneError> {
    let int_ior = super::ior::read(p, "int_ior", "bk7")?;
    let ext_ior = super::ior::read(p, "ext_ior", "air")?;
    let transmittance = tex.reflectance(p, "specular_transmittance", 1.0, warnings)?;
    let reflectance = tex.reflectance(p, "specular_reflectance", 1.0, warnings)?;
    Ok(Material {
        name,
        kd: Vec3::ZERO,
        ks: reflectance.constant.as_vec3(),
        glossy: Glossy::None,
        mirror: true,
        ke: Vec3::ZERO,
        two_sided: true,
        conductor: None,
        dielectric: Some(Dielectric {
            // In single precision, as Mitsuba computes it.
            eta: int_ior / ext_ior,
            transmittance: transmittance.constant.as_vec3(),
            thin,
        }),
        textures: material_textures(MaterialTextures {
            ks: reflectance.texture,
            transmittance: transmittance.texture,
            ..Default::default()
        }),
    })
}

fn area_emitter(p: &Props, warnings: &mut Vec<String>) -> Result<Vec3, SceneError> {
    if p.object().plugin != "area" {
        return Err(emitter_refusal(p));
    }
    let radiance = p
        .color("radiance", ColorUse::Emission, warnings)?
        .ok_or_else(|| p.error("needs a `radiance`"))?;
    if radiance.min_element() < 0.0 || radiance.as_vec3().max_element() > 1e30 {
        return Err(p.error(format!("`radiance` {radiance} is negative or beyond 1e30")));
    }
    p.finish()?;
    Ok(radiance.as_vec3())
}

/// The perspective sensor, its film and sampler: the camera and the default spp.
fn sensor(p: &Props, warnings: &mut Vec<String>) -> Result<(Camera, Option<u32>), SceneError> {
    if p.object().plugin != "perspective" {
        return Err(p.error(format!(
            "genpath does not implement the `{}` sensor (supported: perspective)",
            p.object().plugin
        )));
    }
    let films = p.children_of("film");
    let (width, height) = match films[..] {
        [] => return Err(p.error("no <film>: Mitsuba's default hdrfilm uses a gaussian filter, which genpath does not implement; add <film type=\"hdrfilm\"> with <rfilter type=\"box\"/>")),
        [f] => film(&Props::new(p.doc, f), warnings)?,
        _ => return Err(p.error("more than one <film>")),
    };
    let spp = match p.children_of("sampler")[..] {
        [] => 4,
        [s] => sampler(&Props::new(p.doc, s), warnings)?,
        _ => return Err(p.error("more than one <sampler>")),
    };
    let aspect = f64::from(width) / f64::from(height);
    let fov_x = fov_x(p, aspect)?;
    let near = p.float("near_clip", 1e-2)?;
    let far = p.float("far_clip", 1e4)?;
    if !(near >= 0.0 && far > near) {
        return Err(p.error(format!(
            "clip distances near {near}, far {far} are not 0 ≤ near < far"
        )));
    }
    for name in ["principal_point_offset_x", "principal_point_offset_y"] {
        if p.float(name, 0.0)? != 0.0 {
            return Err(p.error(format!("`{name}` is not supported")));
        }
    }
    p.ignore(
        &["shutter_open", "shutter_close"],
        "genpath renders no motion",
        warnings,
    );
    let m = p.transform("to_world")?;
    let linear = DMat3::from_mat4(m);
    let [x, y, z] = [linear.x_axis, linear.y_axis, linear.z_axis];
    let orthonormal = [x, y, z].iter().all(|a| (a.length() - 1.0).abs() < 1e-4)
        && x.dot(y).abs() < 1e-4
        && y.dot(z).abs() < 1e-4
        && x.dot(z).abs() < 1e-4;
    if !orthonormal {
        return Err(
            p.error("scale factors in the camera's to_world are not allowed (as in Mitsuba)")
        );
    }
    p.finish()?;
    // Mitsuba's camera looks along local +z with local +x to the image's left.
    let camera = Camera::with_frame(
        m.transform_point3(DVec3::ZERO).as_vec3(),
        [
            z.normalize().as_vec3(),
            (-x).normalize().as_vec3(),
            y.normalize().as_vec3(),
        ],
        fov_x.to_radians() as f32,
        (width, height),
        (near as f32, far as f32),
    );
    Ok((camera, Some(spp)))
}

/// The horizontal field of view in degrees (Mitsuba's `parse_fov`).
fn fov_x(p: &Props, aspect: f64) -> Result<f64, SceneError> {
    let half_tan = |deg: f64| (0.5 * deg.to_radians()).tan();
    let to_deg = |t: f64| (2.0 * t.atan()).to_degrees();
    let (fov, axis) = if p.get("fov").is_some() {
        if p.get("focal_length").is_some() {
            return Err(p.error("give either `fov` or `focal_length`, not both"));
        }
        let axis = p.string("fov_axis")?.unwrap_or("x").to_ascii_lowercase();
        let axis = match axis.as_str() {
            "smaller" if aspect > 1.0 => "y".to_string(),
            "smaller" => "x".to_string(),
            "larger" if aspect > 1.0 => "x".to_string(),
            "larger" => "y".to_string(),
            _ => axis,
        };
        (p.float("fov", 0.0)?, axis)
    } else {
        let f = p.string("focal_length")?.unwrap_or("50mm");
        let mm = super::numbers::parse_f64(f.strip_suffix("mm").unwrap_or(f))
            .filter(|v| *v > 0.0)
            .ok_or_else(|| p.error(format!("focal_length \"{f}\" is not of the form <x>mm")))?;
        (
            to_deg((36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * mm)),
            "diagonal".to_string(),
        )
    };
    let x = match axis.as_str() {
        "x" => fov,
        "y" => to_deg(half_tan(fov) * aspect),
        "diagonal" => {
            let diagonal = 2.0 * half_tan(fov);
            to_deg(0.5 * diagonal / (1.0 + 1.0 / (aspect * aspect)).sqrt())
        }
        other => {
            return Err(p.error(format!(
                "`fov_axis` \"{other}\" is not x, y, diagonal, smaller or larger"
            )))
        }
    };
    if !(x > 0.0 && x < 180.0) {
        return Err(p.error(format!(
            "the horizontal field of view {x}° is not in (0, 180)"
        )));
    }
    Ok(x)
}

fn film(p: &Props, warnings: &mut Vec<String>) -> Result<(u32, u32), SceneError> {
    if p.object().plugin != "hdrfilm" {
        return Err(p.error("genpath renders linear radiance: only `hdrfilm` is supported"));
    }
    let side = |name: &str, default: i64| -> Result<u32, SceneError> {
        let v = p.int(name, default)?;
        u32::try_from(v)
            .ok()
            .filter(|v| (1..=MAX_IMAGE_SIDE).contains(v))
            .ok_or_else(|| p.error(format!("`{name}` {v} is not in 1..={MAX_IMAGE_SIDE}")))
    };
    let (width, height) = (side("width", 768)?, side("height", 576)?);
    match p.children_of("rfilter")[..] {
        [] => return Err(p.error("hdrfilm's default reconstruction filter is gaussian, which genpath does not implement (each sample counts only in its own pixel); add <rfilter type=\"box\"/>")),
        [f] => {
            let f = Props::new(p.doc, f);
            match f.object().plugin.as_str() {
                "box" => f.finish()?,
                "gaussian" => return Err(f.error("the gaussian filter is not implemented (each sample counts only in its own pixel); use <rfilter type=\"box\"/>")),
                other => return Err(f.error(format!("the `{other}` filter is not implemented; use box"))),
            }
        }
        _ => return Err(p.error("more than one <rfilter>")),
    }
    if let Some(format) = p.string("pixel_format")? {
        if !matches!(format, "rgb" | "rgba") {
            return Err(p.error(format!("pixel_format \"{format}\" is not supported (rgb)")));
        }
    }
    if p.bool("sample_border", false)? {
        return Err(p.error("`sample_border` is not supported"));
    }
    p.ignore(
        &["file_format", "component_format", "banner", "compensate"],
        "genpath writes the formats -o names",
        warnings,
    );
    p.finish()?;
    Ok((width, height))
}

fn sampler(p: &Props, warnings: &mut Vec<String>) -> Result<u32, SceneError> {
    let plugin = p.object().plugin.as_str();
    if plugin != "independent" {
        warnings.push(format!("{}: the `{plugin}` sampler is rendered with genpath's independent samples (the noise differs, the image's expectation does not)", p.doc.at(p.loc())));
    }
    let spp = p.int("sample_count", 4)?;
    p.ignore(
        &["seed"],
        "genpath's --seed sets the random streams",
        warnings,
    );
    p.ignore(
        &["jitter", "scramble_seed"],
        "genpath's samples are independent",
        warnings,
    );
    p.finish()?;
    u32::try_from(spp)
        .ok()
        .filter(|s| (1..=1 << 24).contains(s))
        .ok_or_else(|| p.error(format!("`sample_count` {spp} is not in 1..=16777216")))
}

/// The `path` integrator as genpath's max bounces (Mitsuba's `max_depth` − 1) and its
/// `hide_emitters`.
fn integrator(p: &Props, warnings: &mut Vec<String>) -> Result<(u32, bool), SceneError> {
    if p.object().plugin != "path" {
        return Err(p.error(format!("genpath does not implement the `{}` integrator (supported: path; genpath's --method picks how it is estimated)", p.object().plugin)));
    }
    let depth = p.int("max_depth", -1)?;
    let bounces = match depth {
        -1 => MAX_BOUNCES_LIMIT,
        0 => return Err(p.error("max_depth 0 renders a black image; genpath does not render one")),
        d if d > 0 => u32::try_from(d - 1)
            .ok()
            .filter(|b| *b <= MAX_BOUNCES_LIMIT)
            .ok_or_else(|| {
                p.error(format!(
                    "max_depth {d} is beyond genpath's limit of {} bounces",
                    MAX_BOUNCES_LIMIT
                ))
            })?,
        d => return Err(p.error(format!("max_depth {d} is not -1 or positive"))),
    };
    if depth == -1 {
        warnings.push(format!(
            "{}: max_depth -1 (unbounded) is rendered with at most {MAX_BOUNCES_LIMIT} bounces",
            p.doc.at(p.loc())
        ));
    }
    let rr = p.int("rr_depth", 5)?;
    if rr != i64::from(RR_START) {
        warnings.push(format!("{}: rr_depth {rr}: genpath's Russian roulette starts at bounce {} (the noise differs, the image's expectation does not)", p.doc.at(p.loc()), RR_START));
    }
    let hide_emitters = p.bool("hide_emitters", false)?;
    p.finish()?;
    Ok((bounces, hide_emitters))
}
