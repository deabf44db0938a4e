//! The WGSL a pipeline runs, composed from modules (modules.rs): the files
//! in shaders/ (named by their stem), the modules generated from the Rust
//! uniforms and constants (uniforms.rs), and the binding modules of the
//! pipeline's groups, each written at the group's index. Each file names
//! what it imports; a pipeline's shader is its entry file and what that
//! imports.

use super::bindings::{BindingTable, GroupLayout};
use super::modules::{ComposeError, Library};
use super::uniforms;
use crate::render::RenderError;

const FILES: [(&str, &str); 16] = [
    ("volume", include_str!("../../../shaders/volume.wgsl")),
    ("surface", include_str!("../../../shaders/surface.wgsl")),
    ("trace", include_str!("../../../shaders/trace.wgsl")),
    ("color", include_str!("../../../shaders/color.wgsl")),
    ("band", include_str!("../../../shaders/band.wgsl")),
    ("cells", include_str!("../../../shaders/cells.wgsl")),
    ("amr", include_str!("../../../shaders/amr.wgsl")),
    ("nanovdb", include_str!("../../../shaders/nanovdb.wgsl")),
    ("stereo", include_str!("../../../shaders/stereo.wgsl")),
    ("raycast", include_str!("../../../shaders/raycast.wgsl")),
    ("reproject", include_str!("../../../shaders/reproject.wgsl")),
    ("composite", include_str!("../../../shaders/composite.wgsl")),
    ("warp", include_str!("../../../shaders/warp.wgsl")),
    ("capture", include_str!("../../../shaders/capture.wgsl")),
    ("iso", include_str!("../../../shaders/iso.wgsl")),
    ("iso_panel", include_str!("../../../shaders/iso_panel.wgsl")),
];

/// The WGSL of entry module `entry` for a pipeline whose bind groups are
/// `groups`, group g at index g.
pub(super) fn compose(entry: &str, groups: &[&BindingTable]) -> Result<String, ComposeError> {
    let mut library = Library::default();
    for (name, source) in FILES {
        library.add(name, source);
    }
    for (name, source) in uniforms::modules() {
        library.add(name, source);
    }
    for (g, table) in groups.iter().enumerate() {
        library.add(table.module, table.wgsl(g as u32));
    }
    library.compose(entry)
}

/// A compute pipeline running `entry_point` of module `module`, with
/// `groups` as its bind groups (the shader declares them from their
/// tables) and values for the shader's override constants.
pub(super) fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    module: &str,
    entry_point: &str,
    groups: &[&GroupLayout],
    constants: &[(&str, f64)],
) -> Result<wgpu::ComputePipeline, RenderError> {
    let tables: Vec<&BindingTable> = groups.iter().map(|g| g.table()).collect();
    let source = compose(module, &tables)
        .map_err(|e| RenderError::Gpu(format!("internal: the {label} shader: {e}")))?;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> =
        groups.iter().map(|g| Some(g.layout())).collect();
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    Ok(
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(label),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(entry_point),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            cache: None,
        }),
    )
}
