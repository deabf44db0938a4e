//! What caveray implements: every subtype's table (`table.rs`), each in
//! its own module beside its commit, listed once in `SUBTYPES`, with the
//! extensions and channels the device reports.

use std::sync::Arc;

use super::camera::CameraModel;
use super::frame::state::FrameState;
use super::frame::state::HIT_CHANNEL_NAMES;
use super::geometry::GeometryModel;
use super::group::GroupModel;
use super::instance::InstanceModel;
use super::light::DirectionalLight;
use super::material::MaterialModel;
use super::object::State;
use super::sampler::SamplerModel;
use super::surface::SurfaceModel;
use super::table::{
    ParamInfo, SubtypeInfo, EXT_ACCUMULATION, EXT_AMBIENT, EXT_BACKGROUND, EXT_BACKGROUND_IMAGE,
    EXT_COMPLETION, EXT_CONE, EXT_CURVATURE, EXT_CURVE, EXT_CYLINDER, EXT_FRAME_DEADLINE,
    EXT_FRAME_PAIR, EXT_HIT_CHANNELS, EXT_IMAGE1D, EXT_IMAGE2D, EXT_IMAGE3D, EXT_ISOSURFACE,
    EXT_MATRIX, EXT_MATRIX_VSNRAY, EXT_MATTE, EXT_MULTI_VIEW, EXT_OFF_AXIS, EXT_ORTHOGRAPHIC,
    EXT_PBR, EXT_PRIMITIVE_SAMPLER, EXT_QUAD, EXT_SHADING, EXT_SPHERE, EXT_STEREO,
    EXT_TRANSFORM_SAMPLER, EXT_TRIANGLE,
};
use super::types::DataType as T;
use super::volume::VolumeModel;
use super::world::WorldModel;
use super::{
    camera, device_object, frame, geometry, group, instance, light, material, renderer, sampler,
    spatial_field, surface, volume, world,
};
use crate::render::RenderSettings;
use crate::scene::SpatialField;

/// Every extension the device supports (device property `extension`).
pub const EXTENSIONS: &[&str] = &[
    "ANARI_KHR_CAMERA_PERSPECTIVE",
    EXT_STEREO,
    EXT_ORTHOGRAPHIC,
    "ANARI_KHR_SPATIAL_FIELD_STRUCTURED_REGULAR",
    "ANARI_KHR_SPATIAL_FIELD_UNSTRUCTURED",
    "ANARI_KHR_SPATIAL_FIELD_NANOVDB",
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
    EXT_HIT_CHANNELS[0],
    EXT_HIT_CHANNELS[1],
    EXT_HIT_CHANNELS[2],
    EXT_HIT_CHANNELS[3],
    EXT_HIT_CHANNELS[4],
    EXT_ISOSURFACE,
    EXT_TRIANGLE,
    EXT_QUAD,
    EXT_SPHERE,
    EXT_CYLINDER,
    EXT_CONE,
    EXT_CURVE,
    EXT_AMBIENT,
    EXT_MATTE,
    EXT_PBR,
    "ANARI_KHR_LIGHT_POINT",
    "ANARI_KHR_LIGHT_SPOT",
    EXT_IMAGE1D,
    EXT_IMAGE2D,
    EXT_IMAGE3D,
    EXT_PRIMITIVE_SAMPLER,
    EXT_TRANSFORM_SAMPLER,
    EXT_CURVATURE,
    EXT_MULTI_VIEW,
    #[cfg(feature = "mpi")]
    super::table::EXT_DEVICE_MPI,
];

/// Frame channels (`anariGetObjectInfo(FRAME, "channel")`).
pub const CHANNELS: &[&str] = &[
    "channel.color",
    "channel.depth",
    HIT_CHANNEL_NAMES[0],
    HIT_CHANNEL_NAMES[1],
    HIT_CHANNEL_NAMES[2],
    HIT_CHANNEL_NAMES[3],
    HIT_CHANNEL_NAMES[4],
];

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
    &spatial_field::unstructured::INFO,
    &spatial_field::amr::INFO,
    &spatial_field::nanovdb::INFO,
    &volume::transfer_function_1d::INFO,
    &light::directional::INFO,
    &light::point::POINT,
    &light::point::SPOT,
    &geometry::isosurface::INFO,
    &geometry::triangle::INFO,
    &geometry::quad::INFO,
    &geometry::sphere::INFO,
    &geometry::cylinder::INFO,
    &geometry::cone::INFO,
    &geometry::curve::INFO,
    &material::matte::INFO,
    &material::physically_based::INFO,
    &material::curvature::INFO,
    &sampler::image::INFO_1D,
    &sampler::image::INFO_2D,
    &sampler::image::INFO_3D,
    &sampler::primitive::INFO,
    &sampler::transform::INFO,
    &surface::INFO,
    &group::INFO,
    &instance::transform::INFO,
    &world::INFO,
    &renderer::INFO,
    &renderer::DIRECT_LIGHT,
    &frame::INFO,
];

/// The state of a new object of `kind`: what its commit will derive, not
/// yet derived.
pub fn initial_state(kind: T, implemented: bool) -> State {
    if !implemented {
        return State::Inert;
    }
    match kind {
        T::SPATIAL_FIELD => State::uncommitted::<Arc<SpatialField>>(),
        T::VOLUME => State::uncommitted::<VolumeModel>(),
        T::WORLD => State::uncommitted::<WorldModel>(),
        T::GROUP => State::uncommitted::<GroupModel>(),
        T::GEOMETRY => State::uncommitted::<GeometryModel>(),
        T::MATERIAL => State::uncommitted::<MaterialModel>(),
        T::SAMPLER => State::uncommitted::<SamplerModel>(),
        T::SURFACE => State::uncommitted::<SurfaceModel>(),
        T::INSTANCE => State::uncommitted::<InstanceModel>(),
        T::LIGHT => State::uncommitted::<DirectionalLight>(),
        T::CAMERA => State::uncommitted::<CameraModel>(),
        // A renderer works with its defaults before any commit.
        T::RENDERER => State::ready(RenderSettings::default()),
        T::FRAME => State::held(FrameState::default()),
        _ => State::Inert,
    }
}

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
    use crate::device::table::DefaultValue;

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
        assert_eq!(
            subtypes(T::GEOMETRY),
            [
                "isosurface",
                "triangle",
                "quad",
                "sphere",
                "cylinder",
                "cone",
                "curve"
            ]
        );
        assert_eq!(
            subtypes(T::MATERIAL),
            ["matte", "physicallyBased", "curvature"]
        );
        assert_eq!(
            subtypes(T::SAMPLER),
            ["image1D", "image2D", "image3D", "primitive", "transform"]
        );
    }

    #[test]
    fn every_subtype_but_the_device_commits() {
        for s in SUBTYPES {
            assert_eq!(s.commit.is_none(), s.kind == T::DEVICE, "{}", s.subtype);
        }
    }
}
