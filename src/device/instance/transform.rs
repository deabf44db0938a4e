//! The `transform` instance (ANARI_KHR_INSTANCE_TRANSFORM): a group placed
//! in the world by an affine matrix, as VTK and ParaView place each
//! dataset's volume, with the uniform attributes (`color`,
//! `attribute0..3`) that stand for its surfaces' own: one cube mesh in a
//! hundred instances of a hundred colors.

use glam::Mat4;

use crate::device::object::{ObjectRef, State};
use crate::device::table::Read;
use crate::device::table::{id_param, p, DefaultValue, SubtypeInfo, MAT4};
use crate::device::types::DataType as T;
use crate::scene::{PlacedVolume, Uniforms, ATTRIBUTE_NAMES};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::INSTANCE,
    subtype: "transform",
    description: "a group placed by an affine, invertible transform",
    extensions: &["ANARI_KHR_INSTANCE_TRANSFORM"],
    params: &[
        p(
            "group",
            &[T::GROUP],
            true,
            DefaultValue::None,
            "the group placed",
        ),
        p(
            "transform",
            MAT4,
            false,
            DefaultValue::Floats(&[
                1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
            ]),
            "object to world, column-major",
        ),
        uniform("color"),
        uniform("attribute0"),
        uniform("attribute1"),
        uniform("attribute2"),
        uniform("attribute3"),
        id_param(
            "the instance's number in the frame's instanceId channel (default: none, UINT32 max)",
        ),
    ],
    commit: Some(commit),
};

const fn uniform(name: &'static str) -> crate::device::table::ParamInfo {
    p(
        name,
        &[T::FLOAT32_VEC4],
        false,
        DefaultValue::None,
        "one value of this attribute for every surface the instance places: a material that names it reads this, not the geometry's",
    )
}

/// An instance after commit.
#[derive(Clone)]
pub struct InstanceModel {
    pub group: ObjectRef,
    pub transform: Mat4,
    pub uniform: Uniforms,
    pub id: u32,
}

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let group = r
        .object("group")
        .ok_or("parameter 'group' (GROUP) is required")?
        .clone();
    let transform = r.mat4("transform")?;
    PlacedVolume::check_transform(transform).map_err(|e| format!("transform {transform} {e}"))?;
    let mut uniform = Uniforms::default();
    for (slot, name) in ATTRIBUTE_NAMES.iter().enumerate() {
        if r.set(name).is_some() {
            let v = r.vec4(name)?;
            if !v.is_finite() {
                return Err(format!("{name} {v} must be finite"));
            }
            uniform[slot] = Some(v);
        }
    }
    Ok(Some(State::ready(InstanceModel {
        group,
        transform,
        uniform,
        id: r.id(),
    })))
}
