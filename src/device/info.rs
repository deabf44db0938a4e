//! What caveray implements: one `SubtypeInfo` per object kind and subtype,
//! each in its own module beside its commit, listed once in `SUBTYPES`.
//! Setting a parameter is checked against these tables, commits read their
//! defaults from them, and the info queries (`anariGetObjectInfo`,
//! `anariGetParameterInfo`) answer from them.

use super::object::State;
use super::read::Read;
use super::types::DataType as T;
use super::{
    camera, device_object, frame, geometry, group, instance, light, material, renderer,
    spatial_field, surface, volume, world,
};

pub struct ParamInfo {
    pub name: &'static str,
    /// Accepted types, the preferred one first.
    pub types: &'static [T],
    pub required: bool,
    pub default: DefaultValue,
    pub description: &'static str,
    /// For array parameters: the element types read.
    pub elements: &'static [T],
    /// For enumerations (STRING): the names understood.
    pub names: &'static [&'static str],
    /// For DATA_TYPE parameters: the types understood.
    pub data_types: &'static [T],
    /// For numbers: the smallest and largest sensible value.
    pub range: Option<(f32, f32)>,
}

impl ParamInfo {
    pub const fn elements(mut self, elements: &'static [T]) -> Self {
        self.elements = elements;
        self
    }
    pub const fn names(mut self, names: &'static [&'static str]) -> Self {
        self.names = names;
        self
    }
    pub const fn data_types(mut self, types: &'static [T]) -> Self {
        self.data_types = types;
        self
    }
    pub const fn range(mut self, lo: f32, hi: f32) -> Self {
        self.range = Some((lo, hi));
        self
    }
}

/// A parameter's value when the host sets none.
pub enum DefaultValue {
    None,
    /// FLOAT32 components (for FLOAT32-based types); the info queries
    /// answer these.
    Floats(&'static [f32]),
    /// An enumeration's default name.
    Text(&'static str),
    /// A BOOL's.
    Bool(bool),
}

/// What committing a subtype derives from its parameters: its new state,
/// `None` where parameters are read later (frames, at render time), or
/// why the parameters cannot be used. Warnings about accepted-but-odd
/// input go to the callback.
pub type Commit = fn(&Read<'_>, &mut dyn FnMut(String)) -> Result<Option<State>, String>;

pub struct SubtypeInfo {
    pub kind: T,
    pub subtype: &'static str,
    pub description: &'static str,
    /// Extensions (by name) this subtype belongs to.
    pub extensions: &'static [&'static str],
    pub params: &'static [ParamInfo],
    /// `None` for the device, whose commit is the device's own.
    pub commit: Option<Commit>,
}

/// An optional ARRAY1D parameter of objects of one kind.
pub const fn object_list(
    name: &'static str,
    element: &'static [T],
    description: &'static str,
) -> ParamInfo {
    p(name, &[T::ARRAY1D], false, DefaultValue::None, description).elements(element)
}

pub const fn p(
    name: &'static str,
    types: &'static [T],
    required: bool,
    default: DefaultValue,
    description: &'static str,
) -> ParamInfo {
    ParamInfo {
        name,
        types,
        required,
        default,
        description,
        elements: &[],
        names: &[],
        data_types: &[],
        range: None,
    }
}

pub const VEC3: &[T] = &[T::FLOAT32_VEC3];
pub const F32: &[T] = &[T::FLOAT32];
pub const MAT4: &[T] = &[T::FLOAT32_MAT4];

/// The matrix camera's extension under anari-visionaray's name (clients
/// written for it work unchanged) and under ours. Every name carries the
/// `ANARI_` prefix, as hosts look extensions up with it.
pub const EXT_MATRIX_VSNRAY: &str = "ANARI_VSNRAY_CAMERA_MATRIX";
pub const EXT_MATRIX: &str = "ANARI_CAVERAY_CAMERA_MATRIX";
pub const EXT_OFF_AXIS: &str = "ANARI_CAVERAY_CAMERA_OFF_AXIS";
pub const EXT_SHADING: &str = "ANARI_CAVERAY_RENDERER_SHADING";
pub const EXT_BACKGROUND: &str = "ANARI_KHR_RENDERER_BACKGROUND_COLOR";
pub const EXT_BACKGROUND_IMAGE: &str = "ANARI_KHR_RENDERER_BACKGROUND_IMAGE";
pub const EXT_COMPLETION: &str = "ANARI_KHR_FRAME_COMPLETION_CALLBACK";
pub const EXT_ACCUMULATION: &str = "ANARI_KHR_FRAME_ACCUMULATION";
pub const EXT_STEREO: &str = "ANARI_KHR_CAMERA_STEREO";
pub const EXT_ORTHOGRAPHIC: &str = "ANARI_KHR_CAMERA_ORTHOGRAPHIC";
/// Per-eye frames rendered in one re-projection pass (frame
/// `stereoPartner`, device `pairStereoFrames`).
pub const EXT_FRAME_PAIR: &str = "ANARI_CAVERAY_FRAME_STEREO_PAIR";
/// Frames that are ready by a deadline, showing the newest complete image
/// warped to their camera (frame `caveray.deadline`, `caveray.warp`;
/// properties `caveray.imageAge`, `caveray.warp`).
pub const EXT_FRAME_DEADLINE: &str = "ANARI_CAVERAY_FRAME_DEADLINE";
pub const EXT_ISOSURFACE: &str = "ANARI_KHR_GEOMETRY_ISOSURFACE";
pub const EXT_MATTE: &str = "ANARI_KHR_MATERIAL_MATTE";
/// Surfaces colored by curvature (material `curvature`).
pub const EXT_CURVATURE: &str = "ANARI_CAVERAY_MATERIAL_CURVATURE";
/// Multi-view autostereoscopic panels, each subpixel from its own eye
/// (camera `multiView`).
pub const EXT_MULTI_VIEW: &str = "ANARI_CAVERAY_CAMERA_MULTI_VIEW";

/// Every extension the device supports (device property `extension`).
pub const EXTENSIONS: &[&str] = &[
    "ANARI_KHR_CAMERA_PERSPECTIVE",
    EXT_STEREO,
    EXT_ORTHOGRAPHIC,
    "ANARI_KHR_SPATIAL_FIELD_STRUCTURED_REGULAR",
    "ANARI_KHR_VOLUME_TRANSFER_FUNCTION1D",
    EXT_COMPLETION,
    EXT_ACCUMULATION,
    EXT_BACKGROUND,
    EXT_BACKGROUND_IMAGE,
    "ANARI_KHR_LIGHT_DIRECTIONAL",
    "ANARI_KHR_INSTANCE_TRANSFORM",
    EXT_MATRIX_VSNRAY,
    EXT_MATRIX,
    EXT_OFF_AXIS,
    EXT_SHADING,
    EXT_FRAME_PAIR,
    EXT_FRAME_DEADLINE,
    EXT_ISOSURFACE,
    EXT_MATTE,
    EXT_CURVATURE,
    EXT_MULTI_VIEW,
];

/// Frame channels (`anariGetObjectInfo(FRAME, "channel")`).
pub const CHANNELS: &[&str] = &["channel.color", "channel.depth"];

/// Whether any parameter of any subtype reads arrays of `element`: an
/// array of another type can never be used, and its host hears so when
/// it makes one.
pub fn element_is_read(element: T) -> bool {
    SUBTYPES
        .iter()
        .flat_map(|s| s.params)
        .any(|p| p.elements.contains(&element))
}

/// The registry: adding a subtype is a module and a line here.
pub static SUBTYPES: &[&SubtypeInfo] = &[
    &device_object::INFO,
    &camera::perspective::INFO,
    &camera::orthographic::INFO,
    &camera::matrix::INFO,
    &camera::off_axis::INFO,
    &camera::multi_view::INFO,
    &spatial_field::structured_regular::INFO,
    &volume::transfer_function_1d::INFO,
    &light::directional::INFO,
    &geometry::isosurface::INFO,
    &material::matte::INFO,
    &material::curvature::INFO,
    &surface::INFO,
    &group::INFO,
    &instance::transform::INFO,
    &world::INFO,
    &renderer::INFO,
    &frame::INFO,
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
        .copied()
        .find(|s| s.kind == kind && (s.subtype.is_empty() || s.subtype == subtype))
}

pub fn param(kind: T, sub: &str, name: &str) -> Option<&'static ParamInfo> {
    subtype(kind, sub)?.params.iter().find(|p| p.name == name)
}

/// The table a new object of `kind` and `subtype` works by: its own, or
/// for renderers the default renderer's. Hosts name the renderer their
/// config holds (`scivis`, `dvr`, `raycast`, ...), and a volume device has
/// one way to render.
pub fn for_new_object(kind: T, sub: &str) -> Option<&'static SubtypeInfo> {
    subtype(kind, sub).or_else(|| (kind == T::RENDERER).then_some(&renderer::INFO))
}

/// Parameters hosts send that caveray has no use for: they are accepted
/// without a word (a warning on every `name` a host sets would bury the
/// ones that matter). Other unknown parameters are warned about once per
/// object and name.
pub const IGNORED_PARAMS: &[&str] = &[
    "name",
    "id",
    "visible",
    "ambientColor",
    "ambientRadiance",
    "ambientIntensity",
    "ambientOcclusionDistance",
    "ambientSamples",
    "denoise",
    "pixelSamples",
    "maxDepth",
    "lightFalloff",
    "apertureRadius",
    "focusDistance",
];

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
                match p.default {
                    DefaultValue::Floats(d) => assert!(
                        p.types.iter().any(|t| t.size() == 4 * d.len()),
                        "{}.{}: default {d:?} fits none of {:?}",
                        s.subtype,
                        p.name,
                        p.types
                    ),
                    DefaultValue::Text(_) => assert!(
                        p.types.contains(&T::STRING),
                        "{}.{}: a text default for a parameter that takes no STRING",
                        s.subtype,
                        p.name
                    ),
                    DefaultValue::Bool(_) => assert!(
                        p.types.contains(&T::BOOL),
                        "{}.{}: a BOOL default for a parameter that takes no BOOL",
                        s.subtype,
                        p.name
                    ),
                    DefaultValue::None => {}
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
        assert_eq!(
            subtypes(T::CAMERA),
            [
                "perspective",
                "orthographic",
                "matrix",
                "offAxis",
                "multiView"
            ]
        );
        assert_eq!(subtypes(T::GEOMETRY), ["isosurface"]);
        assert_eq!(subtypes(T::MATERIAL), ["matte", "curvature"]);
    }

    #[test]
    fn every_subtype_but_the_device_commits() {
        for s in SUBTYPES {
            assert_eq!(s.commit.is_none(), s.kind == T::DEVICE, "{}", s.subtype);
        }
    }
}
