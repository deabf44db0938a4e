//! One ANARI object: its kind and subtype, the parameters set since the
//! last commit (values as the device stores them between `set` and
//! `commit`), the committed ones, and what was derived from them. The
//! derived value is kept as whatever type its subtype derives, so this
//! file knows no subtype; `access.rs` hands it out by type.

use std::any::{Any, TypeId};
use std::collections::{BTreeMap, BTreeSet};
use std::sync::{Arc, Mutex, MutexGuard};

use glam::{Mat4, Vec2, Vec3, Vec4};

use super::types::{kind_name, words, DataType};

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
    inner: Mutex<Object>,
}

impl ObjectCell {
    pub fn new(
        handle: u64,
        kind: DataType,
        subtype: &str,
        implemented: bool,
        state: State,
    ) -> Self {
        Self {
            handle,
            kind,
            subtype: subtype.to_owned(),
            implemented,
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
    /// What the object's commit derives (a field's volume, a camera's
    /// model, a renderer's settings), of the type `of`, or why there is
    /// none yet.
    Model {
        of: TypeId,
        derived: Derived<Box<dyn Any + Send>>,
        /// Objects (arrays) whose memory `derived` reads in place: held
        /// while it is the committed state, so that a host releasing one
        /// of them makes the copy the state still needs.
        holds: Vec<ObjectRef>,
    },
    /// What the device changes in place between commits: an array's
    /// memory, a frame's render slot and channels.
    Held(Box<dyn Any + Send>),
    /// Kinds and subtypes caveray does not implement.
    Inert,
}

impl State {
    /// Not committed yet; its commit will derive a `T`.
    pub fn uncommitted<T: Any>() -> Self {
        State::Model {
            of: TypeId::of::<T>(),
            derived: Derived::Uncommitted,
            holds: Vec::new(),
        }
    }

    /// A commit's result.
    pub fn ready<T: Any + Send>(value: T) -> Self {
        Self::ready_holding(value, Vec::new())
    }

    /// A commit's result that reads the memory of `holds` in place.
    pub fn ready_holding<T: Any + Send>(value: T, holds: Vec<ObjectRef>) -> Self {
        State::Model {
            of: TypeId::of::<T>(),
            derived: Derived::Ready(Box::new(value)),
            holds,
        }
    }

    pub fn held<T: Any + Send>(value: T) -> Self {
        State::Held(Box::new(value))
    }

    /// This state's kind, unusable for `why` (its commit failed); `None`
    /// for states a commit never replaces (arrays, frames, inert objects).
    pub fn invalid(&self, why: String) -> Option<Self> {
        match self {
            State::Model { of, .. } => Some(State::Model {
                of: *of,
                derived: Derived::Invalid(why),
                holds: Vec::new(),
            }),
            State::Held(_) | State::Inert => None,
        }
    }
}

/// A parameter value. Values passed by pointer are kept as their bytes,
/// so any type can be stored and read back as what it is.
#[derive(Clone)]
pub enum Value {
    Bytes {
        ty: DataType,
        bytes: Vec<u8>,
    },
    String(String),
    /// VOID_POINTER and the callback types: an address the device only
    /// hands back to the host.
    Pointer {
        ty: DataType,
        addr: usize,
    },
    Object {
        ty: DataType,
        object: ObjectRef,
    },
}

impl Value {
    /// The numbers of a FLOAT32-based value (scalar, vector, box, matrix).
    pub fn f32s(&self) -> Option<Vec<f32>> {
        match self {
            Value::Bytes { ty, bytes } if is_f32_based(*ty) => {
                Some(words(bytes).map(f32::from_ne_bytes).collect())
            }
            Value::Bytes { ty, bytes } if is_f64_based(*ty) => {
                Some(words(bytes).map(|w| f64::from_ne_bytes(w) as f32).collect())
            }
            _ => None,
        }
    }

    pub fn u32s(&self) -> Option<Vec<u32>> {
        match self {
            Value::Bytes {
                ty: DataType::UINT32 | DataType::UINT32_VEC2,
                bytes,
            } => Some(words(bytes).map(u32::from_ne_bytes).collect()),
            _ => None,
        }
    }

    /// A UINT64 or UINT32 value.
    pub fn u64(&self) -> Option<u64> {
        match self {
            Value::Bytes {
                ty: DataType::UINT64,
                bytes,
            } => words(bytes).next().map(u64::from_ne_bytes),
            Value::Bytes {
                ty: DataType::UINT32,
                bytes,
            } => words(bytes)
                .next()
                .map(|w| u64::from(u32::from_ne_bytes(w))),
            _ => None,
        }
    }

    /// An INT32 or DATA_TYPE value.
    pub fn i32(&self) -> Option<i32> {
        match self {
            Value::Bytes {
                ty: DataType::INT32 | DataType::DATA_TYPE,
                bytes,
            } => words(bytes).next().map(i32::from_ne_bytes),
            _ => None,
        }
    }

    /// A BOOL value (one byte, non-zero is true).
    pub fn bool(&self) -> Option<bool> {
        match self {
            Value::Bytes {
                ty: DataType::BOOL,
                bytes,
            } => bytes.first().map(|b| *b != 0),
            _ => None,
        }
    }

    pub fn string(&self) -> Option<&str> {
        match self {
            Value::String(s) => Some(s),
            _ => None,
        }
    }

    pub fn object(&self) -> Option<&ObjectRef> {
        match self {
            Value::Object { object, .. } => Some(object),
            _ => None,
        }
    }

    pub fn pointer(&self) -> Option<usize> {
        match self {
            Value::Pointer { addr, .. } => Some(*addr),
            _ => None,
        }
    }
}

fn is_f32_based(ty: DataType) -> bool {
    matches!(
        ty,
        DataType::FLOAT32
            | DataType::FLOAT32_VEC2
            | DataType::FLOAT32_VEC3
            | DataType::FLOAT32_VEC4
            | DataType::FLOAT32_BOX1
            | DataType::FLOAT32_BOX2
            | DataType::FLOAT32_BOX3
            | DataType::FLOAT32_MAT4
    )
}

fn is_f64_based(ty: DataType) -> bool {
    matches!(
        ty,
        DataType::FLOAT64
            | DataType::FLOAT64_VEC2
            | DataType::FLOAT64_VEC3
            | DataType::FLOAT64_VEC4
            | DataType::FLOAT64_BOX1
    )
}

/// An object's parameters by name.
#[derive(Clone, Default)]
pub struct Params(BTreeMap<String, Value>);

impl Params {
    pub fn get(&self, name: &str) -> Option<&Value> {
        self.0.get(name)
    }
    pub fn set(&mut self, name: &str, value: Value) {
        self.0.insert(name.to_owned(), value);
    }
    pub fn unset(&mut self, name: &str) -> Option<Value> {
        self.0.remove(name)
    }
    pub fn clear(&mut self) {
        self.0.clear();
    }
    fn floats<const N: usize>(&self, name: &str) -> Option<[f32; N]> {
        self.get(name)?.f32s()?.try_into().ok()
    }
    pub fn f32(&self, name: &str, default: f32) -> f32 {
        self.floats::<1>(name).map_or(default, |[x]| x)
    }
    pub fn vec2(&self, name: &str) -> Option<Vec2> {
        self.floats::<2>(name).map(Vec2::from)
    }
    pub fn vec3(&self, name: &str) -> Option<Vec3> {
        self.floats::<3>(name).map(Vec3::from)
    }
    pub fn vec4(&self, name: &str) -> Option<Vec4> {
        self.floats::<4>(name).map(Vec4::from)
    }
    pub fn mat4(&self, name: &str) -> Option<Mat4> {
        self.floats::<16>(name).map(|m| Mat4::from_cols_array(&m))
    }
    pub fn bool(&self, name: &str) -> Option<bool> {
        self.get(name).and_then(Value::bool)
    }

    pub fn string(&self, name: &str) -> Option<&str> {
        self.get(name)?.string()
    }
    pub fn object(&self, name: &str) -> Option<&ObjectRef> {
        self.get(name)?.object()
    }
}
