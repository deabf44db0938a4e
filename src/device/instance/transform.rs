//! The `transform` instance (ANARI_KHR_INSTANCE_TRANSFORM): a group placed
//! in the world by an affine matrix, as VTK and ParaView place each
//! dataset's volume.

use glam::Mat4;

use crate::device::object::{ObjectRef, State};
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, MAT4};
use crate::device::types::DataType as T;
use crate::scene::PlacedVolume;

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
    ],
    commit: Some(commit),
};

/// An instance after commit.
#[derive(Clone)]
pub struct InstanceModel {
    pub group: ObjectRef,
    pub transform: Mat4,
}

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let group = r
        .object("group")
        .ok_or("parameter 'group' (GROUP) is required")?
        .clone();
    let transform = r.mat4("transform")?;
    PlacedVolume::check_transform(transform).map_err(|e| format!("transform {transform} {e}"))?;
    Ok(Some(State::ready(InstanceModel { group, transform })))
}
