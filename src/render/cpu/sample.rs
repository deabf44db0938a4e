use glam::{IVec3, Vec3, Vec4};

use crate::render::march_plan::MarchPlan;
use crate::scene::{Filter, TABLE_SIZE};

/// The volume and table as the CPU reads them: voxel values already
/// normalised to f32, exactly what the GPU texture holds.
pub(super) struct Field<'a> {
    pub plan: &'a MarchPlan,
    values: &'a [f32],
    table: &'a [Vec4],
}

impl<'a> Field<'a> {
    pub fn new(plan: &'a MarchPlan, values: &'a [f32], table: &'a [Vec4]) -> Self {
        debug_assert_eq!(table.len(), TABLE_SIZE);
        Self {
            plan,
            values,
            table,
        }
    }

    pub fn inside(&self, p: Vec3) -> bool {
        p.cmpge(self.plan.box_lo).all() && p.cmple(self.plan.box_hi).all()
    }

    fn voxel(&self, i: IVec3) -> f32 {
        let d = self.plan.dims.as_ivec3();
        self.values[(i.x + d.x * (i.y + d.y * i.z)) as usize]
    }

    /// Trilinear interpolation between the eight surrounding grid
    /// vertices, or the nearest vertex's value.
    pub fn sample(&self, p: Vec3) -> f32 {
        let plan = self.plan;
        let hi = plan.dims.as_ivec3() - IVec3::ONE;
        let g = ((p - plan.box_lo) * plan.inv_spacing).clamp(Vec3::ZERO, hi.as_vec3());
        if plan.filter == Filter::Nearest {
            // floor(g + 0.5), not round(): the shader's rounding, halves up.
            return self.voxel((g + Vec3::splat(0.5)).floor().as_ivec3().min(hi));
        }
        let i0 = g.floor().as_ivec3().min((hi - IVec3::ONE).max(IVec3::ZERO));
        let f = g - i0.as_vec3();
        let i1 = (i0 + IVec3::ONE).min(hi);
        let at = |x: i32, y: i32, z: i32| self.voxel(IVec3::new(x, y, z));
        let x00 = mix(at(i0.x, i0.y, i0.z), at(i1.x, i0.y, i0.z), f.x);
        let x10 = mix(at(i0.x, i1.y, i0.z), at(i1.x, i1.y, i0.z), f.x);
        let x01 = mix(at(i0.x, i0.y, i1.z), at(i1.x, i0.y, i1.z), f.x);
        let x11 = mix(at(i0.x, i1.y, i1.z), at(i1.x, i1.y, i1.z), f.x);
        mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z)
    }

    /// Post-classification: straight RGBA of a value from the table.
    pub fn classify(&self, v: f32) -> Vec4 {
        let plan = self.plan;
        let last = (TABLE_SIZE - 1) as f32;
        let t = ((v - plan.value_lo) * plan.value_scale).clamp(0.0, 1.0) * last;
        let i = (t as usize).min(TABLE_SIZE - 2);
        let f = t - i as f32;
        self.table[i] * (1.0 - f) + self.table[i + 1] * f
    }
}

/// WGSL's `mix`.
fn mix(a: f32, b: f32, t: f32) -> f32 {
    a * (1.0 - t) + b * t
}

/// Opacity of a segment `exponent` unit distances long whose per-unit
/// opacity is `a`: `1 - (1 - a)^exponent`.
pub(super) fn correct(a: f32, exponent: f32) -> f32 {
    if a >= 1.0 {
        1.0
    } else {
        1.0 - (1.0 - a).powf(exponent)
    }
}
