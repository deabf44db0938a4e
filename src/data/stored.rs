//! Voxel values as files store them: the scalar types the readers
//! write, either byte order, into a grid in index space, in their own
//! type where the renderers sample it (8 and 16-bit integers, 32-bit
//! floats) and read through the file's linear scaling; and zlib streams
//! inflated no further than a volume needs.

use std::io::Read;
use std::path::Path;
use std::sync::Arc;

use glam::{UVec3, Vec3};

use super::{files, DataError};
use crate::scene::{Buf, Mapping, Scaling, StructuredVolume, Voxels, MAX_VOXELS};

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

/// The voxels of a grid of `dims`, refused past `MAX_VOXELS` before
/// anything is allocated for them.
pub fn voxel_count(dims: UVec3) -> Result<u64, DataError> {
    let voxels = u64::from(dims.x)
        .saturating_mul(u64::from(dims.y))
        .saturating_mul(u64::from(dims.z));
    if voxels > MAX_VOXELS {
        return Err(DataError::TooManyVoxels {
            dims: format!("{}x{}x{}", dims.x, dims.y, dims.z),
        });
    }
    Ok(voxels)
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

    /// The grid of `dims` stored at byte `offset` of the file at `path`,
    /// mapped rather than read (storage.rs): where the numbers are ones
    /// the renderers sample as stored, in this machine's byte order,
    /// aligned for their type, and the file holds them all. None where
    /// they cannot be mapped; the caller then reads them (and reports a
    /// short file).
    pub fn mapped_grid(
        self,
        path: &Path,
        offset: u64,
        dims: UVec3,
        big_endian: bool,
        scaling: (f64, f64),
    ) -> Option<Result<StructuredVolume, DataError>> {
        let (file, len) = files::open_regular(path).ok()?;
        let map = Arc::new(Mapping::of(&file, usize::try_from(len).ok()?).ok()?);
        let at = usize::try_from(offset).ok()?;
        self.mapped_in(&map, at, dims, big_endian, scaling)
    }

    /// The grid of `dims` at byte `at` of the mapped file `map`, as
    /// `mapped_grid` takes it (None where the map does not hold it all).
    pub fn mapped_in(
        self,
        map: &Arc<Mapping>,
        at: usize,
        dims: UVec3,
        big_endian: bool,
        scaling: (f64, f64),
    ) -> Option<Result<StructuredVolume, DataError>> {
        if big_endian != cfg!(target_endian = "big") && self.bytes() > 1 {
            return None;
        }
        let n = voxel_count(dims).ok()? as usize;
        let map = Arc::clone(map);
        let voxels = match self {
            Stored::U8 => Voxels::U8(Buf::mapped(map, at, n)?),
            Stored::U16 => Voxels::U16(Buf::mapped(map, at, n)?),
            Stored::I16 => Voxels::I16(Buf::mapped(map, at, n)?),
            Stored::F32 => Voxels::F32(Buf::mapped(map, at, n)?),
            _ => return None,
        };
        let scaling = Scaling {
            slope: scaling.0 as f32,
            intercept: scaling.1 as f32,
        };
        Some(
            StructuredVolume::new(dims, voxels, Vec3::ZERO, Vec3::ONE)
                .and_then(|v| v.with_scaling(scaling))
                .map_err(DataError::from),
        )
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
    /// 0 and spacing 1 (a file's own map places it): 8 and 16-bit integers
    /// and 32-bit floats kept in their own type, read through `scaling`
    /// (slope, intercept); the other types as 32-bit floats, scaled.
    pub fn grid(
        self,
        dims: UVec3,
        data: &[u8],
        big_endian: bool,
        (slope, intercept): (f64, f64),
        file: &str,
    ) -> Result<StructuredVolume, DataError> {
        let io = |source| DataError::Io {
            file: file.to_string(),
            source,
        };
        let scaling = Scaling {
            slope: slope as f32,
            intercept: intercept as f32,
        };
        let (voxels, scaling) = match self {
            Stored::U8 => (
                Voxels::U8(own(data, |b: [u8; 1]| b[0]).map_err(io)?.into()),
                scaling,
            ),
            Stored::U16 => (
                Voxels::U16(
                    own(data, |b| ordered(b, big_endian, u16::from_le_bytes))
                        .map_err(io)?
                        .into(),
                ),
                scaling,
            ),
            Stored::I16 => (
                Voxels::I16(
                    own(data, |b| ordered(b, big_endian, i16::from_le_bytes))
                        .map_err(io)?
                        .into(),
                ),
                scaling,
            ),
            Stored::F32 => (
                Voxels::F32(
                    own(data, |b| ordered(b, big_endian, f32::from_le_bytes))
                        .map_err(io)?
                        .into(),
                ),
                scaling,
            ),
            _ => (
                Voxels::F32(
                    self.decode(data, big_endian, (slope, intercept))
                        .map_err(io)?
                        .into(),
                ),
                Scaling::IDENTITY,
            ),
        };
        Ok(StructuredVolume::new(dims, voxels, Vec3::ZERO, Vec3::ONE)?.with_scaling(scaling)?)
    }
}

impl Stored {
    /// `grid` of voxels read from `reader` (after `prefix`, their first
    /// bytes, read already) straight into a buffer of their own type, so
    /// that an uncompressed file's voxels are held once, not twice on the
    /// way in. For sizes the caller has checked against the file: the
    /// buffer is the size `dims` says.
    pub fn read_grid(
        self,
        dims: UVec3,
        prefix: &[u8],
        reader: &mut dyn Read,
        big_endian: bool,
        scaling: (f64, f64),
        file: &str,
    ) -> Result<StructuredVolume, DataError> {
        let io = |source| DataError::Io {
            file: file.to_string(),
            source,
        };
        let n = (u64::from(dims.x) * u64::from(dims.y) * u64::from(dims.z)) as usize;
        let swap = big_endian != cfg!(target_endian = "big");
        let voxels = match self {
            Stored::U8 => Voxels::U8(filled_from(n, prefix, reader).map_err(io)?.into()),
            Stored::U16 => {
                let mut v: Vec<u16> = filled_from(n, prefix, reader).map_err(io)?;
                if swap {
                    v.iter_mut().for_each(|x| *x = x.swap_bytes());
                }
                Voxels::U16(v.into())
            }
            Stored::I16 => {
                let mut v: Vec<i16> = filled_from(n, prefix, reader).map_err(io)?;
                if swap {
                    v.iter_mut().for_each(|x| *x = x.swap_bytes());
                }
                Voxels::I16(v.into())
            }
            Stored::F32 => {
                let mut v: Vec<f32> = filled_from(n, prefix, reader).map_err(io)?;
                if swap {
                    v.iter_mut()
                        .for_each(|x| *x = f32::from_bits(x.to_bits().swap_bytes()));
                }
                Voxels::F32(v.into())
            }
            // Converted to f32 anyway: read as bytes first.
            _ => {
                let bytes = n as u64 * self.bytes();
                let mut data = Vec::new();
                data.try_reserve_exact(bytes as usize)
                    .map_err(|_| io(out_of_memory(bytes)))?;
                data.extend_from_slice(&prefix[..prefix.len().min(bytes as usize)]);
                let rest = bytes - data.len() as u64;
                reader.take(rest).read_to_end(&mut data).map_err(io)?;
                if (data.len() as u64) < bytes {
                    return Err(io(std::io::ErrorKind::UnexpectedEof.into()));
                }
                return self.grid(dims, &data, big_endian, scaling, file);
            }
        };
        let scaling = Scaling {
            slope: scaling.0 as f32,
            intercept: scaling.1 as f32,
        };
        Ok(StructuredVolume::new(dims, voxels, Vec3::ZERO, Vec3::ONE)?.with_scaling(scaling)?)
    }
}

/// `n` numbers whose bytes are `prefix` and then what `reader` holds;
/// their buffer reserved fallibly.
fn filled_from<T: bytemuck::Pod>(
    n: usize,
    prefix: &[u8],
    reader: &mut dyn Read,
) -> std::io::Result<Vec<T>> {
    let mut values = Vec::new();
    values
        .try_reserve_exact(n)
        .map_err(|_| out_of_memory((n * std::mem::size_of::<T>()) as u64))?;
    values.resize(n, T::zeroed());
    let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut values);
    let first = prefix.len().min(bytes.len());
    bytes[..first].copy_from_slice(&prefix[..first]);
    reader.read_exact(&mut bytes[first..])?;
    Ok(values)
}

/// `data` as numbers of `N` bytes each, by `read`; their buffer reserved
/// fallibly.
fn own<T, const N: usize>(data: &[u8], read: impl Fn([u8; N]) -> T) -> std::io::Result<Vec<T>> {
    let mut values = Vec::new();
    values
        .try_reserve_exact(data.len() / N)
        .map_err(|_| out_of_memory((data.len() / N * std::mem::size_of::<T>()) as u64))?;
    values.extend(
        data.chunks_exact(N)
            .map(|c| read(c.try_into().unwrap_or([0; N]))),
    );
    Ok(values)
}

/// A little-endian reader `read` of bytes `b` stored `big_endian` or not.
fn ordered<T, const N: usize>(mut b: [u8; N], big_endian: bool, read: fn([u8; N]) -> T) -> T {
    if big_endian {
        b.reverse();
    }
    read(b)
}
