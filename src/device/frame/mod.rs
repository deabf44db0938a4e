//! The frame: what to render (world, camera, renderer), at which size and
//! into which channels. Its parameters are read when it renders, since
//! hosts commit frames before they know the size; commit only reports a
//! color channel caveray cannot fill. A render whose inputs equal the
//! last one's keeps its image (the engine's `FrameRenders`).

pub mod state;

use glam::UVec2;

use super::object::Params;
use super::object::State;
use super::table::Read;
use super::table::{
    p, DefaultValue, SubtypeInfo, EXT_ACCUMULATION, EXT_COMPLETION, EXT_FRAME_DEADLINE,
    EXT_FRAME_PAIR, F32,
};
use super::types::DataType as T;
use crate::engine::Deadline;
use crate::render::warp::WarpMode;
use crate::render::ColorFormat;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::FRAME,
    subtype: "",
    description: "render target: color and depth, lower-left pixel first",
    extensions: &[
        EXT_COMPLETION,
        EXT_ACCUMULATION,
        EXT_FRAME_PAIR,
        EXT_FRAME_DEADLINE,
    ],
    params: &[
        p(
            "size",
            &[T::UINT32_VEC2],
            true,
            DefaultValue::None,
            "width and height in pixels",
        ),
        p("world", &[T::WORLD], true, DefaultValue::None, "what to render"),
        p("camera", &[T::CAMERA], true, DefaultValue::None, "where from"),
        p("renderer", &[T::RENDERER], true, DefaultValue::None, "how"),
        p(
            "channel.color",
            &[T::DATA_TYPE],
            false,
            DefaultValue::None,
            "UFIXED8_VEC4, UFIXED8_RGBA_SRGB or FLOAT32_VEC4 (unset: no color channel)",
        )
        .data_types(&[T::UFIXED8_VEC4, T::UFIXED8_RGBA_SRGB, T::FLOAT32_VEC4]),
        p(
            "channel.depth",
            &[T::DATA_TYPE],
            false,
            DefaultValue::None,
            "FLOAT32: distance from the camera to the first visible sample",
        )
        .data_types(&[T::FLOAT32]),
        p(
            "frameCompletionCallback",
            &[T::FRAME_COMPLETION_CALLBACK],
            false,
            DefaultValue::None,
            "called on the render thread when a frame is done",
        ),
        p(
            "frameCompletionCallbackUserData",
            &[T::VOID_POINTER],
            false,
            DefaultValue::None,
            "first argument of the frame completion callback",
        ),
        p(
            "accumulation",
            &[T::BOOL],
            false,
            DefaultValue::None,
            "accepted: a render is complete at once, and renders of unchanged inputs keep it (numSamples counts them)",
        ),
        p(
            "stereoPartner",
            &[T::FRAME],
            false,
            DefaultValue::None,
            "the frame showing the other eye of this wall: rendered with this one in one re-projection pass, its image kept for its next render if its inputs are unchanged",
        ),
        p(
            "caveray.deadline",
            F32,
            false,
            DefaultValue::Floats(&[0.0]),
            "milliseconds after anariRenderFrame by which the frame is ready: the newest complete image warped to this render's camera, while the full render goes on in the background (0: no deadline, every render whole)",
        )
        .range(0.0, MAX_DEADLINE_MS),
        p(
            "caveray.warp",
            &[T::STRING],
            false,
            DefaultValue::Text("quad"),
            "how a deadline frame brings the newest complete image to its camera: none, quad (the image as a plane through the scene's centre), grid (a mesh on the first-hit depth) or layers (emission-absorption layers re-marched)",
        )
        .names(WARP_NAMES),
    ],
    commit: Some(commit),
};

/// The longest deadline a frame may set (ms).
pub const MAX_DEADLINE_MS: f32 = 10_000.0;
const WARP_NAMES: &[&str] = &["none", "quad", "grid", "layers"];

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    color_type(r.params())?;
    deadline(r.params())?;
    Ok(None)
}

/// The deadline (if any) and warp a frame asks for.
pub fn deadline(p: &Params) -> Result<Option<Deadline>, String> {
    let r = Read::new(p, INFO.params);
    let ms = r.f32("caveray.deadline")?;
    if !(ms.is_finite() && (0.0..=MAX_DEADLINE_MS).contains(&ms)) {
        return Err(format!(
            "caveray.deadline must be 0 (none) to {MAX_DEADLINE_MS} ms, got {ms}"
        ));
    }
    let warp = r.string("caveray.warp").unwrap_or("quad");
    let warp = warp
        .parse::<WarpMode>()
        .map_err(|e| format!("caveray.warp: {e}"))?;
    Ok((ms > 0.0).then(|| Deadline {
        after: std::time::Duration::from_secs_f32(ms / 1e3),
        warp,
    }))
}

/// The renderer's pixel format for a `channel.color` type.
pub fn color_format(ty: T) -> Option<ColorFormat> {
    match ty {
        T::UFIXED8_VEC4 => Some(ColorFormat::Rgba8),
        T::UFIXED8_RGBA_SRGB => Some(ColorFormat::Srgba8),
        T::FLOAT32_VEC4 => Some(ColorFormat::Rgba32F),
        _ => None,
    }
}

/// The color channel's type, `None` if the frame has none.
pub fn color_type(p: &Params) -> Result<Option<T>, String> {
    let Some(code) = p.get("channel.color").and_then(|v| v.i32()) else {
        return Ok(None);
    };
    match T::from_code(code) {
        Some(t) if color_format(t).is_some() => Ok(Some(t)),
        t => Err(format!(
            "channel.color {} is not UFIXED8_VEC4, UFIXED8_RGBA_SRGB or FLOAT32_VEC4",
            t.map_or_else(|| code.to_string(), |t| t.name().to_owned())
        )),
    }
}

/// What a committed frame asks for, read when it renders.
pub struct Setup {
    pub size: UVec2,
    pub color_type: Option<T>,
    pub depth: bool,
    pub deadline: Option<Deadline>,
}

pub fn setup(p: &Params) -> Result<Setup, String> {
    let size = match p.get("size").and_then(|v| v.u32s()).as_deref() {
        Some(&[w, h]) if w > 0 && h > 0 => UVec2::new(w, h),
        Some(&[w, h]) => return Err(format!("size {w}x{h} has no pixels")),
        _ => return Err("parameter 'size' (UINT32_VEC2) is not set".into()),
    };
    let color_type = color_type(p)?;
    let depth = match p.get("channel.depth").and_then(|v| v.i32()) {
        None => false,
        Some(code) if code == T::FLOAT32 as i32 => true,
        Some(code) => return Err(format!("channel.depth {code} is not FLOAT32")),
    };
    Ok(Setup {
        size,
        color_type,
        depth,
        deadline: deadline(p)?,
    })
}
