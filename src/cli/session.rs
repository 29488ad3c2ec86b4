//! A loaded scene with its accelerator and worker pool, and the JSON every render writes.

use super::args::SceneArgs;
use anyhow::{Context, Result};
use genpath::accel::{self, Accel};
use genpath::film::Shard;
use genpath::integrators::{Method, RenderSettings, Settings};
use genpath::path::RayCounts;
use genpath::scene::Scene;
use genpath::shard::{Header, Identity, Part};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A loaded scene with its accelerator and worker pool, and how long loading took.
pub struct Session {
    pub scene: Scene,
    pub accel: Box<dyn Accel>,
    pub pool: rayon::ThreadPool,
    pub load_s: f64,
    pub accel_s: f64,
}

impl Session {
    pub fn open(args: &SceneArgs) -> Result<Self> {
        let t_load = Instant::now();
        let mut scene = Scene::load_with(&args.scene, &args.define)?;
        if args.width.is_some() || args.height.is_some() {
            scene.resize(
                args.width.unwrap_or(scene.camera.width),
                args.height.unwrap_or(scene.camera.height),
            );
        }
        if !args.quiet {
            for warning in &scene.warnings {
                eprintln!("genpath: warning: {warning}");
            }
        }
        let load_s = t_load.elapsed().as_secs_f64();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(args.threads.unwrap_or(0) as usize)
            .build()
            .context("cannot start the worker threads")?;
        let t_accel = Instant::now();
        let accel = accel::build_with(args.accel, &scene.mesh, args.embree_isa)?;
        Ok(Self {
            scene,
            accel,
            pool,
            load_s,
            accel_s: t_accel.elapsed().as_secs_f64(),
        })
    }

    pub fn settings(&self, args: &SceneArgs, method: Method, spp: u32) -> RenderSettings {
        RenderSettings {
            method,
            spp,
            max_bounces: args.max_bounces.unwrap_or(self.scene.render.max_bounces),
            seed: args.seed,
            progress: !args.quiet,
            shard: Shard::WHOLE,
            control: Default::default(),
            learning: None,
        }
    }

    /// What the JSON of every render records first.
    pub fn stats(&self, settings: &RenderSettings) -> serde_json::Map<String, serde_json::Value> {
        let value = serde_json::json!({
            "genpath_version": env!("CARGO_PKG_VERSION"),
            "command_line": std::env::args().collect::<Vec<_>>(),
            "scene": self.scene.path,
            "settings": settings,
            "threads": self.pool.current_num_threads(),
            "accel": self.accel.name(),
            "accel_kernels": self.accel.kernels(),
            "width": self.scene.camera.width,
            "height": self.scene.camera.height,
            "warnings": self.scene.warnings,
        });
        match value {
            serde_json::Value::Object(map) => map,
            _ => unreachable!("a JSON object literal"),
        }
    }
}

impl Session {
    /// The identity of a shard of `command`'s render with `settings` and `layer_seeds`
    /// ([`genpath::shard::Identity`]).
    pub fn identity(
        &self,
        command: &str,
        args: &SceneArgs,
        settings: &RenderSettings,
        layer_seeds: Vec<u64>,
        config: &Settings,
    ) -> Result<genpath::shard::Identity> {
        let inputs = genpath::shard::SceneInputs {
            files: self.scene.files.clone(),
            defines: args.define.clone(),
            width: self.scene.camera.width,
            height: self.scene.camera.height,
        };
        let accel = self.accel.kernels();
        Ok(genpath::shard::Identity::new(
            command,
            args.seed,
            settings,
            layer_seeds,
            config,
            &inputs,
            &accel,
        )?)
    }

    /// Writes the shard file `path` of this render: `layers` with `identity`, `shard` and
    /// its part.
    pub fn write_shard(
        &self,
        path: &Path,
        identity: genpath::shard::Identity,
        shard: (Shard, genpath::shard::Part),
        layers: &[genpath::shard::LayerSums],
    ) -> Result<()> {
        let header = header(self, identity, shard);
        genpath::shard::file::write(path, &header, layers)?;
        Ok(())
    }
}

/// The header of the shard file that `session`'s render with `identity` writes.
pub fn header(session: &Session, identity: Identity, (shard, part): (Shard, Part)) -> Header {
    Header {
        splats: false,
        shard,
        identity,
        scene_path: session.scene.path.clone(),
        command_line: std::env::args().collect(),
        part,
    }
}

/// `<output>.shard`, where a shard of a render to `output` keeps its sums.
pub fn shard_path(output: &Path) -> PathBuf {
    beside(output, ".shard")
}

/// `path` with `suffix` added after its whole name (`plan.bin` → `plan.bin.json`): the files
/// that go with an output.
pub fn beside(path: &Path, suffix: &str) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(suffix);
    PathBuf::from(name)
}

pub fn rays_json(rays: RayCounts) -> serde_json::Value {
    serde_json::json!({
        "closest": rays.closest, "shadow": rays.shadow, "total": rays.total(),
        "densities": rays.densities, "cost": rays.cost(),
    })
}

/// Writes `stats` as `<output>.json` beside each output.
pub fn write_stats(outputs: &[PathBuf], stats: &serde_json::Value) -> Result<()> {
    let text = serde_json::to_string_pretty(stats)?;
    for output in outputs {
        genpath::image::write_bytes_atomic(&beside(output, ".json"), text.as_bytes())?;
    }
    Ok(())
}
