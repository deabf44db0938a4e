//! The world: the scene a frame renders.

use super::info::{p, Default, SubtypeInfo};
use super::object::{Derived, State};
use super::read::Read;
use super::types::DataType as T;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::WORLD,
    subtype: "",
    description: "the scene: caveray renders its first volume",
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
    let volumes = match r.object("volume") {
        None => Vec::new(),
        Some(array) => {
            let guard = array.lock();
            let State::Array(a) = &guard.state else {
                return Err(format!("'volume' is {}, not an array", array.describe()));
            };
            if a.element() != T::VOLUME {
                return Err(format!(
                    "'volume' array holds {}; expected ANARI_VOLUME",
                    a.element()
                ));
            }
            a.objects.iter().flatten().cloned().collect()
        }
    };
    Ok(Some(State::World(Derived::Ready(volumes))))
}
