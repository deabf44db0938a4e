//! ANARI's data type codes and object kinds. The numbers are ANARI's; the C
//! layer checks at compile time that they match `include/anari/anari.h`.

use std::fmt;

pub use crate::engine::{Severity, StatusCode};

const PTR: usize = std::mem::size_of::<usize>();

macro_rules! data_types {
    ($($name:ident = $code:literal, $size:expr;)*) => {
        /// One of ANARI's `ANARIDataType` values that caveray knows.
        #[allow(non_camel_case_types)]
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum DataType {
            $($name = $code,)*
        }

        impl DataType {
            pub const ALL: &'static [DataType] = &[$(DataType::$name,)*];

            pub fn from_code(code: i32) -> Option<Self> {
                match code {
                    $($code => Some(DataType::$name),)*
                    _ => None,
                }
            }

            /// The C macro's name, e.g. `ANARI_FLOAT32_VEC3`.
            pub fn name(self) -> &'static str {
                match self {
                    $(DataType::$name => concat!("ANARI_", stringify!($name)),)*
                }
            }

            /// Bytes of one value as it sits in memory: pointed to by
            /// `anariSetParameter`'s `mem`, or one element of an array.
            pub fn size(self) -> usize {
                match self {
                    $(DataType::$name => $size,)*
                }
            }
        }
    };
}

data_types! {
    UNKNOWN = 0, 0;
    DATA_TYPE = 100, 4;
    STRING = 101, PTR;
    VOID_POINTER = 102, PTR;
    BOOL = 103, 1;
    STRING_LIST = 150, PTR;
    DATA_TYPE_LIST = 151, PTR;
    PARAMETER_LIST = 152, PTR;
    FUNCTION_POINTER = 200, PTR;
    MEMORY_DELETER = 201, PTR;
    STATUS_CALLBACK = 202, PTR;
    FRAME_COMPLETION_CALLBACK = 203, PTR;
    LIBRARY = 500, PTR;
    DEVICE = 501, PTR;
    OBJECT = 502, PTR;
    ARRAY = 503, PTR;
    ARRAY1D = 504, PTR;
    ARRAY2D = 505, PTR;
    ARRAY3D = 506, PTR;
    CAMERA = 507, PTR;
    FRAME = 508, PTR;
    GEOMETRY = 509, PTR;
    GROUP = 510, PTR;
    INSTANCE = 511, PTR;
    LIGHT = 512, PTR;
    MATERIAL = 513, PTR;
    RENDERER = 514, PTR;
    SURFACE = 515, PTR;
    SAMPLER = 516, PTR;
    SPATIAL_FIELD = 517, PTR;
    VOLUME = 518, PTR;
    WORLD = 519, PTR;
    INT8 = 1000, 1;
    INT8_VEC2 = 1001, 2;
    INT8_VEC3 = 1002, 3;
    INT8_VEC4 = 1003, 4;
    UINT8 = 1004, 1;
    UINT8_VEC2 = 1005, 2;
    UINT8_VEC3 = 1006, 3;
    UINT8_VEC4 = 1007, 4;
    INT16 = 1008, 2;
    INT16_VEC2 = 1009, 4;
    INT16_VEC3 = 1010, 6;
    INT16_VEC4 = 1011, 8;
    UINT16 = 1012, 2;
    UINT16_VEC2 = 1013, 4;
    UINT16_VEC3 = 1014, 6;
    UINT16_VEC4 = 1015, 8;
    INT32 = 1016, 4;
    INT32_VEC2 = 1017, 8;
    INT32_VEC3 = 1018, 12;
    INT32_VEC4 = 1019, 16;
    UINT32 = 1020, 4;
    UINT32_VEC2 = 1021, 8;
    UINT32_VEC3 = 1022, 12;
    UINT32_VEC4 = 1023, 16;
    INT64 = 1024, 8;
    INT64_VEC2 = 1025, 16;
    INT64_VEC3 = 1026, 24;
    INT64_VEC4 = 1027, 32;
    UINT64 = 1028, 8;
    UINT64_VEC2 = 1029, 16;
    UINT64_VEC3 = 1030, 24;
    UINT64_VEC4 = 1031, 32;
    FIXED8 = 1032, 1;
    FIXED8_VEC2 = 1033, 2;
    FIXED8_VEC3 = 1034, 3;
    FIXED8_VEC4 = 1035, 4;
    UFIXED8 = 1036, 1;
    UFIXED8_VEC2 = 1037, 2;
    UFIXED8_VEC3 = 1038, 3;
    UFIXED8_VEC4 = 1039, 4;
    FIXED16 = 1040, 2;
    FIXED16_VEC2 = 1041, 4;
    FIXED16_VEC3 = 1042, 6;
    FIXED16_VEC4 = 1043, 8;
    UFIXED16 = 1044, 2;
    UFIXED16_VEC2 = 1045, 4;
    UFIXED16_VEC3 = 1046, 6;
    UFIXED16_VEC4 = 1047, 8;
    FIXED32 = 1048, 4;
    FIXED32_VEC2 = 1049, 8;
    FIXED32_VEC3 = 1050, 12;
    FIXED32_VEC4 = 1051, 16;
    UFIXED32 = 1052, 4;
    UFIXED32_VEC2 = 1053, 8;
    UFIXED32_VEC3 = 1054, 12;
    UFIXED32_VEC4 = 1055, 16;
    FIXED64 = 1056, 8;
    FIXED64_VEC2 = 1057, 16;
    FIXED64_VEC3 = 1058, 24;
    FIXED64_VEC4 = 1059, 32;
    UFIXED64 = 1060, 8;
    UFIXED64_VEC2 = 1061, 16;
    UFIXED64_VEC3 = 1062, 24;
    UFIXED64_VEC4 = 1063, 32;
    FLOAT16 = 1064, 2;
    FLOAT16_VEC2 = 1065, 4;
    FLOAT16_VEC3 = 1066, 6;
    FLOAT16_VEC4 = 1067, 8;
    FLOAT32 = 1068, 4;
    FLOAT32_VEC2 = 1069, 8;
    FLOAT32_VEC3 = 1070, 12;
    FLOAT32_VEC4 = 1071, 16;
    FLOAT64 = 1072, 8;
    FLOAT64_VEC2 = 1073, 16;
    FLOAT64_VEC3 = 1074, 24;
    FLOAT64_VEC4 = 1075, 32;
    UFIXED8_R_SRGB = 2000, 1;
    UFIXED8_RA_SRGB = 2001, 2;
    UFIXED8_RGB_SRGB = 2002, 3;
    UFIXED8_RGBA_SRGB = 2003, 4;
    INT32_BOX1 = 2004, 8;
    INT32_BOX2 = 2005, 16;
    INT32_BOX3 = 2006, 24;
    INT32_BOX4 = 2007, 32;
    FLOAT32_BOX1 = 2008, 8;
    FLOAT32_BOX2 = 2009, 16;
    FLOAT32_BOX3 = 2010, 24;
    FLOAT32_BOX4 = 2011, 32;
    FLOAT32_MAT2 = 2012, 16;
    FLOAT32_MAT3 = 2013, 36;
    FLOAT32_MAT4 = 2014, 64;
    FLOAT32_MAT2x3 = 2015, 24;
    FLOAT32_MAT3x4 = 2016, 48;
    FLOAT32_QUAT_IJKW = 2017, 16;
    UINT64_REGION1 = 2104, 16;
    UINT64_REGION2 = 2105, 32;
    UINT64_REGION3 = 2106, 48;
    UINT64_REGION4 = 2107, 64;
    FLOAT64_BOX1 = 2208, 16;
    FLOAT64_BOX2 = 2209, 32;
    FLOAT64_BOX3 = 2210, 48;
    FLOAT64_BOX4 = 2211, 64;
}

impl DataType {
    /// Handles of ANARI objects (arrays, cameras, ..., the device itself).
    pub fn is_object(self) -> bool {
        (500..=519).contains(&(self as i32))
    }

    /// Whether a handle of kind `actual` may be passed where `self` is
    /// declared: the same kind, or a generic object or array type.
    pub fn accepts_object(self, actual: DataType) -> bool {
        self == actual
            || self == DataType::OBJECT
            || (self == DataType::ARRAY
                && matches!(
                    actual,
                    DataType::ARRAY1D | DataType::ARRAY2D | DataType::ARRAY3D
                ))
    }

    /// Whether an array declared to hold `self`s may hold an `actual`:
    /// as a parameter would, and an array of any dimension for any other
    /// (OpenCOVER's `amr` field sends its ARRAY3D blocks in an array
    /// declared to hold ARRAY1D).
    pub fn holds_object(self, actual: DataType) -> bool {
        let array = |t| {
            matches!(
                t,
                DataType::ARRAY | DataType::ARRAY1D | DataType::ARRAY2D | DataType::ARRAY3D
            )
        };
        self.accepts_object(actual) || (array(self) && array(actual))
    }
}

impl fmt::Display for DataType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The object kind ANARI names as `name` (in `anariNewObject` and in the
/// device property `subtypes.<name>`).
pub fn object_kind(name: &str) -> Option<DataType> {
    Some(match name {
        "camera" => DataType::CAMERA,
        "frame" => DataType::FRAME,
        "geometry" => DataType::GEOMETRY,
        "group" => DataType::GROUP,
        "instance" => DataType::INSTANCE,
        "light" => DataType::LIGHT,
        "material" => DataType::MATERIAL,
        "renderer" => DataType::RENDERER,
        "surface" => DataType::SURFACE,
        "sampler" => DataType::SAMPLER,
        "spatialField" => DataType::SPATIAL_FIELD,
        "volume" => DataType::VOLUME,
        "world" => DataType::WORLD,
        _ => return None,
    })
}

/// Human names of object kinds for messages ("camera", "spatial field").
pub fn kind_name(kind: DataType) -> &'static str {
    match kind {
        DataType::DEVICE => "device",
        DataType::ARRAY1D => "1D array",
        DataType::ARRAY2D => "2D array",
        DataType::ARRAY3D => "3D array",
        DataType::CAMERA => "camera",
        DataType::FRAME => "frame",
        DataType::GEOMETRY => "geometry",
        DataType::GROUP => "group",
        DataType::INSTANCE => "instance",
        DataType::LIGHT => "light",
        DataType::MATERIAL => "material",
        DataType::RENDERER => "renderer",
        DataType::SURFACE => "surface",
        DataType::SAMPLER => "sampler",
        DataType::SPATIAL_FIELD => "spatial field",
        DataType::VOLUME => "volume",
        DataType::WORLD => "world",
        _ => "object",
    }
}

/// One message for the host's status callback. `source` is the handle the
/// message is about (0 for none) with its kind.
#[derive(Clone, Debug, PartialEq)]
pub struct Status {
    pub severity: Severity,
    pub code: StatusCode,
    pub source: u64,
    pub source_kind: DataType,
    pub message: String,
}

/// Where a device's status messages go; called from any thread.
pub type Reporter = std::sync::Arc<dyn Fn(Status) + Send + Sync>;

/// `bytes` as native-endian values of `N` bytes each (trailing bytes ignored).
pub(crate) fn words<const N: usize>(bytes: &[u8]) -> impl Iterator<Item = [u8; N]> + '_ {
    bytes.chunks_exact(N).map(|c| {
        let mut word = [0u8; N];
        word.copy_from_slice(c);
        word
    })
}
