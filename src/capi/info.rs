//! The C views of `device::info`: NULL-terminated string lists, parameter
//! lists and descriptions, built once and kept for the life of the process
//! (the pointers handed out must stay valid).

use std::collections::HashMap;
use std::ffi::{c_char, c_void, CString};
use std::sync::OnceLock;

use super::sys;
use crate::device::info::{self, CHANNELS, EXTENSIONS, SUBTYPES};
use crate::device::table::DefaultValue;
use crate::device::DataType;

struct List {
    _strings: Vec<CString>,
    pointers: Vec<*const c_char>,
}

/// The tables are ours and hold no NUL; if one ever did, the string is
/// cut there rather than panicking on the host's thread.
fn c_string(s: &str) -> CString {
    CString::new(s.split('\0').next().unwrap_or_default()).unwrap_or_default()
}

impl List {
    fn new<'a>(items: impl IntoIterator<Item = &'a str>) -> Self {
        let strings: Vec<CString> = items.into_iter().map(c_string).collect();
        let mut pointers: Vec<*const c_char> = strings.iter().map(|s| s.as_ptr()).collect();
        pointers.push(std::ptr::null());
        Self {
            _strings: strings,
            pointers,
        }
    }
}

struct Subtype {
    description: CString,
    /// One entry per parameter and accepted type.
    parameters: Vec<sys::ANARIParameter>,
    _names: Vec<CString>,
    extensions: List,
    /// The subtype's first extension: each parameter's `sourceExtension`.
    source: Option<CString>,
    params: HashMap<&'static str, Param>,
}

/// One parameter's answers, kept where the pointers stay valid.
struct Param {
    description: CString,
    /// DATA_TYPE_LISTs, ended by ANARI_UNKNOWN.
    elements: Vec<i32>,
    data_types: Vec<i32>,
    names: List,
    range: Option<[f32; 2]>,
}

/// A DATA_TYPE_LIST: the codes, then ANARI_UNKNOWN.
fn type_list(types: &[DataType]) -> Vec<i32> {
    types
        .iter()
        .map(|t| *t as i32)
        .chain([DataType::UNKNOWN as i32])
        .collect()
}

struct Tables {
    device_subtypes: List,
    extensions: List,
    channels: List,
    subtypes: HashMap<i32, List>,
    by_subtype: HashMap<(i32, &'static str), Subtype>,
}

// SAFETY: the tables are immutable after construction; the raw pointers
// point into strings the tables own.
unsafe impl Send for Tables {}
unsafe impl Sync for Tables {}

static TABLES: OnceLock<Tables> = OnceLock::new();

/// One byte each, for the `required` info (ANARI's BOOL).
static TRUE: u8 = 1;
static FALSE: u8 = 0;

fn tables() -> &'static Tables {
    TABLES.get_or_init(|| {
        let mut subtypes = HashMap::new();
        for kind in DataType::ALL.iter().filter(|k| k.is_object()) {
            subtypes.insert(*kind as i32, List::new(info::subtypes(*kind)));
        }
        let by_subtype = SUBTYPES
            .iter()
            .map(|s| {
                let names: Vec<CString> = s.params.iter().map(|p| c_string(p.name)).collect();
                // A parameter that takes several types is listed once per type.
                let mut parameters: Vec<sys::ANARIParameter> = s
                    .params
                    .iter()
                    .zip(&names)
                    .flat_map(|(p, n)| {
                        p.types.iter().map(move |t| sys::ANARIParameter {
                            name: n.as_ptr(),
                            type_: *t as i32,
                        })
                    })
                    .collect();
                parameters.push(sys::ANARIParameter {
                    name: std::ptr::null(),
                    type_: DataType::UNKNOWN as i32,
                });
                let params = s
                    .params
                    .iter()
                    .map(|p| {
                        let param = Param {
                            description: c_string(p.description),
                            elements: type_list(p.elements),
                            data_types: type_list(p.data_types),
                            names: List::new(p.names.iter().copied()),
                            range: p.range.map(|(lo, hi)| [lo, hi]),
                        };
                        (p.name, param)
                    })
                    .collect();
                let sub = Subtype {
                    description: c_string(s.description),
                    parameters,
                    _names: names,
                    extensions: List::new(s.extensions.iter().copied()),
                    source: s.extensions.first().map(|e| c_string(e)),
                    params,
                };
                ((s.kind as i32, s.subtype), sub)
            })
            .collect();
        Tables {
            device_subtypes: List::new(["default"]),
            extensions: List::new(EXTENSIONS.iter().copied()),
            channels: List::new(CHANNELS.iter().copied()),
            subtypes,
            by_subtype,
        }
    })
}

pub fn device_subtypes() -> *const *const c_char {
    tables().device_subtypes.pointers.as_ptr()
}

pub fn extensions() -> *const *const c_char {
    tables().extensions.pointers.as_ptr()
}

/// Subtypes of an object kind; an empty list for kinds without any.
pub fn object_subtypes(kind: i32) -> *const *const c_char {
    tables()
        .subtypes
        .get(&kind)
        .map_or(std::ptr::null(), |l| l.pointers.as_ptr())
}

fn subtype(kind: i32, name: &str) -> Option<&'static Subtype> {
    let ty = DataType::from_code(kind)?;
    let entry = info::subtype(ty, name)?;
    tables().by_subtype.get(&(kind, entry.subtype))
}

/// `anariGetObjectInfo`: "description" (STRING), "parameter"
/// (PARAMETER_LIST), "extension" (STRING_LIST), and for frames "channel"
/// (STRING_LIST).
pub fn object_info(kind: i32, sub: &str, info_name: &str, info_type: i32) -> *const c_void {
    let Some(s) = subtype(kind, sub) else {
        return std::ptr::null();
    };
    match (info_name, DataType::from_code(info_type)) {
        ("description", Some(DataType::STRING)) => s.description.as_ptr().cast(),
        ("parameter", Some(DataType::PARAMETER_LIST)) => s.parameters.as_ptr().cast(),
        ("extension", Some(DataType::STRING_LIST)) => s.extensions.pointers.as_ptr().cast(),
        ("channel", Some(DataType::STRING_LIST)) if kind == DataType::FRAME as i32 => {
            tables().channels.pointers.as_ptr().cast()
        }
        _ => std::ptr::null(),
    }
}

/// `anariGetParameterInfo`: "description" (STRING), "required" (BOOL),
/// "default" (the parameter's own type, for FLOAT32-based parameters),
/// "elementType" (DATA_TYPE_LIST, for arrays), "value" (STRING_LIST for
/// enumerations, DATA_TYPE_LIST for DATA_TYPE parameters), "minimum" and
/// "maximum" (FLOAT32), "sourceExtension" (STRING).
pub fn parameter_info(
    kind: i32,
    sub: &str,
    param: &str,
    param_type: i32,
    info_name: &str,
    info_type: i32,
) -> *const c_void {
    let (Some(s), Some(ty)) = (subtype(kind, sub), DataType::from_code(kind)) else {
        return std::ptr::null();
    };
    let (Some(p), Some(c)) = (info::param(ty, sub, param), s.params.get(param)) else {
        return std::ptr::null();
    };
    if !p.types.iter().any(|t| *t as i32 == param_type) {
        return std::ptr::null();
    }
    let list = |l: &Vec<i32>| {
        if l.len() > 1 {
            l.as_ptr().cast()
        } else {
            std::ptr::null()
        }
    };
    match (info_name, DataType::from_code(info_type)) {
        ("description", Some(DataType::STRING)) => c.description.as_ptr().cast(),
        ("required", Some(DataType::BOOL)) => {
            let b: &'static u8 = if p.required { &TRUE } else { &FALSE };
            (b as *const u8).cast()
        }
        // Defaults are FLOAT32 components for the FLOAT32-based types, or
        // a BOOL's byte.
        ("default", Some(t)) if info_type == param_type && !t.is_object() => match p.default {
            DefaultValue::Floats(d) if d.len() * 4 == t.size() => d.as_ptr().cast(),
            DefaultValue::Bool(b) if t == DataType::BOOL => {
                let b: &'static u8 = if b { &TRUE } else { &FALSE };
                (b as *const u8).cast()
            }
            _ => std::ptr::null(),
        },
        ("elementType", Some(DataType::DATA_TYPE_LIST)) => list(&c.elements),
        ("value", Some(DataType::DATA_TYPE_LIST)) => list(&c.data_types),
        ("value", Some(DataType::STRING_LIST)) if !p.names.is_empty() => {
            c.names.pointers.as_ptr().cast()
        }
        ("minimum", Some(DataType::FLOAT32)) => c
            .range
            .as_ref()
            .map_or(std::ptr::null(), |r| (&r[0] as *const f32).cast()),
        // A quantity in the host's own units has no maximum to tell.
        ("maximum", Some(DataType::FLOAT32)) => c
            .range
            .as_ref()
            .filter(|r| r[1].is_finite())
            .map_or(std::ptr::null(), |r| (&r[1] as *const f32).cast()),
        ("sourceExtension", Some(DataType::STRING)) => s
            .source
            .as_ref()
            .map_or(std::ptr::null(), |e| e.as_ptr().cast()),
        _ => std::ptr::null(),
    }
}
