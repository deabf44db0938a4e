//! NanoVDB's own file format (.nvdb), as `nanovdb::io::writeGrids`
//! writes it: segments, each a 16-byte header (magic "NanoVDB0", or
//! "NanoVDB2" from NanoVDB 32.6 on; version; grid count; codec), one
//! 176-byte record per grid followed by its name, then the grids' buffers
//! one after another. Since 32.6 a file may also be raw grid buffers back
//! to back; both are read. Grids are taken by name; compressed segments
//! (ZIP, BLOSC) are refused, naming the codec.

use std::path::Path;

use crate::scene::{
    Filter, NanoVdbGrid, NANOVDB_MAGIC, NANOVDB_MAGIC_FILE, NANOVDB_MAGIC_GRID, NANOVDB_MAJOR,
};

use super::DataError;

/// Bytes of a segment's header and of a grid's record before its name.
const HEADER: usize = 16;
const RECORD: usize = 176;

/// One grid of a file: its name, type and where its buffer lies.
#[derive(Clone, Debug, PartialEq)]
pub struct NvdbEntry {
    pub name: String,
    /// NanoVDB's name of its value type (Float, Fp16, Vec3f, ...).
    pub grid_type: String,
    pub active_voxels: u64,
    at: usize,
    len: usize,
}

/// A .nvdb file's grids, read and one of them checked.
pub struct NvdbFile {
    pub entries: Vec<NvdbEntry>,
    /// The grid asked for (or the first).
    pub name: String,
    pub grid: NanoVdbGrid,
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}
fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}
fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

/// Whether `head` (a file's first bytes) begins a NanoVDB file or grid.
pub fn is_nvdb(head: &[u8]) -> bool {
    u64_at(head, 0)
        .is_some_and(|m| [NANOVDB_MAGIC, NANOVDB_MAGIC_GRID, NANOVDB_MAGIC_FILE].contains(&m))
}

/// The grids of the file `bytes` (named `file` in errors).
pub fn nvdb_entries(bytes: &[u8], file: &str) -> Result<Vec<NvdbEntry>, DataError> {
    let magic = u64_at(bytes, 0)
        .ok_or_else(|| super::bad(file, "NanoVDB", "the file is shorter than a header".into()))?;
    type Reader = fn(&[u8], &str) -> Result<Vec<NvdbEntry>, DataError>;
    let (first, second): (Reader, Reader) = match magic {
        NANOVDB_MAGIC_FILE => return segments_of(bytes, file),
        NANOVDB_MAGIC_GRID => return raw_grids(bytes, file),
        // NanoVDB 32.5 and before start files and grids alike: a grid
        // has its version at byte 16, a segment a grid's size there.
        _ if u32_at(bytes, 16).is_some_and(|v| v >> 21 == NANOVDB_MAJOR) => {
            (raw_grids, segments_of)
        }
        _ => (segments_of, raw_grids),
    };
    first(bytes, file).or_else(|e| second(bytes, file).map_err(|_| e))
}

/// The grids of a file of segments.
fn segments_of(bytes: &[u8], file: &str) -> Result<Vec<NvdbEntry>, DataError> {
    let bad = |why: String| super::bad(file, "NanoVDB", why);
    let mut entries = Vec::new();
    let mut at = 0usize;
    while at < bytes.len() {
        let magic = u64_at(bytes, at).unwrap_or(0);
        if magic != NANOVDB_MAGIC && magic != NANOVDB_MAGIC_FILE {
            return Err(bad(format!(
                "the segment at byte {at} does not start with NanoVDB's magic number"
            )));
        }
        let version = u32_at(bytes, at + 8).unwrap_or(0);
        if version >> 21 != NANOVDB_MAJOR {
            return Err(bad(format!(
                "the file is NanoVDB {}.{}.{}; caveray reads the version {NANOVDB_MAJOR} layout",
                version >> 21,
                (version >> 10) & 0x7ff,
                version & 0x3ff
            )));
        }
        let count = usize::from(u16_at(bytes, at + 12).unwrap_or(0));
        let codec = u16_at(bytes, at + 14).unwrap_or(0);
        if codec != 0 {
            let name = match codec {
                1 => "ZIP",
                2 => "BLOSC",
                _ => "an unknown codec",
            };
            return Err(bad(format!(
                "the segment at byte {at} is compressed with {name}; caveray reads uncompressed files (write them with Codec::NONE, e.g. nanovdb_convert without -z or -b)"
            )));
        }
        at += HEADER;
        let mut records = Vec::with_capacity(count.min(1024));
        for k in 0..count {
            let short = || bad(format!("grid record {k} runs past the end of the file"));
            let grid_size = u64_at(bytes, at).ok_or_else(short)?;
            let file_size = u64_at(bytes, at + 8).ok_or_else(short)?;
            let voxels = u64_at(bytes, at + 24).ok_or_else(short)?;
            let grid_type = u32_at(bytes, at + 32).ok_or_else(short)?;
            let name_size = u32_at(bytes, at + 136).ok_or_else(short)? as usize;
            let name_bytes = bytes
                .get(at + RECORD..(at + RECORD).saturating_add(name_size))
                .ok_or_else(short)?;
            let end = name_bytes.iter().position(|&c| c == 0).unwrap_or(name_size);
            if grid_size != file_size {
                return Err(bad(format!(
                    "grid record {k} says {file_size} bytes on disk for {grid_size} in memory; caveray reads uncompressed grids"
                )));
            }
            records.push((
                String::from_utf8_lossy(&name_bytes[..end]).into_owned(),
                grid_type,
                voxels,
                grid_size,
            ));
            at += RECORD + name_size;
        }
        for (k, (name, grid_type, voxels, size)) in records.into_iter().enumerate() {
            let len = usize::try_from(size).unwrap_or(usize::MAX);
            if at.checked_add(len).is_none_or(|end| end > bytes.len()) {
                return Err(bad(format!(
                    "grid {k} ('{name}', {size} bytes at byte {at}) runs past the end of the file ({} bytes)",
                    bytes.len()
                )));
            }
            entries.push(NvdbEntry {
                name,
                grid_type: type_name(grid_type),
                active_voxels: voxels,
                at,
                len,
            });
            at += len;
        }
    }
    Ok(entries)
}

/// Grid buffers written back to back, each sized by its own header.
fn raw_grids(bytes: &[u8], file: &str) -> Result<Vec<NvdbEntry>, DataError> {
    let mut entries = Vec::new();
    let mut at = 0usize;
    while at < bytes.len() {
        let magic = u64_at(bytes, at).unwrap_or(0);
        if magic != NANOVDB_MAGIC && magic != NANOVDB_MAGIC_GRID {
            return Err(super::bad(
                file,
                "NanoVDB",
                format!("the bytes at {at} are neither a NanoVDB file's segment nor a grid"),
            ));
        }
        let size = u64_at(bytes, at + 32).unwrap_or(0);
        let len = usize::try_from(size).unwrap_or(usize::MAX);
        if len < 672 || at.checked_add(len).is_none_or(|end| end > bytes.len()) {
            return Err(super::bad(
                file,
                "NanoVDB",
                format!(
                    "the grid at byte {at} says it is {size} bytes; the file holds {} after it",
                    bytes.len() - at
                ),
            ));
        }
        let name = &bytes[at + 40..at + 296];
        let end = name.iter().position(|&c| c == 0).unwrap_or(256);
        entries.push(NvdbEntry {
            name: String::from_utf8_lossy(&name[..end]).into_owned(),
            grid_type: type_name(u32_at(bytes, at + 636).unwrap_or(0)),
            active_voxels: u64_at(bytes, at + 672 + 56).unwrap_or(0),
            at,
            len,
        });
        at += len;
    }
    Ok(entries)
}

fn type_name(code: u32) -> String {
    crate::scene::VDB_TYPE_NAMES
        .get(code as usize)
        .map_or_else(|| format!("type {code}"), |n| n.to_string())
}

/// The grid named `grid` (else the first) of the .nvdb file at `path`.
pub fn load_nvdb(path: &Path, grid: Option<&str>) -> Result<NvdbFile, DataError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| DataError::Io {
        file: file.clone(),
        source,
    })?;
    parse_nvdb(&bytes, &file, grid)
}

/// `load_nvdb` of a file's bytes.
pub fn parse_nvdb(bytes: &[u8], file: &str, grid: Option<&str>) -> Result<NvdbFile, DataError> {
    let entries = nvdb_entries(bytes, file)?;
    let names = || {
        entries
            .iter()
            .map(|e| format!("'{}' ({})", e.name, e.grid_type))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let entry = match grid {
        Some(name) => entries.iter().find(|e| e.name == name).ok_or_else(|| {
            super::bad(
                file,
                "--grid",
                format!("the file has no grid named '{name}'; it holds {}", names()),
            )
        })?,
        None => entries
            .first()
            .ok_or_else(|| super::bad(file, "NanoVDB", "the file holds no grid".into()))?,
    };
    let blob = &bytes[entry.at..entry.at + entry.len];
    let grid = NanoVdbGrid::new(blob, Filter::Linear)
        .map_err(|e| super::bad(file, &format!("grid '{}'", entry.name), e.to_string()))?;
    Ok(NvdbFile {
        name: entry.name.clone(),
        entries: entries.clone(),
        grid,
    })
}
