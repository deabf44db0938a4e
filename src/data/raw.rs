use std::path::Path;

use glam::{UVec3, Vec3};

use super::stored::Stored;
use super::{files, DataError};
use crate::scene::{StructuredVolume, Voxels, MAX_VOXELS};

/// Voxel types of headerless little-endian raw files.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VoxelType {
    U8,
    U16,
    F32,
}

impl VoxelType {
    pub fn parse(name: &str) -> Result<Self, DataError> {
        match name {
            "u8" | "uint8" => Ok(VoxelType::U8),
            "u16" | "uint16" => Ok(VoxelType::U16),
            "f32" | "float32" | "float" => Ok(VoxelType::F32),
            other => Err(DataError::VoxelType(other.to_string())),
        }
    }

    pub fn bytes(self) -> u64 {
        match self {
            VoxelType::U8 => 1,
            VoxelType::U16 => 2,
            VoxelType::F32 => 4,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            VoxelType::U8 => "uint8",
            VoxelType::U16 => "uint16",
            VoxelType::F32 => "float32",
        }
    }

    fn decode(self, bytes: &[u8]) -> Voxels {
        match self {
            VoxelType::U8 => Voxels::U8(bytes.to_vec().into()),
            VoxelType::U16 => Voxels::U16(
                bytes
                    .chunks_exact(2)
                    .map(|b| u16::from_le_bytes([b[0], b[1]]))
                    .collect::<Vec<_>>()
                    .into(),
            ),
            VoxelType::F32 => Voxels::F32(
                bytes
                    .chunks_exact(4)
                    .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .collect::<Vec<_>>()
                    .into(),
            ),
        }
    }
}

/// Checks that `actual` bytes (of the file or buffer `name`) are what a
/// raw volume of `dims` and `dtype` needs.
fn check_size(name: &str, dims: UVec3, dtype: VoxelType, actual: u64) -> Result<(), DataError> {
    let expected = raw_size(dims, dtype)?;
    if actual == expected {
        return Ok(());
    }
    Err(DataError::FileSize {
        file: name.to_string(),
        dims: format!("{}x{}x{}", dims.x, dims.y, dims.z),
        dtype: dtype.name(),
        expected,
        actual,
    })
}

/// The byte size of a raw volume of `dims` and `dtype`, every product
/// checked, or why it cannot be loaded.
pub fn raw_size(dims: UVec3, dtype: VoxelType) -> Result<u64, DataError> {
    let voxels = u64::from(dims.x)
        .checked_mul(u64::from(dims.y))
        .and_then(|n| n.checked_mul(u64::from(dims.z)))
        .filter(|&n| n <= MAX_VOXELS)
        .ok_or_else(|| DataError::TooManyVoxels {
            dims: format!("{}x{}x{}", dims.x, dims.y, dims.z),
        })?;
    Ok(voxels * dtype.bytes())
}

/// Loads a headerless little-endian raw volume, x fastest, read straight
/// into a buffer of its type (no copy of the file's bytes beside it). A
/// file whose size does not match `dims` and `dtype` is rejected with
/// both numbers, before anything is read.
pub fn load_raw(
    path: &Path,
    dims: UVec3,
    dtype: VoxelType,
    spacing: Vec3,
) -> Result<StructuredVolume, DataError> {
    let name = path.display().to_string();
    let io = |source| DataError::Io {
        file: name.clone(),
        source,
    };
    let (file, actual) = files::open_regular(path).map_err(io)?;
    check_size(&name, dims, dtype, actual)?;
    let (stored, slope) = match dtype {
        VoxelType::U8 => (Stored::U8, 1.0 / 255.0),
        VoxelType::U16 => (Stored::U16, 1.0 / 65535.0),
        VoxelType::F32 => (Stored::F32, 1.0),
    };
    if let Some(mapped) = stored.mapped_grid(path, 0, dims, false, (slope, 0.0)) {
        return Ok(mapped?.with_geometry(Vec3::ZERO, spacing)?);
    }
    let mut reader = std::io::BufReader::new(file);
    let volume = stored.read_grid(dims, &[], &mut reader, false, (slope, 0.0), &name)?;
    Ok(volume.with_geometry(Vec3::ZERO, spacing)?)
}

/// The bytes of the raw file at `path`, which must be exactly the size
/// `dims` and `dtype` need.
pub(crate) fn read_raw(path: &Path, dims: UVec3, dtype: VoxelType) -> Result<Vec<u8>, DataError> {
    let io = |source| DataError::Io {
        file: path.display().to_string(),
        source,
    };
    let (file, actual) = files::open_regular(path).map_err(io)?;
    check_size(&path.display().to_string(), dims, dtype, actual)?;
    files::read_len(file, actual).map_err(io)
}

/// A raw volume from bytes in memory (`name` names them in errors), with
/// the checks a file gets.
pub fn parse_raw(
    bytes: &[u8],
    name: &str,
    dims: UVec3,
    dtype: VoxelType,
    spacing: Vec3,
) -> Result<StructuredVolume, DataError> {
    check_size(name, dims, dtype, bytes.len() as u64)?;
    decode_raw(bytes, dims, dtype, spacing)
}

/// Decodes the bytes of a raw file, already checked to be the right size.
pub(crate) fn decode_raw(
    bytes: &[u8],
    dims: UVec3,
    dtype: VoxelType,
    spacing: Vec3,
) -> Result<StructuredVolume, DataError> {
    Ok(StructuredVolume::new(
        dims,
        dtype.decode(bytes),
        Vec3::ZERO,
        spacing,
    )?)
}
