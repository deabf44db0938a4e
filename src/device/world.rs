//! The world: the scene a frame renders, its volumes and its lights.

use super::info::{p, Default, SubtypeInfo};
use super::object::{Derived, ObjectRef, State};
use super::read::Read;
use super::types::DataType as T;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::WORLD,
    subtype: "",
    description: "the scene: caveray renders its first volume, lit by its first directional light",
    extensions: &[],
    params: &[
        p(
            "volume",
            &[T::ARRAY1D],
            false,
            Default::None,
            "ARRAY1D of ANARI_VOLUME",
        )
        .elements(&[T::VOLUME]),
        p(
            "light",
            &[T::ARRAY1D],
            false,
            Default::None,
            "ARRAY1D of ANARI_LIGHT; the first directional light sets the shading's light",
        )
        .elements(&[T::LIGHT]),
    ],
    commit: Some(commit),
};

/// A world after commit: the objects its arrays name.
#[derive(Clone, Default)]
pub struct WorldModel {
    pub volumes: Vec<ObjectRef>,
    pub lights: Vec<ObjectRef>,
}

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    Ok(Some(State::World(Derived::Ready(WorldModel {
        volumes: objects(r, "volume", T::VOLUME)?,
        lights: objects(r, "light", T::LIGHT)?,
    }))))
}

/// The objects of array parameter `name`, which must hold `element`s.
fn objects(r: &Read<'_>, name: &str, element: T) -> Result<Vec<ObjectRef>, String> {
    let Some(array) = r.object(name) else {
        return Ok(Vec::new());
    };
    let guard = array.lock();
    let State::Array(a) = &guard.state else {
        return Err(format!("'{name}' is {}, not an array", array.describe()));
    };
    if a.element() != element {
        return Err(format!(
            "'{name}' array holds {}; expected {element}",
            a.element()
        ));
    }
    Ok(a.objects.iter().flatten().cloned().collect())
}
