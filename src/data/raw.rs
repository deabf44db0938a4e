use std::path::Path;

use glam::{UVec3, Vec3};

use super::DataError;
use crate::scene::{StructuredVolume, Voxels};

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
            VoxelType::U8 => Voxels::U8(bytes.to_vec()),
            VoxelType::U16 => Voxels::U16(
                bytes
                    .chunks_exact(2)
                    .map(|b| u16::from_le_bytes([b[0], b[1]]))
                    .collect(),
            ),
            VoxelType::F32 => Voxels::F32(
                bytes
                    .chunks_exact(4)
                    .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                    .collect(),
            ),
        }
    }
}

/// Loads a headerless little-endian raw volume, x fastest. A file whose
/// size does not match `dims` and `dtype` is rejected with both numbers.
pub fn load_raw(
    path: &Path,
    dims: UVec3,
    dtype: VoxelType,
    spacing: Vec3,
) -> Result<StructuredVolume, DataError> {
    let bytes = std::fs::read(path).map_err(|source| DataError::Io {
        file: path.display().to_string(),
        source,
    })?;
    decode_raw(path, &bytes, dims, dtype, spacing)
}

/// Decodes the bytes of a raw file read from `path` (named in errors).
pub(crate) fn decode_raw(
    path: &Path,
    bytes: &[u8],
    dims: UVec3,
    dtype: VoxelType,
    spacing: Vec3,
) -> Result<StructuredVolume, DataError> {
    let expected = u64::from(dims.x) * u64::from(dims.y) * u64::from(dims.z) * dtype.bytes();
    let actual = bytes.len() as u64;
    if actual != expected {
        return Err(DataError::FileSize {
            file: path.display().to_string(),
            dims: format!("{}x{}x{}", dims.x, dims.y, dims.z),
            dtype: dtype.name(),
            expected,
            actual,
        });
    }
    Ok(StructuredVolume::new(
        dims,
        dtype.decode(bytes),
        Vec3::ZERO,
        spacing,
    )?)
}
