//! Committed parameters read through a subtype's table: a parameter the
//! host did not set takes the table's default, so each default is written
//! once, in the table that `anariGetParameterInfo` answers from too.

use glam::{Mat4, Vec3, Vec4};

use super::array::Array;
use super::info::{DefaultValue, ParamInfo};
use super::object::ObjectRef;
use super::types::DataType;
use super::value::{Params, Value};

pub struct Read<'a> {
    params: &'a Params,
    table: &'static [ParamInfo],
}

impl<'a> Read<'a> {
    pub fn new(params: &'a Params, table: &'static [ParamInfo]) -> Self {
        Self { params, table }
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
    pub fn objects(&self, name: &str, element: DataType) -> Result<Vec<ObjectRef>, String> {
        let objects = self.array_of(name, element, |a| {
            Ok(a.objects.iter().flatten().cloned().collect())
        })?;
        Ok(objects.unwrap_or_default())
    }
}
