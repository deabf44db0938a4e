//! The surface: a geometry drawn in a material, as worlds and groups
//! hold them.

use super::object::{ObjectRef, State};
use super::table::Read;
use super::table::{id_param, p, DefaultValue, SubtypeInfo};
use super::types::DataType as T;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::SURFACE,
    subtype: "",
    description: "a geometry (triangle, quad, sphere, isosurface) drawn in a material (matte; curvature for isosurfaces)",
    extensions: &[],
    params: &[
        p(
            "geometry",
            &[T::GEOMETRY],
            true,
            DefaultValue::None,
            "what is drawn",
        ),
        p(
            "material",
            &[T::MATERIAL],
            true,
            DefaultValue::None,
            "how it is colored",
        ),
        id_param("the surface's number in the frame's objectId channel (default: none, UINT32 max)"),
    ],
    commit: Some(commit),
};

/// A surface after commit: its objects, resolved when a frame renders.
#[derive(Clone)]
pub struct SurfaceModel {
    pub geometry: ObjectRef,
    pub material: ObjectRef,
    pub id: u32,
}

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    // Setting the parameters checked their kinds.
    let object = |name: &str, kind: T| -> Result<ObjectRef, String> {
        r.object(name)
            .cloned()
            .ok_or_else(|| format!("parameter '{name}' ({kind}) is required"))
    };
    Ok(Some(State::ready(SurfaceModel {
        geometry: object("geometry", T::GEOMETRY)?,
        material: object("material", T::MATERIAL)?,
        id: r.id(),
    })))
}
