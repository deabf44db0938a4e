//! The group: volumes and surfaces an instance places in the world
//! together.

use super::object::{ObjectRef, State};
use super::table::Read;
use super::table::{object_list, SubtypeInfo};
use super::types::DataType as T;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::GROUP,
    subtype: "",
    description: "volumes and surfaces placed together by an instance",
    extensions: &[],
    params: &[
        object_list("volume", &[T::VOLUME, T::OBJECT], "ARRAY1D of ANARI_VOLUME"),
        object_list(
            "surface",
            &[T::SURFACE, T::OBJECT],
            "ARRAY1D of ANARI_SURFACE",
        ),
    ],
    commit: Some(commit),
};

/// A group after commit.
#[derive(Clone, Default)]
pub struct GroupModel {
    pub volumes: Vec<ObjectRef>,
    pub surfaces: Vec<ObjectRef>,
}

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    Ok(Some(State::ready(GroupModel {
        volumes: r.objects("volume", T::VOLUME)?,
        surfaces: r.objects("surface", T::SURFACE)?,
    })))
}
