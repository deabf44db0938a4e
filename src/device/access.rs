//! Typed access to what an object holds: the one place that looks inside
//! an object's `State`. Everything else asks an object for the value of
//! the type it wants (`ready::<CameraModel>`), its frame state or its
//! array, and gets it, or why it cannot have it.

use std::sync::Arc;

use super::array::Array;
use super::camera::CameraModel;
use super::frame::state::FrameState;
use super::geometry::IsoGeometry;
use super::group::GroupModel;
use super::instance::InstanceModel;
use super::light::DirectionalLight;
use super::material::Coloring;
use super::object::{Derived, ObjectCell, State, Unready};
use super::surface::SurfaceModel;
use super::volume::VolumeModel;
use super::world::WorldModel;
use crate::render::RenderSettings;
use crate::scene::StructuredVolume;

/// A value an object's commit derives, by the state that holds it.
pub trait Derivation: Clone {
    fn derived(state: &State) -> Option<&Derived<Self>>;
}

macro_rules! derivations {
    ($($variant:ident => $ty:ty),* $(,)?) => {$(
        impl Derivation for $ty {
            fn derived(state: &State) -> Option<&Derived<Self>> {
                match state {
                    State::$variant(d) => Some(d),
                    _ => None,
                }
            }
        }
    )*};
}

derivations!(
    Field => Arc<StructuredVolume>,
    Volume => VolumeModel,
    World => WorldModel,
    Group => GroupModel,
    Geometry => IsoGeometry,
    Material => Coloring,
    Surface => SurfaceModel,
    Instance => InstanceModel,
    Light => DirectionalLight,
    Camera => CameraModel,
    Renderer => RenderSettings,
);

impl ObjectCell {
    /// The value the object's commit derived, if it holds a `T`.
    pub fn derived<T: Derivation>(&self) -> Result<T, Unready> {
        let g = self.lock();
        match T::derived(&g.state) {
            None => Err(Unready::OtherKind),
            Some(Derived::Ready(v)) => Ok(v.clone()),
            Some(d) => Err(Unready::Unusable(
                d.ready(&self.describe()).err().unwrap_or_default(),
            )),
        }
    }

    /// `derived`, with `other_kind` saying what is wrong with an object of
    /// another kind.
    pub fn ready<T: Derivation>(
        &self,
        other_kind: impl FnOnce(&ObjectCell) -> String,
    ) -> Result<T, String> {
        self.derived().map_err(|e| match e {
            Unready::OtherKind => other_kind(self),
            Unready::Unusable(why) => why,
        })
    }

    /// The value if it is ready; `None` whatever stands in the way.
    pub fn usable<T: Derivation>(&self) -> Option<T> {
        self.derived().ok()
    }

    /// `f` on the frame's state, if the object is a frame.
    pub fn with_frame<R>(&self, f: impl FnOnce(&mut FrameState) -> R) -> Option<R> {
        match &mut self.lock().state {
            State::Frame(frame) => Some(f(frame)),
            _ => None,
        }
    }

    /// `f` on the array, if the object is one.
    pub fn with_array<R>(&self, f: impl FnOnce(&mut Array) -> R) -> Option<R> {
        match &mut self.lock().state {
            State::Array(a) => Some(f(a)),
            _ => None,
        }
    }

    /// Puts in what a commit derived; returns what it replaces, to be
    /// dropped outside the object's lock.
    pub fn replace_state(&self, state: State) -> State {
        std::mem::replace(&mut self.lock().state, state)
    }
}
