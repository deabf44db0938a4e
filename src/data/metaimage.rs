//! ITK MetaImage volumes (`.mha` with its voxels attached, `.mhd` with
//! them in a data file beside it): the `Key = Value` header checked field
//! by field, raw or zlib-compressed voxels of the scalar types, and the
//! index-to-world map its offset, direction and spacing give, turned from
//! ITK's LPS into RAS+, so that a scan lands where the scanner put it.

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use glam::{DMat3, DMat4, DVec3, UVec3};
use serde_json::Value;

use super::files;
use super::stored::{inflate, out_of_memory, voxel_count, Stored};
use super::volume_file::VolumeFile;
use super::{bad, DataError, VolumeFormat};

use crate::scene::StructuredVolume;

/// The most a header may hold.
const HEADER_LIMIT: usize = 1 << 16;

/// Where the voxels lie in their file.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Skip {
    /// This many bytes after the header (attached) or from the start.
    Bytes(u64),
    /// At the very end of the file (`HeaderSize = -1`).
    AtEnd,
}

/// What a MetaImage header says about its volume, besides the voxels.
struct MetaHeader {
    dims: UVec3,
    stored: Stored,
    big_endian: bool,
    compressed: bool,
    compressed_size: Option<u64>,
    skip: Skip,
    spacing: DVec3,
    affine: DMat4,
    /// `LOCAL`, or the data file's name as written.
    data_file: String,
}

impl MetaHeader {
    fn local(&self) -> bool {
        self.data_file.eq_ignore_ascii_case("LOCAL")
    }

    fn bytes(&self) -> u64 {
        u64::from(self.dims.x)
            * u64::from(self.dims.y)
            * u64::from(self.dims.z)
            * self.stored.bytes()
    }
}

/// Loads the MetaImage volume at `path` (`.mha`, or a `.mhd` whose
/// `ElementDataFile` names the file of its voxels, beside it).
pub fn load_metaimage(path: &Path) -> Result<VolumeFile, DataError> {
    let file = path.display().to_string();
    let io = |file: &str| {
        let file = file.to_string();
        move |source: std::io::Error| DataError::Io { file, source }
    };
    let (mut handle, len) = files::open_regular(path).map_err(io(&file))?;
    let mut head = vec![0u8; HEADER_LIMIT.min(usize::try_from(len).unwrap_or(usize::MAX))];
    handle.read_exact(&mut head).map_err(io(&file))?;
    let (header, data_at) = parse_header(&head, &file)?;
    if header.local() {
        if let Some(volume) = mapped(&header, path, data_at as u64, len) {
            return volume_file(header, volume?);
        }
        let data = voxel_bytes(&header, &mut handle, data_at as u64, len, &file)?;
        let volume = grid(&header, &data, &file)?;
        return volume_file(header, volume);
    }
    let data_path = path
        .parent()
        .unwrap_or(Path::new(""))
        .join(&header.data_file);
    let data_name = data_path.display().to_string();
    let (mut handle, len) = files::open_regular(&data_path).map_err(io(&data_name))?;
    if let Some(volume) = mapped(&header, &data_path, 0, len) {
        return volume_file(header, volume?);
    }
    let data = voxel_bytes(&header, &mut handle, 0, len, &data_name)?;
    let volume = grid(&header, &data, &data_name)?;
    volume_file(header, volume)
}

/// The voxels of `header` mapped from the file at `path` (`len` bytes,
/// its data region from `start`), where they are uncompressed and can be
/// mapped (scene/storage.rs); None leaves the reading, and the reporting
/// of what is wrong, to `voxel_bytes`.
fn mapped(
    header: &MetaHeader,
    path: &Path,
    start: u64,
    len: u64,
) -> Option<Result<StructuredVolume, DataError>> {
    if header.compressed {
        return None;
    }
    let at = match header.skip {
        Skip::Bytes(skip) => start.checked_add(skip)?,
        Skip::AtEnd => len.checked_sub(header.bytes())?.max(start),
    };
    header
        .stored
        .mapped_grid(path, at, header.dims, header.big_endian, (1.0, 0.0))
}

/// A `.mha` with its voxels attached held in memory, as `load_metaimage`
/// reads one (for the fuzz target).
pub fn parse_metaimage(bytes: &[u8], name: &str) -> Result<VolumeFile, DataError> {
    let head = bytes.get(..HEADER_LIMIT).unwrap_or(bytes);
    let (header, data_at) = parse_header(head, name)?;
    if !header.local() {
        return Err(bad(
            name,
            "ElementDataFile",
            format!("'{}': the voxels are in another file", header.data_file),
        ));
    }
    let mut source = std::io::Cursor::new(bytes);
    let data = voxel_bytes(
        &header,
        &mut source,
        data_at as u64,
        bytes.len() as u64,
        name,
    )?;
    let volume = grid(&header, &data, name)?;
    volume_file(header, volume)
}

fn grid(header: &MetaHeader, data: &[u8], file: &str) -> Result<StructuredVolume, DataError> {
    header
        .stored
        .grid(header.dims, data, header.big_endian, (1.0, 0.0), file)
}

fn volume_file(header: MetaHeader, volume: StructuredVolume) -> Result<VolumeFile, DataError> {
    Ok(VolumeFile {
        format: VolumeFormat::MetaImage,
        volume,
        affine: header.affine,
        // ITK's physical space is LPS, turned into RAS+ here.
        anatomical: true,
        units: "mm",
        dtype: header.stored.name(),
        details: vec![
            ("compressed", Value::from(header.compressed)),
            ("data_file", Value::from(header.data_file)),
            ("spacing", Value::from(header.spacing.to_array().to_vec())),
        ],
    })
}

/// The voxels' bytes from `source`, a file of `len` bytes whose data
/// region begins at `start` (after an attached header, else 0), every
/// size checked against the file before a buffer is reserved.
fn voxel_bytes(
    header: &MetaHeader,
    source: &mut (impl Read + Seek),
    start: u64,
    len: u64,
    file: &str,
) -> Result<Vec<u8>, DataError> {
    let io = |source: std::io::Error| DataError::Io {
        file: file.to_string(),
        source,
    };
    let bytes = header.bytes();
    let dims = header.dims;
    let region = len.saturating_sub(start);
    // Compressed voxels without a size run to the end of the file.
    let stored = match (header.compressed, header.compressed_size, header.skip) {
        (false, _, _) => bytes,
        (true, Some(size), _) => size,
        (true, None, Skip::Bytes(skip)) => region.saturating_sub(skip),
        (true, None, Skip::AtEnd) => {
            return Err(bad(
                file,
                "HeaderSize",
                "-1 (data at the end) needs CompressedDataSize for compressed data".into(),
            ))
        }
    };
    let at = match header.skip {
        Skip::Bytes(skip) => start.saturating_add(skip),
        Skip::AtEnd => len.saturating_sub(stored).max(start),
    };
    if at.saturating_add(stored) > len {
        let skip = match header.skip {
            Skip::Bytes(skip) => skip.to_string(),
            Skip::AtEnd => "-1".into(),
        };
        let what = if header.compressed {
            format!("the compressed voxels need {stored} bytes")
        } else {
            format!(
                "{}x{}x{} {} needs {stored} bytes",
                dims.x,
                dims.y,
                dims.z,
                header.stored.name()
            )
        };
        return Err(bad(
            file,
            "voxels",
            format!(
                "{what} after a HeaderSize of {skip}; the data holds {}",
                len.saturating_sub(at),
            ),
        ));
    }
    source.seek(SeekFrom::Start(at)).map_err(io)?;
    let mut raw = Vec::new();
    let n = usize::try_from(stored).map_err(|_| io(out_of_memory(stored)))?;
    raw.try_reserve_exact(n)
        .map_err(|_| io(out_of_memory(stored)))?;
    source.take(stored).read_to_end(&mut raw).map_err(io)?;
    if (raw.len() as u64) < stored {
        return Err(bad(
            file,
            "voxels",
            format!("the file ended after {} of {stored} bytes", raw.len()),
        ));
    }
    if !header.compressed {
        return Ok(raw);
    }
    let want = usize::try_from(bytes).map_err(|_| io(out_of_memory(bytes)))?;
    let mut data = Vec::new();
    inflate(&raw, &mut data, want)
        .map_err(|e| bad(file, "CompressedData", format!("the zlib stream: {e}")))?;
    if data.len() < want {
        return Err(bad(
            file,
            "CompressedData",
            format!(
                "the zlib stream holds {} bytes; {}x{}x{} {} needs {bytes}",
                data.len(),
                dims.x,
                dims.y,
                dims.z,
                header.stored.name()
            ),
        ));
    }
    Ok(data)
}

/// The header at the start of `head` (the first bytes of `file`) and
/// where the attached voxels begin: after the `ElementDataFile` line,
/// which ends a MetaImage header.
fn parse_header(head: &[u8], file: &str) -> Result<(MetaHeader, usize), DataError> {
    let field = |name: &str, why: String| bad(file, name, why);
    let mut fields: Vec<(&str, &str)> = Vec::new();
    let mut at = 0;
    let data_at = loop {
        let (line, next) = match head[at..].iter().position(|&b| b == b'\n') {
            Some(i) => (&head[at..at + i], at + i + 1),
            // A detached header may end without a newline; a header cut
            // at the limit may not.
            None if head.len() < HEADER_LIMIT && at < head.len() => (&head[at..], head.len()),
            None => {
                return Err(field(
                    "ElementDataFile",
                    format!(
                        "missing: no header line names the data file (within {HEADER_LIMIT} bytes)"
                    ),
                ))
            }
        };
        let line = std::str::from_utf8(line)
            .map_err(|_| field("header", "it is not text (UTF-8)".into()))?
            .trim();
        at = next;
        if line.is_empty() {
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            let shown: String = line.chars().take(60).collect();
            return Err(field(
                "header",
                format!("'{shown}' is not a 'Key = Value' line"),
            ));
        };
        let (key, value) = (key.trim(), value.trim());
        fields.push((key, value));
        if key == "ElementDataFile" {
            break next;
        }
    };
    let get = |names: &[&str]| {
        names
            .iter()
            .find_map(|name| fields.iter().find(|(k, _)| k == name).copied())
    };
    let need = |name: &'static str| {
        get(&[name])
            .map(|(_, v)| v)
            .ok_or_else(|| field(name, "missing".into()))
    };
    if let Some((_, kind)) = get(&["ObjectType"]) {
        if kind != "Image" {
            return Err(field(
                "ObjectType",
                format!("'{kind}': caveray reads an Image"),
            ));
        }
    }
    let ndims: usize = need("NDims")?
        .parse()
        .map_err(|_| field("NDims", "not a whole number".into()))?;
    if !(1..=3).contains(&ndims) {
        return Err(field(
            "NDims",
            format!("{ndims}: caveray reads volumes of 1 to 3 axes"),
        ));
    }
    let sizes: Vec<u64> = need("DimSize")?
        .split_whitespace()
        .map(|s| s.parse::<u64>())
        .collect::<Result<_, _>>()
        .map_err(|_| field("DimSize", "not whole numbers".into()))?;
    if sizes.len() != ndims {
        return Err(field(
            "DimSize",
            format!("{} sizes for NDims {ndims}", sizes.len()),
        ));
    }
    let mut size = [1u32; 3];
    for (k, (&n, s)) in sizes.iter().zip(&mut size).enumerate() {
        *s = u32::try_from(n)
            .ok()
            .filter(|&n| n >= 1)
            .ok_or_else(|| field("DimSize", format!("{n} voxels along axis {k}")))?;
    }
    let dims = UVec3::from_array(size);
    voxel_count(dims)?;
    let stored = match need("ElementType")? {
        "MET_UCHAR" => Stored::U8,
        "MET_CHAR" => Stored::I8,
        "MET_USHORT" => Stored::U16,
        "MET_SHORT" => Stored::I16,
        "MET_UINT" => Stored::U32,
        "MET_INT" => Stored::I32,
        "MET_FLOAT" => Stored::F32,
        "MET_DOUBLE" => Stored::F64,
        other => {
            return Err(field(
                "ElementType",
                format!("'{other}' is not a scalar type caveray reads (MET_UCHAR, MET_CHAR, MET_USHORT, MET_SHORT, MET_UINT, MET_INT, MET_FLOAT, MET_DOUBLE)"),
            ))
        }
    };
    if let Some((key, channels)) = get(&["ElementNumberOfChannels"]) {
        if channels != "1" {
            return Err(field(
                key,
                format!("{channels}: caveray reads one value a voxel"),
            ));
        }
    }
    let flag = |names: &[&str]| -> Result<Option<bool>, DataError> {
        let Some((key, value)) = get(names) else {
            return Ok(None);
        };
        match value.to_ascii_lowercase().as_str() {
            "true" | "t" | "1" => Ok(Some(true)),
            "false" | "f" | "0" => Ok(Some(false)),
            _ => Err(field(key, format!("'{value}' is not True or False"))),
        }
    };
    if flag(&["BinaryData"])? == Some(false) {
        return Err(field(
            "BinaryData",
            "False (voxels as text): caveray reads binary voxels".into(),
        ));
    }
    let big_endian = flag(&["ElementByteOrderMSB", "BinaryDataByteOrderMSB"])?.unwrap_or(false);
    let compressed = flag(&["CompressedData"])?.unwrap_or(false);
    let compressed_size = match get(&["CompressedDataSize"]) {
        None => None,
        Some((key, s)) => Some(
            s.parse::<u64>()
                .map_err(|_| field(key, format!("'{s}' is not a number of bytes")))?,
        ),
    };
    let skip = match get(&["HeaderSize"]) {
        None => Skip::Bytes(0),
        Some((key, s)) => match s.parse::<i64>() {
            Ok(-1) => Skip::AtEnd,
            Ok(n) if n >= 0 => Skip::Bytes(n as u64),
            _ => {
                return Err(field(
                    key,
                    format!("'{s}': a number of bytes, or -1 for data at the end of the file"),
                ))
            }
        },
    };
    let numbers = |names: &[&str], n: usize| -> Result<Option<Vec<f64>>, DataError> {
        let Some((key, value)) = get(names) else {
            return Ok(None);
        };
        let parsed: Vec<f64> = value
            .split_whitespace()
            .map(|s| s.parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect::<Option<_>>()
            .ok_or_else(|| field(key, format!("'{value}' is not finite numbers")))?;
        if parsed.len() != n {
            return Err(field(
                key,
                format!("{} numbers; NDims {ndims} needs {n}", parsed.len()),
            ));
        }
        Ok(Some(parsed))
    };
    let mut spacing = DVec3::ONE;
    let spacing_keys = ["ElementSpacing", "ElementSize"];
    if let Some(given) = numbers(&spacing_keys, ndims)? {
        for (k, v) in given.into_iter().enumerate() {
            if v == 0.0 {
                let (key, _) = get(&spacing_keys).unwrap_or(("ElementSpacing", ""));
                return Err(field(key, format!("0 along axis {k}")));
            }
            spacing[k] = v;
        }
    }
    let mut origin = DVec3::ZERO;
    if let Some(given) = numbers(&["Offset", "Position", "Origin"], ndims)? {
        for (k, v) in given.into_iter().enumerate() {
            origin[k] = v;
        }
    }
    // ITK writes its direction matrix column by column: the first NDims
    // numbers are the direction of index axis i, and so on.
    let mut direction = DMat3::IDENTITY;
    let transform_keys = ["TransformMatrix", "Rotation", "Orientation"];
    if let Some(given) = numbers(&transform_keys, ndims * ndims)? {
        for (n, v) in given.into_iter().enumerate() {
            direction.col_mut(n / ndims)[n % ndims] = v;
        }
    }
    // LPS to RAS+: x and y turn about.
    let turn = DVec3::new(-1.0, -1.0, 1.0);
    let affine = DMat4::from_cols(
        (direction.x_axis * spacing.x * turn).extend(0.0),
        (direction.y_axis * spacing.y * turn).extend(0.0),
        (direction.z_axis * spacing.z * turn).extend(0.0),
        (origin * turn).extend(1.0),
    );
    let det = DMat3::from_mat4(affine).determinant();
    if !affine.is_finite() || det == 0.0 || !det.is_finite() {
        let (key, _) = get(&transform_keys).unwrap_or(("ElementSpacing", ""));
        return Err(field(
            key,
            "the spacing and directions span no volume".into(),
        ));
    }
    let data_file = need("ElementDataFile")?;
    if data_file.starts_with("LIST") || data_file.contains('%') {
        return Err(field(
            "ElementDataFile",
            format!("'{data_file}': caveray reads one data file, not a list or pattern of them"),
        ));
    }
    Ok((
        MetaHeader {
            dims,
            stored,
            big_endian,
            compressed,
            compressed_size,
            skip,
            spacing,
            affine,
            data_file: data_file.to_string(),
        },
        data_at,
    ))
}
