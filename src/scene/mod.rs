//! Scenes: a TOML description, an OBJ/MTL mesh (through `tobj`), a camera, materials and
//! the emitters, validated strictly at load time.

mod camera;
mod environment;
pub mod envmap;
mod file;
pub mod lights;
pub mod material;
pub mod normals;
mod shading;
mod surface;
pub mod texture;
mod validate;
pub mod xml;

pub use camera::{Camera, CameraConnection};
pub use environment::Environment;
pub use file::{CameraFile, LightFile, RenderDefaults, SceneFile};
pub use lights::emission::{EmissionPdf, EmissionSample, Emitter};
pub use lights::{
    bvh, emission, DeltaArrival, DeltaLight, DirectPick, LightPick, LightSampler, LightTables, Spot,
};
pub use material::{
    Dielectric, Glossy, Material, MaterialAt, MaterialTextures, Opacity, SmoothPlastic, BLACK,
};
pub use shading::Shading;
pub use surface::SurfacePoint;
pub use texture::Texture;

use crate::accel::{Analytic, SphereCone, TriangleMesh};
use crate::math::triangle_area;
use glam::{DVec3, Vec3};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// (Not `source`: anyhow's `{:#}` would print the reason twice.)
    #[error("{path}: cannot read: {reason}")]
    Io {
        path: PathBuf,
        reason: std::io::Error,
    },
    #[error("{path}: {message}")]
    Toml { path: PathBuf, message: String },
    #[error("{path}: field `{field}`: {message}")]
    Field {
        path: PathBuf,
        field: &'static str,
        message: String,
    },
    #[error("{path}:{line}: {message}")]
    Syntax {
        path: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{path}: {message}")]
    Mesh { path: PathBuf, message: String },
    #[error("{path}: the scene has no emitter (give some material a positive `Ke` and use it on a face)")]
    NoEmitter { path: PathBuf },
}

/// The emitting primitives (triangles and analytic shapes), picked by area.
#[derive(Clone, Debug)]
pub struct Emitters {
    /// Primitive index of each emitter, increasing.
    pub prims: Vec<u32>,
    /// Running sum of areas, `cdf[i]` = area of emitters `0..=i`.
    cdf: Vec<f64>,
    pub total_area: f64,
}

/// A point on an emitter, sampled for next-event estimation at a reference point
/// ([`Emitters::sample_seen_from`]).
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    pub point: Vec3,
    /// Unit geometric normal there.
    pub normal: Vec3,
    pub prim: u32,
    /// Density in area measure ([`Emitters::pdf_area_seen_from`]).
    pub pdf_area: f64,
}

impl Emitters {
    /// The primitives of `mesh` for which `is_emitter` holds, in increasing index order.
    pub fn new(mesh: &TriangleMesh, is_emitter: impl Fn(u32) -> bool) -> Self {
        let mut prims = Vec::new();
        let mut cdf = Vec::new();
        let mut total = 0.0f64;
        for prim in 0..mesh.prim_count() as u32 {
            if is_emitter(prim) {
                total += mesh.area(prim);
                prims.push(prim);
                cdf.push(total);
            }
        }
        Self {
            prims,
            cdf,
            total_area: total,
        }
    }

    /// Whether primitive `prim` is an emitter (`prims` is sorted).
    pub fn contains(&self, prim: u32) -> bool {
        self.prims.binary_search(&prim).is_ok()
    }

    /// The emitter chosen with probability proportional to its area by a uniform
    /// `u` in [0, 1] (1, from rounding, picks the last). There must be at least one emitter.
    pub fn pick(&self, u: f64) -> u32 {
        let target = u * self.total_area;
        let i = self
            .cdf
            .partition_point(|&c| c <= target)
            .min(self.prims.len() - 1);
        self.prims[i]
    }

    /// A point on the emitters for next-event estimation at `x`, from three uniform numbers
    /// in [0, 1): `u[0]` picks an emitter by area; on a triangle or a disk the point is
    /// uniform by area, on a sphere that `x` lies outside of it is uniform in the cone of
    /// directions the sphere subtends at `x` (Mitsuba's `Sphere::sample_direction`), else
    /// uniform by area.
    pub fn sample_seen_from(&self, mesh: &TriangleMesh, x: Vec3, u: [f32; 3]) -> LightSample {
        let prim = self.pick(u[0] as f64);
        self.place(mesh, prim, x, (u[1], u[2]), Within::Emitters)
    }

    /// The area density of [`Self::sample_seen_from`] at `x` for the point `y` on emitter
    /// `prim`. On a sphere sampled by its cone it is `(area/total) · cos_y / (Ω·d²)`, valid
    /// for the points `x` sees (the only ones a ray from `x` reaches first).
    pub fn pdf_area_seen_from(&self, mesh: &TriangleMesh, x: Vec3, y: Vec3, prim: u32) -> f64 {
        self.pdf_seen_from(mesh, x, y, prim, Within::Emitters)
    }

    /// A point on emitting primitive `prim` alone for next-event estimation at `x`, from two
    /// uniform numbers: placed as [`Self::sample_seen_from`] places it, with its area
    /// density within `prim`.
    pub fn sample_prim_seen_from(
        &self,
        mesh: &TriangleMesh,
        prim: u32,
        x: Vec3,
        u: (f32, f32),
    ) -> LightSample {
        self.place(mesh, prim, x, u, Within::Prim)
    }

    /// The area density of [`Self::sample_prim_seen_from`] at `x` for the point `y` on
    /// emitting primitive `prim`.
    pub fn pdf_prim_seen_from(&self, mesh: &TriangleMesh, x: Vec3, y: Vec3, prim: u32) -> f64 {
        self.pdf_seen_from(mesh, x, y, prim, Within::Prim)
    }

    /// A point on emitter `prim` seen from `x`, from two uniform numbers: uniform by area on
    /// a triangle (square-root warp) or a disk, in the visible cone of a sphere `x` lies
    /// outside of, else uniform by area; its density is `within`'s.
    fn place(
        &self,
        mesh: &TriangleMesh,
        prim: u32,
        x: Vec3,
        (u1, u2): (f32, f32),
        within: Within,
    ) -> LightSample {
        let Some(shape) = mesh.analytic(prim) else {
            let [a, b, c] = mesh.vertices(prim);
            let su = u1.sqrt();
            let (b0, b1) = (1.0 - su, u2 * su);
            return LightSample {
                point: a * b0 + b * b1 + c * (1.0 - b0 - b1),
                normal: mesh.normals[prim as usize],
                prim,
                pdf_area: 1.0 / self.area_within(mesh, prim, within),
            };
        };
        let (u1, u2) = (f64::from(u1), f64::from(u2));
        let xd = x.as_dvec3();
        let cone = shape.visible_cone(xd);
        let point = match &cone {
            Some(cone) => cone.sample(u1, u2),
            None => shape.sample_area(u1, u2),
        }
        .as_vec3();
        let y = point.as_dvec3();
        let normal = shape.normal_at(y);
        LightSample {
            point,
            normal: normal.as_vec3(),
            prim,
            pdf_area: match &cone {
                Some(cone) => self.cone_pdf_area(shape, cone, (normal, x, y), within),
                None => self.area_within(mesh, prim, within).recip(),
            },
        }
    }

    /// [`Self::place`]'s area density at `x` for the point `y` on emitter `prim`.
    fn pdf_seen_from(
        &self,
        mesh: &TriangleMesh,
        x: Vec3,
        y: Vec3,
        prim: u32,
        within: Within,
    ) -> f64 {
        let Some((shape, cone)) = mesh
            .analytic(prim)
            .and_then(|s| s.visible_cone(x.as_dvec3()).map(|c| (s, c)))
        else {
            return self.area_within(mesh, prim, within).recip();
        };
        let y = y.as_dvec3();
        self.cone_pdf_area(shape, &cone, (shape.normal_at(y), x, y), within)
    }

    /// The area a point uniform by area is drawn over: every emitter's, or `prim`'s.
    fn area_within(&self, mesh: &TriangleMesh, prim: u32, within: Within) -> f64 {
        match within {
            Within::Emitters => self.total_area,
            Within::Prim => mesh.area(prim),
        }
    }

    /// The area density at `y` (unit normal `normal_y`) of directions from `x` uniform in
    /// the `cone` that sphere `shape` subtends there, `cos_y / (Ω·d²)`, times the sphere's
    /// share of the area it is picked from: shared by the sampler, which has the cone and
    /// the normal at hand.
    fn cone_pdf_area(
        &self,
        shape: &Analytic,
        cone: &SphereCone,
        (normal_y, x, y): (DVec3, Vec3, DVec3),
        within: Within,
    ) -> f64 {
        let d = x.as_dvec3() - y;
        let dist2 = d.length_squared();
        let cos_y = normal_y.dot(d).abs() / dist2.sqrt();
        let share = match within {
            Within::Emitters => shape.area() / self.total_area,
            Within::Prim => 1.0,
        };
        share * cone.pdf_solid_angle() * cos_y / dist2
    }
}

/// Which area a light point's density is per ([`Emitters::place`]): of every emitter (the
/// emitter picked by area), or of its primitive alone (the primitive picked beforehand).
#[derive(Clone, Copy, Debug)]
enum Within {
    Emitters,
    Prim,
}

/// A loaded, validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The TOML file it came from.
    pub path: PathBuf,
    pub camera: Camera,
    pub mesh: TriangleMesh,
    /// The vertices' shading normals and texture coordinates (Mitsuba XML meshes).
    pub shading: Shading,
    pub materials: Vec<Material>,
    /// Material index of each primitive (triangles, then analytic shapes).
    pub material_of: Vec<u32>,
    pub emitters: Emitters,
    /// Mitsuba's `constant` or `envmap` emitter, if any: what rays that escape the scene
    /// gather.
    pub environment: Option<Environment>,
    /// Mitsuba's `point` and `directional` emitters, which only light sampling reaches.
    pub delta_lights: Vec<DeltaLight>,
    /// What is built about the lights on first use (emission by power, the light tree).
    pub lights: LightTables,
    /// Mitsuba's `hide_emitters`: camera rays that see an emitter, or escape to the
    /// environment, gather nothing (emitters seen after a scattering event still count).
    pub hide_emitters: bool,
    pub render: RenderDefaults,
    /// Largest absolute coordinate of the scene: sets the scale of ray offsets.
    pub extent: f32,
    /// Non-fatal problems found while loading (ignored MTL statements, dropped triangles).
    pub warnings: Vec<String>,
    /// Every file the scene was read from, the scene file first, in the order read (what a
    /// shard's scene hash covers).
    pub files: Vec<PathBuf>,
}

/// What a scene contains, reported beside what the GA left out (docs/methods/ga.md,
/// "Leaving out what the scene does not need").
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SceneAnalysis {
    /// Primitives: triangles and analytic shapes (the counts below too).
    pub triangles: usize,
    /// Triangles by material kind: Lambertian only, with a glossy lobe (Phong, microfacet),
    /// delta BSDFs (mirrors, conductors, dielectrics), emitters.
    pub diffuse_triangles: usize,
    pub glossy_triangles: usize,
    pub mirror_triangles: usize,
    pub emitter_triangles: usize,
    /// Total emitting area and the smallest emitting triangle's area.
    pub emitter_area: f64,
    pub smallest_emitter_area: f64,
    /// Diagonal of the bounding box.
    pub extent: f32,
}

impl Scene {
    pub fn material(&self, prim: u32) -> &Material {
        &self.materials[self.material_of[prim as usize] as usize]
    }

    /// The unit shading normal of primitive `prim` at `(u, v)`: for a triangle (at
    /// barycentrics in Embree's convention) its interpolated vertex normals, or `ng`, its
    /// geometric normal, where it shades flat; for an analytic shape `ng` (a sphere's and a
    /// disk's shading frame is their geometric one, as in Mitsuba).
    pub fn shading_normal(&self, prim: u32, (u, v): (f32, f32), ng: Vec3) -> Vec3 {
        if self.shading.normals.is_empty() {
            return ng;
        }
        match self.mesh.triangles.get(prim as usize) {
            Some(&t) => self.shading.normal(t, u, v).unwrap_or(ng),
            None => ng,
        }
    }

    /// Mitsuba's texture coordinates of primitive `prim` at the hit parameters `(u, v)`: a
    /// triangle's interpolated vertex coordinates (its barycentrics where its mesh has
    /// none), an analytic shape's own parameterisation (see [`crate::accel::Analytic`]).
    pub fn uv(&self, prim: u32, (u, v): (f32, f32)) -> glam::Vec2 {
        match self.mesh.triangles.get(prim as usize) {
            Some(&t) => self.shading.uv(t, u, v),
            None => glam::Vec2::new(u, v),
        }
    }

    /// Mitsuba's shading tangent (`sh_frame.s`) of primitive `prim`, whose unit geometric
    /// normal is `ng` and whose shading normal is `ns` there: for a triangle its `dp/du`
    /// ([`shading::dp_du`]) made orthogonal to `ns`. Analytic shapes (which the loader keeps
    /// from anisotropic lobes) get `coordinate_system(ns)`'s.
    pub fn shading_tangent(&self, prim: u32, ng: Vec3, ns: Vec3) -> Vec3 {
        let dp_du = match self.mesh.triangles.get(prim as usize) {
            Some(&t) => shading::dp_du(self.mesh.vertices(prim), self.shading.corner_uvs(t), ng),
            None => glam::DVec3::ZERO,
        };
        shading::tangent(dp_du, ns)
    }

    /// The perturbed shading normal `p` gives primitive `prim` at the hit parameters
    /// `(u, v)` (see [`normals`]), where its unit geometric normal is `ng`, its shading
    /// normal and tangent `ns` and `ts`, and its texture coordinates `uv`: zero for an
    /// analytic shape (the loader keeps perturbations off them) and where the perturbation
    /// is undefined.
    pub fn perturbed_normal(
        &self,
        p: &normals::Perturbation,
        prim: u32,
        (ng, ns, ts): (Vec3, Vec3, Vec3),
        uv: glam::Vec2,
    ) -> Vec3 {
        let Some(&t) = self.mesh.triangles.get(prim as usize) else {
            return Vec3::ZERO;
        };
        let (dp_du, dp_dv) =
            shading::dp_duv(self.mesh.vertices(prim), self.shading.corner_uvs(t), ng);
        p.normal(&normals::HitFrame {
            ns,
            ts,
            ng,
            dp_du: dp_du.as_vec3(),
            dp_dv: dp_dv.as_vec3(),
            uv,
        })
    }

    /// The probability with which light sampling picks the environment: 0 without one, else
    /// [`Scene::light_pmf`] (Mitsuba's uniform choice between its emitters, `lights`).
    pub fn environment_share(&self) -> f64 {
        match self.environment {
            None => 0.0,
            Some(_) => self.light_pmf(),
        }
    }

    /// Counts what the scene's primitives (triangles and analytic shapes) use.
    pub fn analysis(&self) -> SceneAnalysis {
        let n = self.mesh.prim_count();
        let count =
            |f: &dyn Fn(&Material) -> bool| (0..n as u32).filter(|&p| f(self.material(p))).count();
        let smallest = self
            .emitters
            .prims
            .iter()
            .map(|&p| self.mesh.area(p))
            .fold(f64::INFINITY, f64::min);
        SceneAnalysis {
            triangles: n,
            diffuse_triangles: count(&|m| m.scatters() && !m.mirror && !m.is_glossy()),
            glossy_triangles: count(&|m| m.is_glossy() && !m.mirror),
            mirror_triangles: count(&|m| m.mirror),
            emitter_triangles: self.emitters.prims.len(),
            emitter_area: self.emitters.total_area,
            smallest_emitter_area: smallest,
            extent: self.extent,
        }
    }

    /// Loads and validates a scene: Mitsuba 3 XML for a `.xml` file, else genpath's TOML.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Self::load_with(path, &[])
    }

    /// [`Scene::load`] with `-D name=value` parameters for a Mitsuba XML scene.
    pub fn load_with(path: &Path, defines: &[(String, String)]) -> Result<Scene, SceneError> {
        if xml::is_xml(path) {
            return xml::load(path, defines);
        }
        if let Some((name, _)) = defines.first() {
            return Err(SceneError::Field {
                path: path.to_path_buf(),
                field: "-D",
                message: format!(
                    "`{name}`: parameters are for Mitsuba XML scenes; this is a TOML scene"
                ),
            });
        }
        Self::load_toml(path)
    }

    fn load_toml(path: &Path) -> Result<Scene, SceneError> {
        let text = read(path)?;
        let file: SceneFile = toml::from_str(&text).map_err(|e| SceneError::Toml {
            path: path.to_path_buf(),
            message: e.to_string().trim_end().to_string(),
        })?;
        let camera = build_camera(path, &file.camera)?;
        if file.render.max_bounces > MAX_BOUNCES_LIMIT {
            return Err(SceneError::Field {
                path: path.to_path_buf(),
                field: "render.max_bounces",
                message: format!(
                    "{} is more than the limit of {MAX_BOUNCES_LIMIT}",
                    file.render.max_bounces
                ),
            });
        }
        let dir = path.parent().unwrap_or(Path::new("."));
        let obj_path = dir.join(&file.mesh);
        let mut warnings = Vec::new();
        let mut files = vec![path.to_path_buf(), obj_path.clone()];
        let (mesh, materials, material_of) = load_mesh(&obj_path, &mut warnings, &mut files)?;
        let emitters = Emitters::new(&mesh, |prim| {
            materials[material_of[prim as usize] as usize].is_emitter()
        });
        let delta_lights = file
            .lights
            .iter()
            .enumerate()
            .map(|(i, l)| {
                toml_light(l).map_err(|message| SceneError::Field {
                    path: path.to_path_buf(),
                    field: "lights",
                    message: format!("light {}: {message}", i + 1),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        if (emitters.prims.is_empty() || emitters.total_area <= 0.0) && delta_lights.is_empty() {
            return Err(SceneError::NoEmitter { path: obj_path });
        }
        let extent = mesh
            .positions
            .iter()
            .fold(0.0f32, |m, p| m.max(p.abs().max_element()));
        Ok(Scene {
            path: path.to_path_buf(),
            camera,
            mesh,
            shading: Shading::default(),
            materials,
            material_of,
            emitters,
            environment: None,
            delta_lights,
            lights: LightTables::default(),
            hide_emitters: false,
            render: file.render,
            extent,
            warnings,
            files,
        })
    }
}

/// A `[[lights]]` table as a delta light, or why it is refused.
fn toml_light(light: &LightFile) -> Result<DeltaLight, String> {
    let vec = |name: &str, v: [f32; 3]| {
        let v = Vec3::from(v);
        match v.is_finite() {
            true => Ok(v),
            false => Err(format!("`{name}` {v} is not finite")),
        }
    };
    let color = |name: &str, v: [f32; 3]| {
        let v = vec(name, v)?;
        match v.min_element() >= 0.0 && v.max_element() <= 1e30 {
            true => Ok(v),
            false => Err(format!("`{name}` {v} is negative or beyond 1e30")),
        }
    };
    let unit = |name: &str, v: Vec3| {
        let length = v.length();
        match length.is_finite() && length > 1e-12 {
            true => Ok(v / length),
            false => Err(format!("`{name}` gives no direction")),
        }
    };
    Ok(match *light {
        LightFile::Point {
            position,
            intensity,
        } => DeltaLight::Point {
            position: vec("position", position)?,
            intensity: color("intensity", intensity)?,
        },
        LightFile::Spot {
            position,
            target,
            intensity,
            cutoff_angle,
            beam_width,
        } => {
            let position = vec("position", position)?;
            let axis = unit("target", vec("target", target)? - position)?;
            let cutoff = cutoff_angle.unwrap_or(20.0);
            let beam = beam_width.unwrap_or(0.75 * cutoff);
            let spot = Spot::new(position, axis, color("intensity", intensity)?, cutoff, beam)
                .ok_or_else(|| {
                    format!("`beam_width` {beam} and `cutoff_angle` {cutoff} must satisfy 0 < beam_width <= cutoff_angle < 180 (degrees)")
                })?;
            DeltaLight::Spot(spot)
        }
        LightFile::Directional {
            direction,
            irradiance,
        } => DeltaLight::Directional {
            direction: unit("direction", vec("direction", direction)?)?,
            irradiance: color("irradiance", irradiance)?,
        },
    })
}

/// Upper bound on `max_bounces`, far above anything useful, so that typos fail fast.
pub const MAX_BOUNCES_LIMIT: u32 = 1000;
/// First bounce at which Russian roulette may end a path. A setting of the path tracer
/// (`path::pt`), kept here beside [`MAX_BOUNCES_LIMIT`] because the Mitsuba loader
/// warns when a scene's `rr_depth` differs from it, and the scene may not import the path
/// layer.
pub const RR_START: u32 = 5;
/// Upper bound on the image side, so that a typo does not allocate terabytes.
pub const MAX_IMAGE_SIDE: u32 = 1 << 15;

fn read(path: &Path) -> Result<String, SceneError> {
    std::fs::read_to_string(path).map_err(|reason| SceneError::Io {
        path: path.to_path_buf(),
        reason,
    })
}

fn build_camera(path: &Path, c: &CameraFile) -> Result<Camera, SceneError> {
    let field_error = |field, message: String| SceneError::Field {
        path: path.to_path_buf(),
        field,
        message,
    };
    for (field, v) in [
        ("camera.origin", c.origin),
        ("camera.target", c.target),
        ("camera.up", c.up),
    ] {
        if !v.iter().all(|x| x.is_finite()) {
            return Err(field_error(
                field,
                format!("{v:?} has a non-finite component"),
            ));
        }
        if v.iter()
            .any(|x| f64::from(x.abs()) > validate::MAX_COORDINATE)
        {
            return Err(field_error(
                field,
                format!(
                    "{v:?} is beyond ±{:e}, genpath's coordinate limit",
                    validate::MAX_COORDINATE
                ),
            ));
        }
    }
    if !(c.fov_x_deg.is_finite() && c.fov_x_deg > 0.0 && c.fov_x_deg < 180.0) {
        return Err(field_error(
            "camera.fov_x_deg",
            format!("{} is not in (0, 180)", c.fov_x_deg),
        ));
    }
    for (field, side) in [("camera.width", c.width), ("camera.height", c.height)] {
        if side == 0 || side > MAX_IMAGE_SIDE {
            return Err(field_error(
                field,
                format!("{side} is not in 1..={MAX_IMAGE_SIDE}"),
            ));
        }
    }
    let (origin, target, up) = (Vec3::from(c.origin), Vec3::from(c.target), Vec3::from(c.up));
    let forward = target - origin;
    if forward.length() <= 1e-6 * origin.length().max(1.0) {
        return Err(field_error(
            "camera.target",
            "coincides with camera.origin".into(),
        ));
    }
    if forward.normalize().cross(up.normalize_or_zero()).length() < 1e-4 {
        return Err(field_error(
            "camera.up",
            "is zero or parallel to the viewing direction".into(),
        ));
    }
    Ok(Camera::new(
        origin,
        target,
        up,
        c.fov_x_deg.to_radians(),
        c.width,
        c.height,
    ))
}

/// The material of MTL entry `m` (of `obj_path`'s libraries).
fn material(
    m: &tobj::Material,
    obj_path: &Path,
    warnings: &mut Vec<String>,
) -> Result<Material, SceneError> {
    let kd = Vec3::from(m.diffuse.unwrap_or([0.0; 3]));
    let ks = Vec3::from(m.specular.unwrap_or([0.0; 3]));
    let mirror = m.illumination_model == Some(3);
    if mirror && kd.max_element() > 0.0 {
        warnings.push(format!(
            "{}: material `{}` is a mirror (`illum 3`): its `Kd` is ignored",
            obj_path.display(),
            m.name
        ));
    }
    if !mirror && (kd + ks).max_element() > 1.0 {
        return Err(SceneError::Mesh {
            path: obj_path.to_path_buf(),
            message: format!(
                "material `{}`: `Kd + Ks` exceeds 1 in some channel, so it would create energy",
                m.name
            ),
        });
    }
    Ok(Material {
        name: m.name.clone(),
        kd: if mirror { Vec3::ZERO } else { kd },
        ks: if mirror { ks } else { Vec3::ZERO },
        // Without `Ks` (or as a mirror) there is no glossy lobe: the material is Lambertian,
        // and the BSDF code runs the Lambertian lobe alone.
        glossy: match mirror || ks.max_element() <= 0.0 {
            true => Glossy::None,
            false => Glossy::Phong {
                ks,
                ns: m.shininess.unwrap_or(1.0),
            },
        },
        mirror,
        ke: Vec3::from(m.emissive.unwrap_or([0.0; 3])),
        two_sided: true,
        conductor: None,
        dielectric: None,
        textures: None,
    })
}

type LoadedMesh = (TriangleMesh, Vec<Material>, Vec<u32>);

/// The OBJ at `obj_path` with its materials; the MTL files it reads are added to `files`.
fn load_mesh(
    obj_path: &Path,
    warnings: &mut Vec<String>,
    files: &mut Vec<PathBuf>,
) -> Result<LoadedMesh, SceneError> {
    let obj_text = read(obj_path)?;
    let summary = validate::check_obj(obj_path, &obj_text, warnings)?;
    let obj_dir = obj_path.parent().unwrap_or(Path::new("."));
    let mut defined = std::collections::BTreeSet::new();
    for lib in &summary.mtllibs {
        let mtl_path = obj_dir.join(lib);
        let text = read(&mtl_path)?;
        files.push(mtl_path.clone());
        defined.extend(validate::check_mtl(&mtl_path, &text, warnings)?);
    }
    if let Some(missing) = summary
        .used_materials
        .iter()
        .find(|m| !defined.contains(*m))
    {
        return Err(SceneError::Mesh {
            path: obj_path.to_path_buf(),
            message: format!("material `{missing}` is used but defined in no `mtllib` file"),
        });
    }

    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let mesh_error = |message: String| SceneError::Mesh {
        path: obj_path.to_path_buf(),
        message,
    };
    let (models, mtl_result) = tobj::load_obj(obj_path, &options)
        .map_err(|e| mesh_error(format!("OBJ could not be loaded: {e}")))?;
    let tobj_materials = if summary.mtllibs.is_empty() {
        Vec::new()
    } else {
        mtl_result.map_err(|e| mesh_error(format!("MTL could not be loaded: {e}")))?
    };
    let materials: Vec<Material> = tobj_materials
        .iter()
        .map(|m| material(m, obj_path, warnings))
        .collect::<Result<_, SceneError>>()?;

    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut material_of = Vec::new();
    let mut degenerate = 0usize;
    for model in &models {
        let m = &model.mesh;
        let Some(material) = m.material_id.filter(|&id| id < materials.len()) else {
            if m.indices.is_empty() {
                continue;
            }
            return Err(mesh_error(format!(
                "object `{}` has faces but no material (add `usemtl`)",
                model.name
            )));
        };
        let base = positions.len() as u32;
        positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        for tri in m.indices.chunks_exact(3) {
            let t = [base + tri[0], base + tri[1], base + tri[2]];
            if triangle_area(t.map(|i| positions[i as usize])) > 0.0 {
                triangles.push(t);
                material_of.push(material as u32);
            } else {
                degenerate += 1;
            }
        }
    }
    if degenerate > 0 {
        warnings.push(format!(
            "{}: {degenerate} degenerate (zero-area) triangles dropped",
            obj_path.display()
        ));
    }
    if triangles.is_empty() {
        return Err(mesh_error("no triangles".into()));
    }
    Ok((
        TriangleMesh::new(positions, triangles),
        materials,
        material_of,
    ))
}

impl Scene {
    /// Changes the image size, keeping the horizontal field of view.
    pub fn resize(&mut self, width: u32, height: u32) {
        self.camera = self.camera.resized(width, height);
    }
}
