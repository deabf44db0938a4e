//! Reading the host's arguments: C strings and typed parameter values.

use std::ffi::{c_char, c_void, CStr};

use crate::device::{DataType, Input};

/// A NUL-terminated argument as UTF-8; `what` names it in the error.
///
/// # Safety
/// `p` is NULL or points to a NUL-terminated string.
pub unsafe fn string(p: *const c_char, what: &str) -> Result<String, String> {
    if p.is_null() {
        return Err(format!("{what} is NULL"));
    }
    CStr::from_ptr(p)
        .to_str()
        .map(str::to_owned)
        .map_err(|_| format!("{what} is not valid UTF-8"))
}

/// A parameter value as `anariSetParameter` receives it: by pointer,
/// except STRING and VOID_POINTER which come by value.
///
/// # Safety
/// `mem` points to a value of type `code` (or is one, for the by-value types).
pub unsafe fn input(code: i32, mem: *const c_void) -> Result<Input, String> {
    let ty = DataType::from_code(code)
        .filter(|t| *t != DataType::UNKNOWN)
        .ok_or_else(|| format!("{code} is not an ANARI data type caveray knows"))?;
    match ty {
        DataType::STRING => Ok(Input::String(string(mem.cast(), "the string value")?)),
        DataType::VOID_POINTER => Ok(Input::Pointer(ty, mem as usize)),
        _ if mem.is_null() => Err(format!("the value pointer for a {ty} is NULL")),
        DataType::STATUS_CALLBACK | DataType::FRAME_COMPLETION_CALLBACK => {
            Ok(Input::Pointer(ty, mem.cast::<usize>().read_unaligned()))
        }
        t if t.is_object() => Ok(Input::Object(
            ty,
            mem.cast::<usize>().read_unaligned() as u64,
        )),
        _ => {
            let bytes = std::slice::from_raw_parts(mem.cast::<u8>(), ty.size()).to_vec();
            Ok(Input::Bytes(ty, bytes))
        }
    }
}
