//! A subtype's parameter table and the reader of committed parameters
//! through it: a parameter the host did not set takes the table's
//! default, so each default is written once, in the table that
//! `anariSetParameter` checks against and `anariGetParameterInfo` answers
//! from too. Each subtype's module holds its `SubtypeInfo`; `info.rs`
//! lists them.

use glam::{Mat4, Vec3, Vec4};

use super::array::Array;
use super::object::{ObjectRef, Params, State, Value};
use super::types::DataType as T;
use super::types::DataType;

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
    /// For numbers: the smallest and largest sensible value; the largest
    /// is infinite for a quantity in the host's own units (a length, a
    /// light's strength), which no bound fits every scene.
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
    /// A finite number of at least `lo`, without an upper bound.
    pub const fn at_least(mut self, lo: f32) -> Self {
        self.range = Some((lo, f32::INFINITY));
        self
    }

    /// Whether `value` is an array this parameter can never take: one
    /// whose element type its table does not list, or an `ANARI_OBJECT`
    /// array holding an object of a kind it does not list. Such a value
    /// is refused at commit and not kept: the objects it holds may lead
    /// back to the object it is set on, and the loop would outlive every
    /// handle.
    pub fn never_takes(&self, value: &Value) -> bool {
        if self.elements.is_empty() {
            return false;
        }
        let Some(object) = value.object() else {
            return false;
        };
        object
            .with_array(|a| {
                !self.elements.contains(&a.element())
                    || (a.element() == T::OBJECT
                        && a.objects
                            .iter()
                            .flatten()
                            .any(|o| !self.elements.contains(&o.kind)))
            })
            .unwrap_or(false)
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

/// An optional ARRAY1D parameter of objects of one kind; `element` lists
/// that kind and `ANARI_OBJECT`, as hosts such as pynari type every object
/// list (`Read::objects` checks each object).
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

/// The `id` a surface, volume or instance reports in the frame's
/// objectId or instanceId channel.
pub const fn id_param(description: &'static str) -> ParamInfo {
    p("id", &[T::UINT32], false, DefaultValue::None, description)
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
/// The device as one rank of a data-parallel MPI job (`caveray.mpi`).
#[cfg(feature = "mpi")]
pub const EXT_DEVICE_MPI: &str = "ANARI_CAVERAY_DEVICE_MPI";
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
/// The frame's channels filled from each pixel's hit.
pub const EXT_HIT_CHANNELS: [&str; 5] = [
    "ANARI_KHR_FRAME_CHANNEL_PRIMITIVE_ID",
    "ANARI_KHR_FRAME_CHANNEL_OBJECT_ID",
    "ANARI_KHR_FRAME_CHANNEL_INSTANCE_ID",
    "ANARI_KHR_FRAME_CHANNEL_NORMAL",
    "ANARI_KHR_FRAME_CHANNEL_ALBEDO",
];
pub const EXT_TRIANGLE: &str = "ANARI_KHR_GEOMETRY_TRIANGLE";
pub const EXT_QUAD: &str = "ANARI_KHR_GEOMETRY_QUAD";
pub const EXT_SPHERE: &str = "ANARI_KHR_GEOMETRY_SPHERE";
pub const EXT_CYLINDER: &str = "ANARI_KHR_GEOMETRY_CYLINDER";
pub const EXT_PBR: &str = "ANARI_KHR_MATERIAL_PHYSICALLY_BASED";
pub const EXT_CONE: &str = "ANARI_KHR_GEOMETRY_CONE";
pub const EXT_CURVE: &str = "ANARI_KHR_GEOMETRY_CURVE";
pub const EXT_AMBIENT: &str = "ANARI_KHR_RENDERER_AMBIENT_LIGHT";
pub const EXT_MATTE: &str = "ANARI_KHR_MATERIAL_MATTE";
pub const EXT_IMAGE1D: &str = "ANARI_KHR_SAMPLER_IMAGE1D";
pub const EXT_IMAGE2D: &str = "ANARI_KHR_SAMPLER_IMAGE2D";
pub const EXT_IMAGE3D: &str = "ANARI_KHR_SAMPLER_IMAGE3D";
pub const EXT_PRIMITIVE_SAMPLER: &str = "ANARI_KHR_SAMPLER_PRIMITIVE";
pub const EXT_TRANSFORM_SAMPLER: &str = "ANARI_KHR_SAMPLER_TRANSFORM";
/// Surfaces colored by curvature (material `curvature`).
pub const EXT_CURVATURE: &str = "ANARI_CAVERAY_MATERIAL_CURVATURE";
/// Multi-view autostereoscopic panels, each subpixel from its own eye
/// (camera `multiView`).
pub const EXT_MULTI_VIEW: &str = "ANARI_CAVERAY_CAMERA_MULTI_VIEW";

pub struct Read<'a> {
    params: &'a Params,
    table: &'static [ParamInfo],
    /// What the commit costs the host beyond reading its data in place
    /// (a copy to change an array's type), said at PERFORMANCE severity.
    costs: std::cell::RefCell<Vec<String>>,
}

impl<'a> Read<'a> {
    pub fn new(params: &'a Params, table: &'static [ParamInfo]) -> Self {
        Self {
            params,
            table,
            costs: Default::default(),
        }
    }

    /// Notes a cost the host should hear of (PERFORMANCE severity).
    pub fn cost(&self, note: String) {
        self.costs.borrow_mut().push(note);
    }

    /// The costs noted, once.
    pub fn take_costs(&self) -> Vec<String> {
        std::mem::take(&mut self.costs.borrow_mut())
    }

    pub fn params(&self) -> &'a Params {
        self.params
    }

    fn info(&self, name: &str) -> Option<&'static ParamInfo> {
        self.table.iter().find(|p| p.name == name)
    }

    /// The value the host set, if any (no default).
    pub fn set(&self, name: &str) -> Option<&'a Value> {
        self.params.get(name)
    }

    /// `N` numbers: the host's value, else the table's default, else an
    /// error saying the parameter is required.
    pub fn floats<const N: usize>(&self, name: &str) -> Result<[f32; N], String> {
        if let Some(v) = self.set(name).and_then(|v| v.f32s()) {
            if let Ok(a) = v.try_into() {
                return Ok(a);
            }
        }
        match self.info(name).map(|p| (p, &p.default)) {
            Some((_, DefaultValue::Floats(d))) => (*d)
                .try_into()
                .map_err(|_| format!("the default of '{name}' has {} numbers, not {N}", d.len())),
            Some((p, _)) => Err(format!(
                "parameter '{name}' ({}) is required",
                p.types.first().map_or("?", |t| t.name())
            )),
            None => Err(format!("'{name}' is not in this subtype's parameter table")),
        }
    }

    pub fn f32(&self, name: &str) -> Result<f32, String> {
        self.floats::<1>(name).map(|[x]| x)
    }

    /// A FLOAT32 within the range its table states: hosts are told that
    /// range (`minimum`, `maximum`), so it is the one that is enforced.
    pub fn f32_in_range(&self, name: &str) -> Result<f32, String> {
        let x = self.f32(name)?;
        match self.info(name).and_then(|p| p.range) {
            Some((lo, hi)) if hi == f32::INFINITY && !(x.is_finite() && x >= lo) => Err(format!(
                "{name} must be a finite number of at least {lo}, got {x:?}"
            )),
            Some((lo, hi)) if !(lo..=hi).contains(&x) => {
                Err(format!("{name} must be from {lo} to {hi}, got {x:?}"))
            }
            _ => Ok(x),
        }
    }

    pub fn vec3(&self, name: &str) -> Result<Vec3, String> {
        self.floats::<3>(name).map(Vec3::from)
    }

    pub fn vec4(&self, name: &str) -> Result<Vec4, String> {
        self.floats::<4>(name).map(Vec4::from)
    }

    pub fn mat4(&self, name: &str) -> Result<Mat4, String> {
        self.floats::<16>(name).map(|m| Mat4::from_cols_array(&m))
    }

    /// The host's BOOL, else the table's default.
    pub fn bool(&self, name: &str) -> Result<bool, String> {
        if let Some(b) = self.set(name).and_then(Value::bool) {
            return Ok(b);
        }
        match self.info(name).map(|p| &p.default) {
            Some(DefaultValue::Bool(b)) => Ok(*b),
            _ => Err(format!(
                "'{name}' has no BOOL default in this subtype's table"
            )),
        }
    }

    /// The object's `id` ([`id_param`]), UINT32 max (ANARI's "none")
    /// where the host set none.
    pub fn id(&self) -> u32 {
        self.set("id")
            .and_then(|v| v.u32s())
            .and_then(|v| v.first().copied())
            .unwrap_or(u32::MAX)
    }

    /// The host's string, else the table's default.
    pub fn string(&self, name: &str) -> Option<&'a str> {
        match self.set(name).and_then(|v| v.string()) {
            Some(s) => Some(s),
            None => match self.info(name)?.default {
                DefaultValue::Text(t) => Some(t),
                _ => None,
            },
        }
    }

    pub fn object(&self, name: &str) -> Option<&'a ObjectRef> {
        self.params.object(name)
    }

    /// `read` applied to the array behind object parameter `name`, `None`
    /// if the parameter is unset; an error if it names something else.
    pub fn array<R>(
        &self,
        name: &str,
        read: impl FnOnce(&Array) -> Result<R, String>,
    ) -> Result<Option<R>, String> {
        let Some(object) = self.object(name) else {
            return Ok(None);
        };
        object
            .with_array(|a| read(a).map(Some))
            .unwrap_or_else(|| Err(format!("'{name}' is {}, not an array", object.describe())))
    }

    /// `read` applied to array parameter `name` if it holds `element`s.
    pub fn array_of<R>(
        &self,
        name: &str,
        element: DataType,
        read: impl FnOnce(&Array) -> Result<R, String>,
    ) -> Result<Option<R>, String> {
        self.array(name, |a| {
            if a.element() != element {
                return Err(format!(
                    "'{name}' array holds {}; expected {element}",
                    a.element()
                ));
            }
            read(a)
        })
    }

    /// The objects of array parameter `name`, which must hold `element`s;
    /// none if it is unset.
    /// An array of `ANARI_OBJECT` (as pynari builds every object list)
    /// is taken too when each object in it is of kind `element`.
    pub fn objects(&self, name: &str, element: DataType) -> Result<Vec<ObjectRef>, String> {
        let objects = self.array(name, |a| {
            if a.element() != element && a.element() != DataType::OBJECT {
                return Err(format!(
                    "'{name}' array holds {}; expected {element}",
                    a.element()
                ));
            }
            let objects: Vec<ObjectRef> = a.objects.iter().flatten().cloned().collect();
            match objects.iter().find(|o| o.kind != element) {
                Some(o) => Err(format!(
                    "'{name}' array holds {}; expected only {element}s",
                    o.describe()
                )),
                None => Ok(objects),
            }
        })?;
        Ok(objects.unwrap_or_default())
    }
}
