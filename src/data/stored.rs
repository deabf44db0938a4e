//! Voxel values as files store them: the scalar types the readers
//! write, either byte order, read as 32-bit floats through a linear
//! scaling into a grid in index space; and zlib streams inflated no
//! further than a volume needs.

use std::io::Read;

use glam::{UVec3, Vec3};

use super::DataError;
use crate::scene::{StructuredVolume, Voxels};

/// The error of a buffer of `bytes` that cannot be had.
pub fn out_of_memory(bytes: u64) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::OutOfMemory,
        format!("cannot hold {bytes} bytes in memory"),
    )
}

/// The most zlib's deflate can expand its input (a stream of one
/// repeated byte comes near), so that a buffer for inflated data need
/// never be larger than its compressed size allows, however large the
/// header says the volume is.
pub const ZLIB_MAX_RATIO: usize = 1032;

/// Appends to `out` at most `want` bytes inflated from the zlib stream
/// `compressed`; its buffer reserved fallibly and never beyond what
/// `compressed` can inflate to, so that neither a header's claim nor a
/// zip bomb can make it larger than the volume needs.
pub fn inflate(compressed: &[u8], out: &mut Vec<u8>, want: usize) -> std::io::Result<()> {
    let reserve = compressed.len().saturating_mul(ZLIB_MAX_RATIO).min(want);
    out.try_reserve_exact(reserve)
        .map_err(|_| out_of_memory(reserve as u64))?;
    flate2::read::ZlibDecoder::new(compressed)
        .take(want as u64)
        .read_to_end(out)?;
    Ok(())
}

/// A stored scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stored {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    F32,
    F64,
}

impl Stored {
    /// As NumPy and the file formats' documentation name it.
    pub fn name(self) -> &'static str {
        match self {
            Stored::U8 => "uint8",
            Stored::I8 => "int8",
            Stored::U16 => "uint16",
            Stored::I16 => "int16",
            Stored::U32 => "uint32",
            Stored::I32 => "int32",
            Stored::F32 => "float32",
            Stored::F64 => "float64",
        }
    }

    pub fn bytes(self) -> u64 {
        match self {
            Stored::U8 | Stored::I8 => 1,
            Stored::U16 | Stored::I16 => 2,
            Stored::U32 | Stored::I32 | Stored::F32 => 4,
            Stored::F64 => 8,
        }
    }

    /// `data`'s values, `big_endian` or not, as `value * slope +
    /// intercept`; their buffer reserved fallibly.
    pub fn decode(
        self,
        data: &[u8],
        big_endian: bool,
        (slope, intercept): (f64, f64),
    ) -> std::io::Result<Vec<f32>> {
        let n = self.bytes() as usize;
        let mut values = Vec::new();
        values
            .try_reserve_exact(data.len() / n)
            .map_err(|_| out_of_memory((data.len() / n * 4) as u64))?;
        values.extend(data.chunks_exact(n).map(|c| {
            let mut b = [0u8; 8];
            b[..n].copy_from_slice(c);
            if big_endian {
                b[..n].reverse();
            }
            let v = match self {
                Stored::U8 => f64::from(b[0]),
                Stored::I8 => f64::from(b[0] as i8),
                Stored::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
                Stored::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
                Stored::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                Stored::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                Stored::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
                Stored::F64 => f64::from_le_bytes(b),
            };
            (v * slope + intercept) as f32
        }));
        Ok(values)
    }

    /// The grid of `dims` voxels that `data` (of file `file`) holds, origin
    /// 0 and spacing 1: a file's own map places it.
    pub fn grid(
        self,
        dims: UVec3,
        data: &[u8],
        big_endian: bool,
        scaling: (f64, f64),
        file: &str,
    ) -> Result<StructuredVolume, DataError> {
        let values = self
            .decode(data, big_endian, scaling)
            .map_err(|source| DataError::Io {
                file: file.to_string(),
                source,
            })?;
        Ok(StructuredVolume::new(
            dims,
            Voxels::F32(values),
            Vec3::ZERO,
            Vec3::ONE,
        )?)
    }
}
