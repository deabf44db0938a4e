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
    EXT_FRAME_PAIR, EXT_HIT_CHANNELS, F32,
};
use super::types::DataType as T;
use crate::engine::Deadline;
use crate::render::warp::WarpMode;
use crate::render::{ColorFormat, HitChannel};

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::FRAME,
    subtype: "",
    description: "render target: color and depth, lower-left pixel first",
    extensions: &[
        EXT_COMPLETION,
        EXT_ACCUMULATION,
        EXT_FRAME_PAIR,
        EXT_FRAME_DEADLINE,
        EXT_HIT_CHANNELS[0],
        EXT_HIT_CHANNELS[1],
        EXT_HIT_CHANNELS[2],
        EXT_HIT_CHANNELS[3],
        EXT_HIT_CHANNELS[4],
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
            "channel.primitiveId",
            &[T::DATA_TYPE],
            false,
            DefaultValue::None,
            "UINT32: the primitive at each pixel's depth, as the host numbered it or its primitive.id (a volume: 0; nothing: UINT32 max)",
        )
        .data_types(&[T::UINT32]),
        p(
            "channel.objectId",
            &[T::DATA_TYPE],
            false,
            DefaultValue::None,
            "UINT32: the 'id' of the surface or volume at each pixel's depth (none set, or nothing there: UINT32 max)",
        )
        .data_types(&[T::UINT32]),
        p(
            "channel.instanceId",
            &[T::DATA_TYPE],
            false,
            DefaultValue::None,
            "UINT32: the 'id' of the instance that placed what is at each pixel's depth (none set, placed directly, or nothing there: UINT32 max)",
        )
        .data_types(&[T::UINT32]),
        p(
            "channel.normal",
            &[T::DATA_TYPE],
            false,
            DefaultValue::None,
            "FLOAT32_VEC3 or FIXED16_VEC3: the world-space unit normal at each pixel's depth, facing the camera (a volume's: its field's gradient; nothing: zero)",
        )
        .data_types(&[T::FLOAT32_VEC3, T::FIXED16_VEC3]),
        p(
            "channel.albedo",
            &[T::DATA_TYPE],
            false,
            DefaultValue::None,
            "FLOAT32_VEC3, UFIXED8_VEC3 or UFIXED8_RGB_SRGB: the color before lighting at each pixel's depth (a volume's: its transfer function's; nothing: zero)",
        )
        .data_types(&[T::FLOAT32_VEC3, T::UFIXED8_VEC3, T::UFIXED8_RGB_SRGB]),
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
            "renders of unchanged inputs refine the image, one more sample of each pixel's area each, up to 64 (numSamples counts them; depth and the id, normal and albedo channels stay the pixel centre's); false: they keep it",
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
    hit_channels(r.params())?;
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

/// The channels a frame fills from each pixel's hit (render::PixelHit),
/// by their names and in the formats the host set.
pub type HitChannels = Vec<(&'static str, HitChannel)>;

/// The hit channels `p` asks for.
pub fn hit_channels(p: &Params) -> Result<HitChannels, String> {
    let mut out = Vec::new();
    for (name, formats) in HIT_CHANNELS {
        let Some(code) = p.get(name).and_then(|v| v.i32()) else {
            continue;
        };
        let ty = T::from_code(code);
        let format = formats.iter().find(|(t, _)| Some(*t) == ty);
        match format {
            Some((_, format)) => out.push((*name, *format)),
            None => {
                let types: Vec<&str> = formats.iter().map(|(t, _)| t.name()).collect();
                return Err(format!(
                    "{name} {} is not {}",
                    ty.map_or_else(|| code.to_string(), |t| t.name().to_owned()),
                    types.join(" or ")
                ));
            }
        }
    }
    Ok(out)
}

/// Each hit channel and the ANARI types it is filled in.
const HIT_CHANNELS: &[(&str, &[(T, HitChannel)])] = &[
    (
        "channel.primitiveId",
        &[(T::UINT32, HitChannel::PrimitiveId)],
    ),
    ("channel.objectId", &[(T::UINT32, HitChannel::ObjectId)]),
    ("channel.instanceId", &[(T::UINT32, HitChannel::InstanceId)]),
    (
        "channel.normal",
        &[
            (T::FLOAT32_VEC3, HitChannel::NormalF32),
            (T::FIXED16_VEC3, HitChannel::NormalFixed16),
        ],
    ),
    (
        "channel.albedo",
        &[
            (T::FLOAT32_VEC3, HitChannel::AlbedoF32),
            (T::UFIXED8_VEC3, HitChannel::AlbedoUnorm8),
            (T::UFIXED8_RGB_SRGB, HitChannel::AlbedoSrgb8),
        ],
    ),
];

/// The ANARI type a hit channel's format is.
pub fn hit_channel_type(format: HitChannel) -> T {
    HIT_CHANNELS
        .iter()
        .flat_map(|(_, formats)| formats.iter())
        .find(|(_, f)| *f == format)
        .map_or(T::UNKNOWN, |(t, _)| *t)
}

/// What a committed frame asks for, read when it renders.
pub struct Setup {
    pub size: UVec2,
    pub color_type: Option<T>,
    pub depth: bool,
    pub hit_channels: HitChannels,
    /// Renders of unchanged inputs refine the image.
    pub accumulate: bool,
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
        hit_channels: hit_channels(p)?,
        accumulate: p
            .get("accumulation")
            .and_then(|v| v.bool())
            .unwrap_or(false),
        deadline: deadline(p)?,
    })
}
