//! Parameter values as the device stores them between `set` and `commit`.

use std::collections::BTreeMap;

use glam::{Mat4, Vec2, Vec3, Vec4};

use super::object::ObjectRef;
use super::types::DataType;

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

/// `bytes` as native-endian values of `N` bytes each (trailing bytes ignored).
pub(crate) fn words<const N: usize>(bytes: &[u8]) -> impl Iterator<Item = [u8; N]> + '_ {
    bytes.chunks_exact(N).map(|c| {
        let mut word = [0u8; N];
        word.copy_from_slice(c);
        word
    })
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
