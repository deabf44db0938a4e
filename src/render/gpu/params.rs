use glam::{UVec2, Vec3, Vec4};

use crate::geometry::RayGen;
use crate::render::frame::ColorFormat;
use crate::render::march_plan::MarchPlan;
use crate::render::settings::Shading;

/// Size of the `Params` uniform in shaders/volume.wgsl: 14 vec4s.
pub(super) const PARAMS_BYTES: u64 = 14 * 16;

/// Packs the `Params` uniform, field for field in the shader's order.
pub(super) fn pack(
    rays: &RayGen,
    plan: &MarchPlan,
    size: UVec2,
    format: ColorFormat,
    shadow_ambient: f32,
) -> Vec<u8> {
    let mut out = Vec::with_capacity(PARAMS_BYTES as usize);
    let mut vec4 = |v: Vec4| {
        for x in v.to_array() {
            out.extend_from_slice(&x.to_le_bytes());
        }
    };
    let w0 = |v: Vec3| v.extend(0.0);
    vec4(w0(rays.origin));
    vec4(w0(rays.origin_dx));
    vec4(w0(rays.origin_dy));
    vec4(w0(rays.direction));
    vec4(w0(rays.direction_dx));
    vec4(w0(rays.direction_dy));
    vec4(plan.box_lo.extend(plan.step));
    vec4(plan.box_hi.extend(plan.shading_step));
    vec4(plan.inv_spacing.extend(plan.inv_unit_distance));
    vec4(plan.background);
    vec4(plan.light.extend(shadow_ambient));
    vec4(Vec4::new(
        plan.value_lo,
        plan.value_scale,
        plan.termination,
        plan.ao_radius,
    ));
    let shading = match plan.shading {
        Shading::None => 0u32,
        Shading::Shadows => 1,
        Shading::Ao => 2,
        Shading::ShadowsAo => 3,
        Shading::Directional(_) => 4,
    };
    let words = [
        size.x,
        size.y,
        format.code(),
        shading,
        plan.dims.x,
        plan.dims.y,
        plan.dims.z,
        plan.directions.len() as u32,
    ];
    for w in words {
        out.extend_from_slice(&w.to_le_bytes());
    }
    debug_assert_eq!(out.len() as u64, PARAMS_BYTES);
    out
}

/// The directions storage buffer: vec4 per direction, at least one entry
/// because WGSL storage arrays cannot be bound empty.
pub(super) fn pack_directions(dirs: &[Vec3]) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 * dirs.len().max(1));
    for d in dirs {
        for x in d.extend(0.0).to_array() {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
    if out.is_empty() {
        out.resize(16, 0);
    }
    out
}
