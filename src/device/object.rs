//! One ANARI object: its kind and subtype, the parameters set since the
//! last commit, the committed ones, and what was derived from them.

use std::collections::BTreeSet;
use std::sync::{Arc, Mutex, MutexGuard};

use super::array::Array;
use super::camera::CameraModel;
use super::frame::state::FrameState;
use super::geometry::IsoGeometry;
use super::group::GroupModel;
use super::info::SubtypeInfo;
use super::instance::InstanceModel;
use super::light::DirectionalLight;
use super::material::Coloring;
use super::surface::SurfaceModel;
use super::types::{kind_name, DataType};
use super::value::Params;
use super::volume::VolumeModel;
use super::world::WorldModel;
use crate::render::RenderSettings;
use crate::scene::StructuredVolume;

/// Objects are shared: the host's handle and every parameter or array that
/// names the object keep it alive.
pub type ObjectRef = Arc<ObjectCell>;

pub struct ObjectCell {
    pub handle: u64,
    pub kind: DataType,
    pub subtype: String,
    /// Whether caveray implements this kind and subtype; other objects are
    /// created, accept parameters and render nothing.
    pub implemented: bool,
    /// The subtype's table, which checks its parameters and commits it.
    pub info: Option<&'static SubtypeInfo>,
    inner: Mutex<Object>,
}

impl ObjectCell {
    pub fn new(
        handle: u64,
        kind: DataType,
        subtype: &str,
        (implemented, info): (bool, Option<&'static SubtypeInfo>),
        state: State,
    ) -> Self {
        Self {
            handle,
            kind,
            subtype: subtype.to_owned(),
            implemented,
            info,
            inner: Mutex::new(Object {
                pending: Params::default(),
                committed: None,
                state,
                warned: BTreeSet::new(),
            }),
        }
    }

    /// The object's data. A panic elsewhere must not make the object
    /// unusable, so a poisoned lock is taken over.
    pub fn lock(&self) -> MutexGuard<'_, Object> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// "camera 'matrix' 0x100000003", for messages.
    pub fn describe(&self) -> String {
        if self.subtype.is_empty() {
            format!("{} {:#x}", kind_name(self.kind), self.handle)
        } else {
            format!(
                "{} '{}' {:#x}",
                kind_name(self.kind),
                self.subtype,
                self.handle
            )
        }
    }
}

pub struct Object {
    pub pending: Params,
    /// `None` until the first commit.
    pub committed: Option<Params>,
    pub state: State,
    /// Unknown parameter names already warned about.
    pub warned: BTreeSet<String>,
}

/// Derived from committed parameters: the value, or why there is none.
#[derive(Clone)]
pub enum Derived<T> {
    Uncommitted,
    Ready(T),
    Invalid(String),
}

impl<T> Derived<T> {
    /// The value, or a message saying why `what` cannot be used.
    pub fn ready(&self, what: &str) -> Result<&T, String> {
        match self {
            Derived::Ready(v) => Ok(v),
            Derived::Uncommitted => Err(format!("{what} has not been committed")),
            Derived::Invalid(e) => Err(format!("{what} is not usable: {e}")),
        }
    }
}

/// Why an object gives no value of the type asked for.
pub enum Unready {
    /// It is an object of another kind (or one caveray does not implement).
    OtherKind,
    /// Not committed, or its commit failed: the message says which.
    Unusable(String),
}

pub enum State {
    Array(Array),
    Field(Derived<Arc<StructuredVolume>>),
    Volume(Derived<VolumeModel>),
    World(Derived<WorldModel>),
    Group(Derived<GroupModel>),
    Geometry(Derived<IsoGeometry>),
    Material(Derived<Coloring>),
    Surface(Derived<SurfaceModel>),
    Instance(Derived<InstanceModel>),
    Light(Derived<DirectionalLight>),
    Camera(Derived<CameraModel>),
    Renderer(Derived<RenderSettings>),
    Frame(FrameState),
    Inert,
}

impl State {
    /// The empty state of a new object of `kind` (implemented or not).
    pub fn for_kind(kind: DataType, implemented: bool) -> Self {
        if !implemented {
            return State::Inert;
        }
        match kind {
            DataType::SPATIAL_FIELD => State::Field(Derived::Uncommitted),
            DataType::VOLUME => State::Volume(Derived::Uncommitted),
            DataType::WORLD => State::World(Derived::Uncommitted),
            DataType::GROUP => State::Group(Derived::Uncommitted),
            DataType::GEOMETRY => State::Geometry(Derived::Uncommitted),
            DataType::MATERIAL => State::Material(Derived::Uncommitted),
            DataType::SURFACE => State::Surface(Derived::Uncommitted),
            DataType::INSTANCE => State::Instance(Derived::Uncommitted),
            DataType::LIGHT => State::Light(Derived::Uncommitted),
            DataType::CAMERA => State::Camera(Derived::Uncommitted),
            // A renderer works with its defaults before any commit.
            DataType::RENDERER => State::Renderer(Derived::Ready(RenderSettings::default())),
            DataType::FRAME => State::Frame(FrameState::default()),
            _ => State::Inert,
        }
    }
}
