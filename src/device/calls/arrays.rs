//! Arrays: made over the host's memory or the device's, mapped and
//! unmapped, and the parameter arrays the device hands out to fill.

use super::Device;
use super::{Input, Subject};
use crate::device::array::{byte_len, Array, HostMemory};
use crate::device::object::{ObjectRef, State};
use crate::device::types::{kind_name, DataType, StatusCode};

impl Device {
    /// `anariNewArray{1,2,3}D`. `memory` is the host's (shared array) or
    /// `None` (device-owned, zeroed). On failure the memory is handed back
    /// with `forget` so the host's deleter is not called for an array that
    /// never existed.
    pub fn new_array(
        &mut self,
        kind: DataType,
        element_code: i32,
        dims: [u64; 3],
        memory: Option<Box<dyn HostMemory>>,
    ) -> Result<u64, Option<Box<dyn HostMemory>>> {
        let what = match kind {
            DataType::ARRAY1D => "anariNewArray1D",
            DataType::ARRAY2D => "anariNewArray2D",
            _ => "anariNewArray3D",
        };
        let element = match DataType::from_code(element_code) {
            Some(t)
                if t.size() > 0
                    && !matches!(
                        t,
                        DataType::STRING_LIST | DataType::DATA_TYPE_LIST | DataType::PARAMETER_LIST
                    ) =>
            {
                t
            }
            _ => {
                self.error(
                    StatusCode::InvalidArgument,
                    None,
                    format!(
                        "{what}: element type {element_code} is not a data type caveray can store"
                    ),
                );
                return Err(memory);
            }
        };
        if !crate::device::info::element_is_read(element) {
            self.warn(
                None,
                format!("{what}: no caveray parameter reads arrays of {element}; this one can never be used"),
            );
        }
        if byte_len(element, dims).is_none() {
            self.error(
                StatusCode::OutOfMemory,
                None,
                format!("{what}: {dims:?} elements of {element} do not fit in memory"),
            );
            return Err(memory);
        }
        let array = match memory {
            Some(m) => Array::shared(element, dims, m),
            None => match Array::owned(element, dims) {
                Some(a) => a,
                None => {
                    self.error(
                        StatusCode::OutOfMemory,
                        None,
                        format!("{what}: cannot allocate {dims:?} elements of {element}"),
                    );
                    return Err(None);
                }
            },
        };
        let cell = self.insert(kind, "", true, State::held(array));
        if element.is_object() {
            self.resolve_array_objects(&cell);
        }
        Ok(cell.handle)
    }

    /// Takes references to the objects an object array names.
    fn resolve_array_objects(&mut self, cell: &ObjectRef) {
        let Some((handles, element)) = cell.with_array(|a| (a.handles(), a.element())) else {
            return;
        };
        let mut objects = Vec::with_capacity(handles.len());
        for (i, h) in handles.into_iter().enumerate() {
            if h == 0 {
                objects.push(None);
                continue;
            }
            let what = format!("{} element {i}", cell.describe());
            let o = self.lookup(h, &what);
            if let Some(o) = &o {
                if !element.holds_object(o.kind) {
                    self.error(
                        StatusCode::InvalidArgument,
                        Some(cell),
                        format!("{what} is a {}, not {element}", kind_name(o.kind)),
                    );
                    objects.push(None);
                    continue;
                }
            }
            objects.push(o);
        }
        cell.with_array(|a| a.objects = objects);
    }

    /// Runs `f` on the array behind `handle`, or reports that it is none.
    fn with_array<R>(
        &mut self,
        handle: u64,
        call: &str,
        f: impl FnOnce(&mut Array) -> R,
    ) -> Option<(ObjectRef, R)> {
        let cell = self.lookup(handle, call)?;
        let result = cell.with_array(f);
        match result {
            Some(r) => Some((cell, r)),
            None => {
                self.error(
                    StatusCode::InvalidArgument,
                    Some(&cell),
                    format!("{call}: {} is not an array", cell.describe()),
                );
                None
            }
        }
    }

    pub fn map_array(&mut self, handle: u64) -> *mut u8 {
        let mapped = self.with_array(handle, "anariMapArray", |a| {
            (!std::mem::replace(&mut a.mapped, true)).then(|| a.ptr())
        });
        match mapped {
            Some((_, Some(ptr))) => ptr,
            Some((cell, None)) => {
                self.error(
                    StatusCode::InvalidOperation,
                    Some(&cell),
                    format!(
                        "anariMapArray: {} is already mapped; unmap it first",
                        cell.describe()
                    ),
                );
                std::ptr::null_mut()
            }
            None => std::ptr::null_mut(),
        }
    }

    pub fn unmap_array(&mut self, handle: u64) {
        self.changed();
        let Some((cell, (was_mapped, objects))) = self.with_array(handle, "anariUnmapArray", |a| {
            (
                std::mem::replace(&mut a.mapped, false),
                a.element().is_object(),
            )
        }) else {
            return;
        };
        if !was_mapped {
            self.error(
                StatusCode::InvalidOperation,
                Some(&cell),
                format!("anariUnmapArray: {} is not mapped", cell.describe()),
            );
        } else if objects {
            self.resolve_array_objects(&cell);
        }
    }

    /// `anariMapParameterArray*D`: a device-owned array of `kind` the host
    /// fills, set as parameter `name` when unmapped.
    pub fn map_param_array(
        &mut self,
        handle: u64,
        name: &str,
        kind: DataType,
        element_code: i32,
        dims: [u64; 3],
    ) -> (*mut u8, u64) {
        let Some(cell) = self.lookup(handle, &format!("anariMapParameterArray('{name}')")) else {
            return (std::ptr::null_mut(), 0);
        };
        let key = (handle, name.to_owned());
        if self.mapped_params.contains_key(&key) {
            self.error(
                StatusCode::InvalidOperation,
                Some(&cell),
                format!(
                    "anariMapParameterArray: '{name}' of {} is already mapped",
                    cell.describe()
                ),
            );
            return (std::ptr::null_mut(), 0);
        }
        let Ok(array) = self.new_array(kind, element_code, dims, None) else {
            return (std::ptr::null_mut(), 0);
        };
        let ptr = self.map_array(array);
        if let Some((array_cell, _)) = self.objects.get(&array) {
            self.mapped_params.insert(key, (kind, array_cell.clone()));
        }
        // The parameter map holds the array now, not the host.
        self.release(array);
        let element = DataType::from_code(element_code).map_or(0, |t| t.size() as u64);
        (ptr, element)
    }

    pub fn unmap_param_array(&mut self, handle: u64, name: &str) {
        let Some(cell) = self.lookup(handle, &format!("anariUnmapParameterArray('{name}')")) else {
            return;
        };
        let Some((kind, array)) = self.mapped_params.remove(&(handle, name.to_owned())) else {
            self.error(
                StatusCode::InvalidOperation,
                Some(&cell),
                format!(
                    "anariUnmapParameterArray: '{name}' of {} is not mapped",
                    cell.describe()
                ),
            );
            return;
        };
        // Back in the table for the unmap and the set, then the host-side
        // reference goes again.
        let h = array.handle;
        self.objects.insert(h, (array, 1));
        self.unmap_array(h);
        self.set_param(Subject::Object(handle), name, Input::Object(kind, h));
        self.release(h);
    }
}
