//! The group: volumes an instance places in the world together.

use super::info::{p, Default, SubtypeInfo};
use super::object::{Derived, State};
use super::read::Read;
use super::types::DataType as T;
use super::world::objects;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::GROUP,
    subtype: "",
    description: "volumes placed together by an instance",
    extensions: &[],
    params: &[p(
        "volume",
        &[T::ARRAY1D],
        false,
        Default::None,
        "ARRAY1D of ANARI_VOLUME",
    )
    .elements(&[T::VOLUME])],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    Ok(Some(State::Group(Derived::Ready(objects(
        r,
        "volume",
        T::VOLUME,
    )?))))
}
