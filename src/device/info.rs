//! What caveray implements, per object kind and subtype: the parameters it
//! reads, their accepted types, defaults and descriptions. Setting a
//! parameter is checked against this table, and the info queries
//! (`anariGetObjectInfo`, `anariGetParameterInfo`) answer from it.

use super::types::DataType as T;

pub struct ParamInfo {
    pub name: &'static str,
    /// Accepted types, the preferred one first.
    pub types: &'static [T],
    pub required: bool,
    /// Default value as FLOAT32 components (for FLOAT32-based types).
    pub default: Option<&'static [f32]>,
    pub description: &'static str,
}

pub struct SubtypeInfo {
    pub kind: T,
    pub subtype: &'static str,
    pub description: &'static str,
    /// Extensions (by name) this subtype belongs to.
    pub extensions: &'static [&'static str],
    pub params: &'static [ParamInfo],
}

const fn p(
    name: &'static str,
    types: &'static [T],
    required: bool,
    default: Option<&'static [f32]>,
    description: &'static str,
) -> ParamInfo {
    ParamInfo {
        name,
        types,
        required,
        default,
        description,
    }
}

/// The matrix camera's extension under anari-visionaray's name (clients
/// written for it work unchanged) and under ours.
pub const EXT_MATRIX_VSNRAY: &str = "ANARI_VSNRAY_CAMERA_MATRIX";
pub const EXT_MATRIX: &str = "CAVERAY_CAMERA_MATRIX";
pub const EXT_OFF_AXIS: &str = "CAVERAY_CAMERA_OFF_AXIS";
pub const EXT_SHADING: &str = "CAVERAY_RENDERER_SHADING";

/// Every extension the device supports (device property `extension`).
pub const EXTENSIONS: &[&str] = &[
    "ANARI_KHR_CAMERA_PERSPECTIVE",
    "ANARI_KHR_SPATIAL_FIELD_STRUCTURED_REGULAR",
    "ANARI_KHR_VOLUME_TRANSFER_FUNCTION1D",
    "ANARI_KHR_FRAME_COMPLETION_CALLBACK",
    EXT_MATRIX_VSNRAY,
    EXT_MATRIX,
    EXT_OFF_AXIS,
    EXT_SHADING,
];

const VEC3: &[T] = &[T::FLOAT32_VEC3];
const F32: &[T] = &[T::FLOAT32];
const MAT4: &[T] = &[T::FLOAT32_MAT4];

pub static SUBTYPES: &[SubtypeInfo] = &[
    SubtypeInfo {
        kind: T::DEVICE,
        subtype: "default",
        description: "caveray: off-axis volume ray casting for CAVEs and powerwalls",
        extensions: &[],
        params: &[
            p("statusCallback", &[T::STATUS_CALLBACK], false, None,
              "function receiving every error, warning and info message; takes effect on commit"),
            p("statusCallbackUserData", &[T::VOID_POINTER], false, None,
              "passed back as the status callback's first argument"),
            p("backend", &[T::STRING], false, None,
              "auto | gpu | cpu: the Vulkan ray caster, the CPU reference, or the GPU when one opens \
               (default auto, or $CAVERAY_BACKEND)"),
        ],
    },
    SubtypeInfo {
        kind: T::CAMERA,
        subtype: "perspective",
        description: "pinhole camera; an off-axis wall is a widened frustum cropped by imageRegion",
        extensions: &["ANARI_KHR_CAMERA_PERSPECTIVE"],
        params: &[
            p("position", VEC3, false, Some(&[0.0, 0.0, 0.0]), "eye position"),
            p("direction", VEC3, false, Some(&[0.0, 0.0, -1.0]), "viewing direction"),
            p("up", VEC3, false, Some(&[0.0, 1.0, 0.0]), "up vector"),
            p("fovy", F32, false, Some(&[std::f32::consts::FRAC_PI_3]),
              "vertical field of view in radians"),
            p("aspect", F32, false, None, "width / height (default: the frame's)"),
            p("imageRegion", &[T::FLOAT32_BOX2], false, Some(&[0.0, 0.0, 1.0, 1.0]),
              "part of the image that is rendered, (min.x, min.y, max.x, max.y) in [0, 1]"),
        ],
    },
    SubtypeInfo {
        kind: T::CAMERA,
        subtype: "matrix",
        description: "rays from the inverse of OpenGL view and projection matrices (off-axis strategy 1)",
        extensions: &[EXT_MATRIX_VSNRAY, EXT_MATRIX],
        params: &[
            p("view", MAT4, true, None, "OpenGL view matrix, column-major"),
            p("proj", MAT4, true, None, "OpenGL projection matrix, column-major, NDC z in [-1, 1]"),
        ],
    },
    SubtypeInfo {
        kind: T::CAMERA,
        subtype: "offAxis",
        description: "rays from a tracked eye through a wall given by three corners",
        extensions: &[EXT_OFF_AXIS],
        params: &[
            p("lowerLeft", VEC3, true, None, "wall's lower-left corner"),
            p("lowerRight", VEC3, true, None, "wall's lower-right corner"),
            p("upperRight", VEC3, true, None, "wall's upper-right corner"),
            p("eye", VEC3, true, None, "eye position, in front of the wall"),
        ],
    },
    SubtypeInfo {
        kind: T::SPATIAL_FIELD,
        subtype: "structuredRegular",
        description: "vertex-centred regular grid, x fastest, sampled trilinearly",
        extensions: &["ANARI_KHR_SPATIAL_FIELD_STRUCTURED_REGULAR"],
        params: &[
            p("data", &[T::ARRAY3D], true, None,
              "voxels: UFIXED8, UFIXED16, FIXED16, FLOAT32 or FLOAT64 (UINT8/UINT16 read as UFIXED)"),
            p("origin", VEC3, false, Some(&[0.0, 0.0, 0.0]), "position of voxel (0, 0, 0)"),
            p("spacing", VEC3, false, Some(&[1.0, 1.0, 1.0]), "distance between voxel centres"),
            p("filter", &[T::STRING], false, None, "linear (nearest is read as linear)"),
        ],
    },
    SubtypeInfo {
        kind: T::VOLUME,
        subtype: "transferFunction1D",
        description: "a spatial field classified by a 1D colour and opacity map",
        extensions: &["ANARI_KHR_VOLUME_TRANSFER_FUNCTION1D"],
        params: &[
            p("value", &[T::SPATIAL_FIELD], true, None, "the spatial field"),
            p("valueRange", &[T::FLOAT32_BOX1, T::FLOAT64_BOX1], false, Some(&[0.0, 1.0]),
              "field values mapped to the first and last entries"),
            p("color", &[T::ARRAY1D, T::FLOAT32_VEC3, T::FLOAT32_VEC4], false, Some(&[1.0, 1.0, 1.0]),
              "ARRAY1D of FLOAT32_VEC3/VEC4 spread over valueRange, or one colour"),
            p("opacity", &[T::ARRAY1D, T::FLOAT32], false, Some(&[1.0]),
              "ARRAY1D of FLOAT32 spread over valueRange, or one opacity"),
            p("unitDistance", F32, false, Some(&[1.0]),
              "world distance over which the opacities apply"),
        ],
    },
    SubtypeInfo {
        kind: T::WORLD,
        subtype: "",
        description: "the scene: caveray renders its first volume",
        extensions: &[],
        params: &[p("volume", &[T::ARRAY1D], false, None, "ARRAY1D of ANARI_VOLUME")],
    },
    SubtypeInfo {
        kind: T::RENDERER,
        subtype: "default",
        description: "emission-absorption ray casting with optional shadows and ambient occlusion",
        extensions: &[EXT_SHADING],
        params: &[
            p("background", &[T::FLOAT32_VEC4], false, Some(&[0.0, 0.0, 0.0, 1.0]),
              "colour behind the volume, straight alpha"),
            p("shading", &[T::STRING], false, None,
              "none | shadows | ao | shadows+ao | directional:N (N <= 64); default none"),
            p("lightDirection", VEC3, false, Some(&[0.3, 0.5, 0.8]),
              "direction towards the parallel light of shadows"),
            p("stepFactor", F32, false, Some(&[1.0]),
              "step length in units of half the smallest voxel extent"),
            p("terminationThreshold", F32, false, Some(&[0.99]),
              "opacity at which a ray stops; above 1 disables early termination"),
        ],
    },
    SubtypeInfo {
        kind: T::FRAME,
        subtype: "",
        description: "render target: colour and depth, lower-left pixel first",
        extensions: &[],
        params: &[
            p("size", &[T::UINT32_VEC2], true, None, "width and height in pixels"),
            p("world", &[T::WORLD], true, None, "what to render"),
            p("camera", &[T::CAMERA], true, None, "where from"),
            p("renderer", &[T::RENDERER], true, None, "how"),
            p("channel.color", &[T::DATA_TYPE], false, None,
              "UFIXED8_VEC4, UFIXED8_RGBA_SRGB or FLOAT32_VEC4 (unset: no colour channel)"),
            p("channel.depth", &[T::DATA_TYPE], false, None,
              "FLOAT32: distance from the camera to the first visible sample"),
            p("frameCompletionCallback", &[T::FRAME_COMPLETION_CALLBACK], false, None,
              "called on the render thread when a frame is done"),
            p("frameCompletionCallbackUserData", &[T::VOID_POINTER], false, None,
              "first argument of the frame completion callback"),
        ],
    },
];

/// Subtype names of `kind` that caveray implements, in table order.
pub fn subtypes(kind: T) -> Vec<&'static str> {
    SUBTYPES
        .iter()
        .filter(|s| s.kind == kind && !s.subtype.is_empty())
        .map(|s| s.subtype)
        .collect()
}

/// The table entry for `kind` and `subtype`; kinds without subtypes
/// (world, frame) match any subtype.
pub fn subtype(kind: T, subtype: &str) -> Option<&'static SubtypeInfo> {
    SUBTYPES
        .iter()
        .find(|s| s.kind == kind && (s.subtype.is_empty() || s.subtype == subtype))
}

pub fn param(kind: T, sub: &str, name: &str) -> Option<&'static ParamInfo> {
    subtype(kind, sub)?.params.iter().find(|p| p.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_fit_their_types_and_names_are_unique() {
        for s in SUBTYPES {
            for (i, p) in s.params.iter().enumerate() {
                assert!(
                    !p.types.is_empty(),
                    "{}.{} accepts nothing",
                    s.subtype,
                    p.name
                );
                if let Some(d) = p.default {
                    let size = p.types.iter().find(|t| t.size() == 4 * d.len());
                    assert!(
                        size.is_some(),
                        "{}.{}: default {d:?} fits none of {:?}",
                        s.subtype,
                        p.name,
                        p.types
                    );
                }
                assert!(
                    s.params[..i].iter().all(|q| q.name != p.name),
                    "{}.{} listed twice",
                    s.subtype,
                    p.name
                );
            }
            for e in s.extensions {
                assert!(
                    EXTENSIONS.contains(e),
                    "{e} of {} is not advertised",
                    s.subtype
                );
            }
        }
    }

    #[test]
    fn kinds_without_subtypes_match_any_name() {
        assert!(subtype(T::WORLD, "").is_some());
        assert!(subtype(T::FRAME, "anything").is_some());
        assert!(subtype(T::CAMERA, "fisheye").is_none());
        assert_eq!(subtypes(T::CAMERA), ["perspective", "matrix", "offAxis"]);
        assert!(subtypes(T::GEOMETRY).is_empty());
    }
}
