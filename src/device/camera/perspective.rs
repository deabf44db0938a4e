//! ANARI's `perspective` camera. An off-axis CAVE wall is a widened
//! symmetric frustum cropped by `imageRegion` (strategy 2).

use super::stereo::{self, Stereo};
use super::{placed_params, CameraModel, Placement};
use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, ParamInfo, SubtypeInfo, EXT_STEREO, F32};
use crate::device::types::DataType as T;

static PARAMS: [ParamInfo; 10] = {
    let [a, b, c, d, e, f, g, h] = placed_params(
        p(
            "fovy",
            F32,
            false,
            DefaultValue::Floats(&[std::f32::consts::FRAC_PI_3]),
            "vertical field of view in radians",
        )
        .range(0.01, 3.1),
    );
    let [mode, ipd] = stereo::params();
    [a, b, c, d, e, f, g, h, mode, ipd]
};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::CAMERA,
    subtype: "perspective",
    description: "pinhole camera; an off-axis wall is a widened frustum cropped by imageRegion; its stereoMode is HMD stereo, wrong for CAVE walls",
    extensions: &["ANARI_KHR_CAMERA_PERSPECTIVE", EXT_STEREO],
    params: &PARAMS,
    commit: Some(commit),
};

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    CameraModel::Perspective {
        placement: Placement::read(r)?,
        fovy: r.f32("fovy")?.into(),
        stereo: Stereo::from_params(r)?,
    }
    .committed()
}
