//! caveray's `offAxis` camera: a wall by three corners and the tracked
//! eye, the form CAVE rigs describe themselves in.

use super::stereo::{self, Stereo};
use super::CameraModel;
use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{
    p, DefaultValue, ParamInfo, SubtypeInfo, EXT_OFF_AXIS, EXT_STEREO, VEC3,
};
use crate::device::types::DataType as T;
use crate::geometry::{OffAxisCamera, Screen};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::CAMERA,
    subtype: "offAxis",
    description: "rays from a tracked eye through a wall given by three corners",
    extensions: &[EXT_OFF_AXIS, EXT_STEREO],
    params: &PARAMS,
    commit: Some(commit),
};

static PARAMS: [ParamInfo; 7] = {
    let [mode, ipd] = stereo::params();
    [
        p(
            "lowerLeft",
            VEC3,
            true,
            DefaultValue::None,
            "wall's lower-left corner",
        ),
        p(
            "lowerRight",
            VEC3,
            true,
            DefaultValue::None,
            "wall's lower-right corner",
        ),
        p(
            "upperRight",
            VEC3,
            true,
            DefaultValue::None,
            "wall's upper-right corner",
        ),
        p(
            "eye",
            VEC3,
            true,
            DefaultValue::None,
            "eye position, in front of the wall (with stereoMode: between the eyes)",
        ),
        mode,
        ipd,
        p(
            "eyeAxis",
            VEC3,
            false,
            DefaultValue::None,
            "from the left eye towards the right one (the head's right vector; default: along the wall's rows)",
        ),
    ]
};

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let point = |name| r.vec3(name).map(|v| v.as_dvec3());
    let screen = Screen::new(
        point("lowerLeft")?,
        point("lowerRight")?,
        point("upperRight")?,
    )
    .map_err(|e| e.to_string())?;
    let camera = OffAxisCamera::new(screen, point("eye")?).map_err(|e| e.to_string())?;
    let axis = match r.set("eyeAxis") {
        Some(_) => point("eyeAxis")?,
        None => screen.lr() - screen.ll(),
    };
    let axis = axis
        .try_normalize()
        .ok_or_else(|| format!("eyeAxis {axis} has no direction"))?;
    CameraModel::OffAxis {
        camera,
        stereo: Stereo::from_params(r)?,
        axis,
    }
    .committed()
}
