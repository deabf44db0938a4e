//! The `matrix` camera (off-axis strategy 1): rays from the inverse of the
//! host's OpenGL view and projection matrices, under anari-visionaray's
//! extension name as well as ours.

use super::CameraModel;
use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, EXT_MATRIX, EXT_MATRIX_VSNRAY, MAT4};
use crate::device::types::DataType as T;
use crate::geometry::MatrixCamera;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::CAMERA,
    subtype: "matrix",
    description:
        "rays from the inverse of OpenGL view and projection matrices (off-axis strategy 1)",
    extensions: &[EXT_MATRIX_VSNRAY, EXT_MATRIX],
    params: &[
        p(
            "view",
            MAT4,
            true,
            DefaultValue::None,
            "OpenGL view matrix, column-major",
        ),
        p(
            "proj",
            MAT4,
            true,
            DefaultValue::None,
            "OpenGL projection matrix, column-major, NDC z in [-1, 1]",
        ),
    ],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let camera = MatrixCamera::from_f32(r.mat4("view")?, r.mat4("proj")?);
    CameraModel::Matrix(Box::new(camera.map_err(|e| e.to_string())?)).committed()
}
