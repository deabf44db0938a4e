//! ANARI's `perspective` camera. An off-axis CAVE wall is a widened
//! symmetric frustum cropped by `imageRegion` (strategy 2).

use super::stereo::{Stereo, StereoMode};
use super::{placed_params, CameraModel, Placement};
use crate::device::info::{p, Default, ParamInfo, SubtypeInfo, EXT_STEREO, F32};
use crate::device::object::State;
use crate::device::read::Read;
use crate::device::types::DataType as T;

static PARAMS: [ParamInfo; 10] = {
    let [a, b, c, d, e, f, g, h] = placed_params(
        p(
            "fovy",
            F32,
            false,
            Default::Floats(&[std::f32::consts::FRAC_PI_3]),
            "vertical field of view in radians",
        )
        .range(0.01, 3.1),
    );
    [
        a,
        b,
        c,
        d,
        e,
        f,
        g,
        h,
        p(
            "stereoMode",
            &[T::STRING],
            false,
            Default::Text("none"),
            "none, left, right, sideBySide (left eye in the left half) or topBottom (left eye on top); wrong for CAVE walls, where each eye needs its own camera",
        )
        .names(StereoMode::NAMES),
        p(
            "interpupillaryDistance",
            F32,
            false,
            Default::Floats(&[0.0635]),
            "distance between the eyes of stereoMode, in world units",
        )
        .range(0.0, 1.0),
    ]
};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::CAMERA,
    subtype: "perspective",
    description: "pinhole camera; an off-axis wall is a widened frustum cropped by imageRegion",
    extensions: &["ANARI_KHR_CAMERA_PERSPECTIVE", EXT_STEREO],
    params: &PARAMS,
    commit: Some(commit),
};

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    CameraModel::Perspective {
        placement: Placement::read(r)?,
        fovy: r.f32("fovy")?.into(),
        stereo: Stereo::read(
            r.string("stereoMode").unwrap_or("none"),
            r.f32("interpupillaryDistance")?,
        )?,
    }
    .committed()
}
