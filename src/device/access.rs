//! Typed access to what an object holds: the one place that looks inside
//! an object's `State`. Everything else asks an object for the value of
//! the type it wants (`ready::<CameraModel>`), its frame state or its
//! array, and gets it, or why it cannot have it.

use std::any::{Any, TypeId};

use super::object::{Derived, ObjectCell, State, Unready};

impl ObjectCell {
    /// The value the object's commit derived, if its commit derives a `T`.
    pub fn derived<T: Any + Clone>(&self) -> Result<T, Unready> {
        let g = self.lock();
        match &g.state {
            State::Model { of, derived, .. } if *of == TypeId::of::<T>() => match derived {
                Derived::Ready(v) => v.downcast_ref::<T>().cloned().ok_or(Unready::OtherKind),
                d => Err(Unready::Unusable(
                    d.ready(&self.describe()).err().unwrap_or_default(),
                )),
            },
            _ => Err(Unready::OtherKind),
        }
    }

    /// `derived`, with `other_kind` saying what is wrong with an object of
    /// another kind.
    pub fn ready<T: Any + Clone>(
        &self,
        other_kind: impl FnOnce(&ObjectCell) -> String,
    ) -> Result<T, String> {
        self.derived().map_err(|e| match e {
            Unready::OtherKind => other_kind(self),
            Unready::Unusable(why) => why,
        })
    }

    /// The value if it is ready; `None` whatever stands in the way.
    pub fn usable<T: Any + Clone>(&self) -> Option<T> {
        self.derived().ok()
    }

    /// `f` on what the object holds in place, if that is a `T` (an
    /// array's memory, a frame's state).
    pub fn with_held<T: Any, R>(&self, f: impl FnOnce(&mut T) -> R) -> Option<R> {
        match &mut self.lock().state {
            State::Held(held) => held.downcast_mut::<T>().map(f),
            _ => None,
        }
    }

    /// The state a failed commit leaves: this object's kind, unusable for
    /// `why`; `None` where a commit never replaces the state.
    pub fn invalid_state(&self, why: String) -> Option<State> {
        self.lock().state.invalid(why)
    }

    /// Puts in what a commit derived; returns what it replaces, to be
    /// dropped outside the object's lock.
    pub fn replace_state(&self, state: State) -> State {
        std::mem::replace(&mut self.lock().state, state)
    }
}
