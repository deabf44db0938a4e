//! The C ABI: `include/anari/anari.h` and `caveray.h`, exported for hosts
//! that link `libanari_library_caveray.so` directly, and the entry point
//! and virtual tables the ANARI SDK loader uses, all generated from one
//! table (`entry_points.rs`). This layer only checks and converts the
//! host's arguments and forwards to `crate::device`.

mod convert;
pub mod entry_points;
mod gate;
mod handles;
mod helpers;
mod info;
mod ops;
mod status;
#[allow(
    non_camel_case_types,
    non_snake_case,
    non_upper_case_globals,
    dead_code,
    clippy::all
)]
#[rustfmt::skip]
pub mod sys;

use crate::device::{DataType, Severity, StatusCode};

// The device model's numbers must be the header's.
macro_rules! same_codes {
    ($($rust:expr => $c:ident),* $(,)?) => {
        $(const _: () = assert!($rust as i32 == sys::$c);)*
    };
}

same_codes! {
    DataType::UNKNOWN => ANARI_UNKNOWN,
    DataType::DATA_TYPE => ANARI_DATA_TYPE,
    DataType::STRING => ANARI_STRING,
    DataType::VOID_POINTER => ANARI_VOID_POINTER,
    DataType::BOOL => ANARI_BOOL,
    DataType::STRING_LIST => ANARI_STRING_LIST,
    DataType::DATA_TYPE_LIST => ANARI_DATA_TYPE_LIST,
    DataType::PARAMETER_LIST => ANARI_PARAMETER_LIST,
    DataType::STATUS_CALLBACK => ANARI_STATUS_CALLBACK,
    DataType::FRAME_COMPLETION_CALLBACK => ANARI_FRAME_COMPLETION_CALLBACK,
    DataType::LIBRARY => ANARI_LIBRARY,
    DataType::DEVICE => ANARI_DEVICE,
    DataType::OBJECT => ANARI_OBJECT,
    DataType::ARRAY => ANARI_ARRAY,
    DataType::ARRAY1D => ANARI_ARRAY1D,
    DataType::ARRAY2D => ANARI_ARRAY2D,
    DataType::ARRAY3D => ANARI_ARRAY3D,
    DataType::CAMERA => ANARI_CAMERA,
    DataType::FRAME => ANARI_FRAME,
    DataType::GEOMETRY => ANARI_GEOMETRY,
    DataType::GROUP => ANARI_GROUP,
    DataType::INSTANCE => ANARI_INSTANCE,
    DataType::LIGHT => ANARI_LIGHT,
    DataType::MATERIAL => ANARI_MATERIAL,
    DataType::RENDERER => ANARI_RENDERER,
    DataType::SURFACE => ANARI_SURFACE,
    DataType::SAMPLER => ANARI_SAMPLER,
    DataType::SPATIAL_FIELD => ANARI_SPATIAL_FIELD,
    DataType::VOLUME => ANARI_VOLUME,
    DataType::WORLD => ANARI_WORLD,
    DataType::UINT8 => ANARI_UINT8,
    DataType::UINT16 => ANARI_UINT16,
    DataType::INT32 => ANARI_INT32,
    DataType::UINT32 => ANARI_UINT32,
    DataType::UINT32_VEC2 => ANARI_UINT32_VEC2,
    DataType::UINT64 => ANARI_UINT64,
    DataType::UFIXED8 => ANARI_UFIXED8,
    DataType::UFIXED8_VEC4 => ANARI_UFIXED8_VEC4,
    DataType::FIXED16 => ANARI_FIXED16,
    DataType::UFIXED16 => ANARI_UFIXED16,
    DataType::FLOAT32 => ANARI_FLOAT32,
    DataType::FLOAT32_VEC2 => ANARI_FLOAT32_VEC2,
    DataType::FLOAT32_VEC3 => ANARI_FLOAT32_VEC3,
    DataType::FLOAT32_VEC4 => ANARI_FLOAT32_VEC4,
    DataType::FLOAT64 => ANARI_FLOAT64,
    DataType::FLOAT64_VEC4 => ANARI_FLOAT64_VEC4,
    DataType::UFIXED8_R_SRGB => ANARI_UFIXED8_R_SRGB,
    DataType::UFIXED8_RA_SRGB => ANARI_UFIXED8_RA_SRGB,
    DataType::UFIXED8_RGB_SRGB => ANARI_UFIXED8_RGB_SRGB,
    DataType::UFIXED8_RGBA_SRGB => ANARI_UFIXED8_RGBA_SRGB,
    DataType::FLOAT32_BOX1 => ANARI_FLOAT32_BOX1,
    DataType::FLOAT32_BOX2 => ANARI_FLOAT32_BOX2,
    DataType::FLOAT32_BOX3 => ANARI_FLOAT32_BOX3,
    DataType::FLOAT32_MAT4 => ANARI_FLOAT32_MAT4,
    DataType::FLOAT64_BOX1 => ANARI_FLOAT64_BOX1,
    Severity::FatalError => ANARI_SEVERITY_FATAL_ERROR,
    Severity::Error => ANARI_SEVERITY_ERROR,
    Severity::Warning => ANARI_SEVERITY_WARNING,
    Severity::PerformanceWarning => ANARI_SEVERITY_PERFORMANCE_WARNING,
    Severity::Info => ANARI_SEVERITY_INFO,
    Severity::Debug => ANARI_SEVERITY_DEBUG,
    StatusCode::NoError => ANARI_STATUS_NO_ERROR,
    StatusCode::UnknownError => ANARI_STATUS_UNKNOWN_ERROR,
    StatusCode::InvalidArgument => ANARI_STATUS_INVALID_ARGUMENT,
    StatusCode::InvalidOperation => ANARI_STATUS_INVALID_OPERATION,
    StatusCode::OutOfMemory => ANARI_STATUS_OUT_OF_MEMORY,
    StatusCode::UnsupportedDevice => ANARI_STATUS_UNSUPPORTED_DEVICE,
    StatusCode::VersionMismatch => ANARI_STATUS_VERSION_MISMATCH,
}

// The loader's object layout (see handles.rs) assumes 64-bit pointers.
const _: () = assert!(std::mem::size_of::<usize>() == 8);
