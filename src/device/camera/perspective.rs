//! ANARI's `perspective` camera. An off-axis CAVE wall is a widened
//! symmetric frustum cropped by `imageRegion` (strategy 2).

use glam::DVec2;

use super::CameraModel;
use crate::device::info::{p, Default, SubtypeInfo, F32, VEC3};
use crate::device::object::State;
use crate::device::read::Read;
use crate::device::types::DataType as T;
use crate::geometry::ImageRegion;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::CAMERA,
    subtype: "perspective",
    description: "pinhole camera; an off-axis wall is a widened frustum cropped by imageRegion",
    extensions: &["ANARI_KHR_CAMERA_PERSPECTIVE"],
    params: &[
        p(
            "position",
            VEC3,
            false,
            Default::Floats(&[0.0, 0.0, 0.0]),
            "eye position",
        ),
        p(
            "direction",
            VEC3,
            false,
            Default::Floats(&[0.0, 0.0, -1.0]),
            "viewing direction",
        ),
        p(
            "up",
            VEC3,
            false,
            Default::Floats(&[0.0, 1.0, 0.0]),
            "up vector",
        ),
        p(
            "fovy",
            F32,
            false,
            Default::Floats(&[std::f32::consts::FRAC_PI_3]),
            "vertical field of view in radians",
        )
        .range(0.01, 3.1),
        p(
            "aspect",
            F32,
            false,
            Default::None,
            "width / height (default: the frame's)",
        ),
        p(
            "imageRegion",
            &[T::FLOAT32_BOX2],
            false,
            Default::Floats(&[0.0, 0.0, 1.0, 1.0]),
            "part of the image that is rendered, (min.x, min.y, max.x, max.y) in [0, 1]",
        ),
    ],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let [x0, y0, x1, y1] = r.floats::<4>("imageRegion")?;
    CameraModel::Perspective {
        position: r.vec3("position")?.as_dvec3(),
        direction: r.vec3("direction")?.as_dvec3(),
        up: r.vec3("up")?.as_dvec3(),
        fovy: r.f32("fovy")?.into(),
        aspect: r
            .set("aspect")
            .map(|_| r.f32("aspect"))
            .transpose()?
            .map(f64::from),
        region: ImageRegion {
            min: DVec2::new(x0.into(), y0.into()),
            max: DVec2::new(x1.into(), y1.into()),
        },
    }
    .committed()
}
