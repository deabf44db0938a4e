//! ANARI's `orthographic` camera: parallel rays from a rectangle `height`
//! tall (VTK and ParaView's parallel projection, the SDK viewer's
//! orthographic mode).

use super::{placed_params, CameraModel, Placement};
use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, ParamInfo, SubtypeInfo, EXT_ORTHOGRAPHIC, F32};
use crate::device::types::DataType as T;

static PARAMS: [ParamInfo; 8] = placed_params(p(
    "height",
    F32,
    false,
    DefaultValue::Floats(&[1.0]),
    "height of the image rectangle in world units",
));

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::CAMERA,
    subtype: "orthographic",
    description: "parallel rays from an image rectangle `height` tall",
    extensions: &[EXT_ORTHOGRAPHIC],
    params: &PARAMS,
    commit: Some(commit),
};

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    CameraModel::Orthographic {
        placement: Placement::read(r)?,
        height: r.f32("height")?.into(),
    }
    .committed()
}
