//! The scene description file (TOML), as written by the user.

use serde::Deserialize;

/// `scene.toml`: a mesh, a camera and optional render defaults.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// OBJ file, relative to the TOML file.
    pub mesh: String,
    pub camera: CameraFile,
    #[serde(default)]
    pub render: RenderDefaults,
    /// Lights beside the mesh's emitting faces (`[[lights]]` tables).
    #[serde(default)]
    pub lights: Vec<LightFile>,
}

/// A light of the TOML scene, `type = "point" | "spot" | "directional"`, with Mitsuba 3's
/// meanings (colours are linear RGB).
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum LightFile {
    /// Radiant `intensity` from `position`.
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
    },
    /// A `point` whose beam points at `target`: full `intensity` out to `beam_width`
    /// degrees from the axis, falling linearly to nothing at `cutoff_angle` (default 20,
    /// and ¾ of it).
    Spot {
        position: [f32; 3],
        target: [f32; 3],
        intensity: [f32; 3],
        cutoff_angle: Option<f32>,
        beam_width: Option<f32>,
    },
    /// `irradiance` arriving along `direction` (the way the light travels).
    Directional {
        direction: [f32; 3],
        irradiance: [f32; 3],
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    pub origin: [f32; 3],
    pub target: [f32; 3],
    pub up: [f32; 3],
    /// Horizontal field of view in degrees.
    pub fov_x_deg: f32,
    pub width: u32,
    pub height: u32,
}

/// Defaults a scene may set; every one is overridable on the command line.
#[derive(Clone, Debug, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct RenderDefaults {
    /// Scattering events on a path (Mitsuba's `max_depth` is this + 1).
    #[serde(default = "default_max_bounces")]
    pub max_bounces: u32,
    /// Samples per pixel when the command line gives none (a Mitsuba scene's
    /// `sample_count`; not a TOML field).
    #[serde(skip_deserializing, skip_serializing_if = "Option::is_none")]
    pub spp: Option<u32>,
}

fn default_max_bounces() -> u32 {
    5
}

impl Default for RenderDefaults {
    fn default() -> Self {
        Self {
            max_bounces: default_max_bounces(),
            spp: None,
        }
    }
}
