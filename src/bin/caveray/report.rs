//! Pieces every report of the tool shares: the machine, the renderer and
//! the volume, as `Serialize` structs the JSON files and the printed
//! tables are both made from.

use anari_library_caveray::render::{PassClock, Renderer};
use anari_library_caveray::scene::{transformed_box, Scene};
use serde::Serialize;

use crate::Failure;

#[derive(Serialize)]
pub struct Machine {
    pub cpu: String,
    pub threads: usize,
}

impl Machine {
    pub fn this() -> Self {
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|s| {
                s.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split(':').nth(1))
                    .map(|m| m.trim().to_string())
            })
            .unwrap_or_else(|| "unknown".into());
        Self {
            cpu,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }
    }
}

/// What rendered, with the GPU's adapter and where its pass times come from.
#[derive(Serialize)]
#[serde(tag = "backend", rename_all = "lowercase")]
pub enum RendererInfo {
    Gpu(Adapter),
    Cpu { threads: usize },
}

#[derive(Serialize)]
pub struct Adapter {
    #[serde(rename = "adapter")]
    pub name: String,
    pub api: String,
    pub driver: String,
    pub device_type: String,
    pub pass_clock: PassClock,
    /// Mesa's on-disk shader cache during the run: "disabled" (the
    /// benches' default), or the caller's MESA_SHADER_CACHE_DISABLE value.
    pub shader_cache: String,
}

/// The environment variable that turns Mesa's on-disk shader cache off.
pub const SHADER_CACHE_VAR: &str = "MESA_SHADER_CACHE_DISABLE";

impl Adapter {
    pub fn of(gpu: &anari_library_caveray::render::GpuRenderer) -> Self {
        let info = gpu.adapter();
        Self {
            name: info.name.clone(),
            api: format!("{:?}", info.backend),
            driver: format!("{} {}", info.driver, info.driver_info),
            device_type: format!("{:?}", info.device_type),
            pass_clock: gpu.pass_clock(),
            shader_cache: match std::env::var(SHADER_CACHE_VAR).as_deref() {
                Ok("true") | Ok("1") => "disabled".into(),
                Ok(other) => format!("{SHADER_CACHE_VAR}={other}"),
                Err(_) => "on-disk cache on".into(),
            },
        }
    }
}

impl RendererInfo {
    pub fn of(renderer: &Renderer) -> Self {
        match renderer {
            Renderer::Gpu(g) => RendererInfo::Gpu(Adapter::of(g)),
            Renderer::Cpu(_) => RendererInfo::Cpu {
                threads: rayon::current_num_threads(),
            },
        }
    }

    pub fn adapter(&self) -> Option<&Adapter> {
        match self {
            RendererInfo::Gpu(a) => Some(a),
            RendererInfo::Cpu { .. } => None,
        }
    }
}

#[derive(Serialize)]
pub struct VolumeInfo {
    pub name: String,
    pub dims: [u32; 3],
    /// Where it landed: its box in the world (lowest and highest corner),
    /// in the rig's units.
    pub world_box: [[f32; 3]; 2],
}

impl VolumeInfo {
    pub fn of(name: &str, scene: &Scene) -> Self {
        let placed = &scene.volumes()[0];
        let (lo, hi) = transformed_box(placed.transform, placed.volume.bounds());
        Self {
            name: name.to_string(),
            dims: placed.volume.dims().to_array(),
            world_box: [lo.to_array(), hi.to_array()],
        }
    }
}

/// Writes `report` as pretty JSON to `path`.
pub fn write_json(report: &impl Serialize, path: &std::path::Path) -> Result<(), Failure> {
    let text = serde_json::to_string_pretty(report).map_err(|e| Failure::Runtime(e.to_string()))?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| Failure::Runtime(format!("cannot create {}: {e}", dir.display())))?;
    }
    std::fs::write(path, text + "\n")
        .map_err(|e| Failure::Runtime(format!("cannot write {}: {e}", path.display())))
}
