//! VTK image data: legacy `.vtk` files of `STRUCTURED_POINTS` and XML
//! `.vti` files of `ImageData`, their point scalars as text, binary,
//! base64 inline or appended, raw or zlib-compressed, and the
//! index-to-world map of their origin, spacing and (XML) direction. VTK
//! names no anatomical space and no unit, so the map is the file's own.
//! Every size is checked against the file before a buffer is reserved.

use std::borrow::Cow;
use std::path::Path;
use std::sync::Arc;

use base64::Engine;
use glam::{DMat3, DMat4, DVec3, UVec3, Vec3};
use serde_json::Value;

use super::files::{self, find};
use super::stored::{inflate, voxel_count, ZLIB_MAX_RATIO};
use super::stored::{out_of_memory, Stored};
use super::volume_file::VolumeFile;
use super::{bad, DataError, VolumeFormat};
use crate::scene::{Mapping, StructuredVolume, Voxels};

/// Loads the VTK image data at `path`, legacy or XML as its content says.
pub fn load_vtk(path: &Path) -> Result<VolumeFile, DataError> {
    let file = path.display().to_string();
    let io = |source| DataError::Io {
        file: file.clone(),
        source,
    };
    let (handle, len) = files::open_regular(path).map_err(io)?;
    // Mapped, raw appended voxels in this machine's byte order stay where
    // they are in the file (scene/storage.rs).
    if let Some(map) = usize::try_from(len)
        .ok()
        .and_then(|n| Mapping::of(&handle, n).ok())
    {
        let map = Arc::new(map);
        return parse(map.bytes(), &file, Some(&map));
    }
    let bytes = files::read_len(handle, len).map_err(io)?;
    parse_vtk(&bytes, &file)
}

/// A VTK image data file held in memory, as `load_vtk` reads one (for
/// the fuzz target).
pub fn parse_vtk(bytes: &[u8], name: &str) -> Result<VolumeFile, DataError> {
    parse(bytes, name, None)
}

/// `bytes`, the whole file, or a map of it (`map`) whose voxels may stay
/// mapped.
fn parse(bytes: &[u8], name: &str, map: Option<&Arc<Mapping>>) -> Result<VolumeFile, DataError> {
    if bytes.starts_with(b"# vtk DataFile") {
        return legacy(bytes, name);
    }
    let start = bytes
        .strip_prefix("\u{feff}".as_bytes())
        .unwrap_or(bytes)
        .trim_ascii_start();
    if start.starts_with(b"<?xml") || start.starts_with(b"<VTKFile") {
        return xml(bytes, name, map);
    }
    Err(bad(
        name,
        "format",
        "neither legacy VTK (# vtk DataFile) nor VTK XML (<VTKFile)".into(),
    ))
}

/// A grid's values as the file holds them.
enum Scalars<'a> {
    /// Binary, big-endian or not.
    Binary(Cow<'a, [u8]>, bool),
    /// Read from text.
    Text(Vec<f32>),
}

/// What either flavour found in its file.
struct Grid<'a> {
    dims: UVec3,
    stored: Stored,
    scalars: Scalars<'a>,
    affine: DMat4,
    details: Vec<(&'static str, Value)>,
}

impl Grid<'_> {
    /// The file's volume; its voxels mapped where they are the bytes of
    /// `map` as they stand.
    fn into_file(
        self,
        format: VolumeFormat,
        file: &str,
        map: Option<&Arc<Mapping>>,
    ) -> Result<VolumeFile, DataError> {
        let mapped = match (&self.scalars, map) {
            (Scalars::Binary(Cow::Borrowed(data), big_endian), Some(map)) => {
                let base = map.bytes().as_ptr() as usize;
                (data.as_ptr() as usize).checked_sub(base).and_then(|at| {
                    self.stored
                        .mapped_in(map, at, self.dims, *big_endian, (1.0, 0.0))
                })
            }
            _ => None,
        };
        let volume = match (mapped, self.scalars) {
            (Some(volume), _) => volume?,
            (None, Scalars::Binary(data, big_endian)) => {
                self.stored
                    .grid(self.dims, &data, big_endian, (1.0, 0.0), file)?
            }
            (None, Scalars::Text(values)) => {
                StructuredVolume::new(self.dims, Voxels::F32(values.into()), Vec3::ZERO, Vec3::ONE)?
            }
        };
        Ok(VolumeFile {
            format,
            volume,
            affine: self.affine,
            anatomical: false,
            units: "unknown",
            dtype: self.stored.name(),
            details: self.details,
        })
    }
}

/// A legacy file: a few header lines, then keyword lines each followed
/// by its data, read in order until the first scalars at points.
/// A legacy file's first three lines (the magic line, the title, which
/// is anything, and ASCII or BINARY): whether it is binary.
pub(super) fn legacy_header(reader: &mut Reader<'_>, name: &str) -> Result<bool, DataError> {
    reader.line();
    if reader.line().is_none() {
        return Err(bad(name, "header", "the file ends before its title".into()));
    }
    match text(reader.line().unwrap_or_default(), name)?
        .trim()
        .to_ascii_uppercase()
        .as_str()
    {
        "ASCII" => Ok(false),
        "BINARY" => Ok(true),
        other => Err(bad(
            name,
            "format",
            format!("'{other}' is neither ASCII nor BINARY"),
        )),
    }
}

fn legacy(bytes: &[u8], name: &str) -> Result<VolumeFile, DataError> {
    let field = |f: &str, why: String| bad(name, f, why);
    let mut reader = Reader { bytes, at: 0 };
    let binary = legacy_header(&mut reader, name)?;
    let mut dataset = false;
    let mut dims = None;
    let (mut spacing, mut origin) = (DVec3::ONE, DVec3::ZERO);
    // Whether at points (POINT_DATA) or cells, and how many tuples each
    // array there holds.
    let mut section: Option<(bool, u64)> = None;
    let mut cells = false;
    while let Some(line) = reader.line() {
        let line = text(line, name)?;
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some(first) = words.first() else {
            continue;
        };
        let key = first.to_ascii_uppercase();
        let args = &words[1..];
        match key.as_str() {
            "DATASET" => {
                let kind = args.first().copied().unwrap_or("");
                if !kind.eq_ignore_ascii_case("STRUCTURED_POINTS") {
                    return Err(field(
                        "DATASET",
                        format!("'{kind}': caveray reads STRUCTURED_POINTS (image data)"),
                    ));
                }
                dataset = true;
            }
            "DIMENSIONS" => {
                let n: Vec<u32> = args
                    .iter()
                    .map(|s| s.parse::<u32>().ok().filter(|&n| n >= 1))
                    .collect::<Option<_>>()
                    .filter(|n: &Vec<u32>| n.len() == 3)
                    .ok_or_else(|| {
                        field(
                            "DIMENSIONS",
                            format!("'{}' is not three sizes of 1 or more", args.join(" ")),
                        )
                    })?;
                dims = Some(UVec3::from_slice(&n));
            }
            "SPACING" | "ASPECT_RATIO" => {
                let s = three(args)
                    .filter(|s| s.iter().all(|&s| s != 0.0))
                    .ok_or_else(|| {
                        field(
                            &key,
                            format!("'{}' is not three finite, non-zero numbers", args.join(" ")),
                        )
                    })?;
                spacing = DVec3::from_array(s);
            }
            "ORIGIN" => {
                let o = three(args).ok_or_else(|| {
                    field(
                        "ORIGIN",
                        format!("'{}' is not three finite numbers", args.join(" ")),
                    )
                })?;
                origin = DVec3::from_array(o);
            }
            "POINT_DATA" | "CELL_DATA" => {
                let n = args
                    .first()
                    .and_then(|n| n.parse::<u64>().ok())
                    .ok_or_else(|| field(&key, "not a number of values".into()))?;
                cells |= key == "CELL_DATA";
                section = Some((key == "POINT_DATA", n));
            }
            // Field data (of the data set, or of points or cells) counts
            // its own tuples.
            "FIELD" => skip_field(&mut reader, args, binary).map_err(|why| field("FIELD", why))?,
            "SCALARS" | "VECTORS" | "NORMALS" | "TENSORS" | "TEXTURE_COORDINATES" => {
                if !dataset {
                    return Err(field("DATASET", "missing before the data".into()));
                }
                let Some((points, count)) = section else {
                    return Err(field(&key, "comes before POINT_DATA or CELL_DATA".into()));
                };
                if key == "SCALARS" && points {
                    let dims = dims.ok_or_else(|| field("DIMENSIONS", "missing".into()))?;
                    let (stored, scalars, array) =
                        legacy_scalars(&mut reader, args, binary, dims, count, name)?;
                    let affine = DMat4::from_cols(
                        DVec3::X.extend(0.0) * spacing.x,
                        DVec3::Y.extend(0.0) * spacing.y,
                        DVec3::Z.extend(0.0) * spacing.z,
                        origin.extend(1.0),
                    );
                    let encoding = if binary { "binary" } else { "ascii" };
                    let grid = Grid {
                        dims,
                        stored,
                        scalars,
                        affine,
                        details: vec![
                            ("flavour", Value::from("legacy")),
                            ("encoding", Value::from(encoding)),
                            ("array", Value::from(array)),
                            ("spacing", Value::from(spacing.to_array().to_vec())),
                            ("origin", Value::from(origin.to_array().to_vec())),
                        ],
                    };
                    // Legacy binary is big-endian: read, not mapped.
                    return grid.into_file(VolumeFormat::VtkLegacy, name, None);
                }
                skip_attribute(&mut reader, &key, args, binary, count)
                    .map_err(|why| field(&key, why))?;
            }
            other => {
                return Err(field(
                    other,
                    "not a part of structured points caveray reads or passes over".into(),
                ))
            }
        }
    }
    if !dataset {
        return Err(field("DATASET", "missing".into()));
    }
    if cells {
        return Err(field(
            "CELL_DATA",
            "the file has cell data only: caveray samples values at points (POINT_DATA SCALARS)"
                .into(),
        ));
    }
    Err(field(
        "POINT_DATA",
        "missing: no SCALARS array at points".into(),
    ))
}

/// The point scalars a `SCALARS name type [components]` line (its
/// `args`) begins: their type, values and name.
fn legacy_scalars<'a>(
    reader: &mut Reader<'a>,
    args: &[&str],
    binary: bool,
    dims: UVec3,
    count: u64,
    file: &str,
) -> Result<(Stored, Scalars<'a>, String), DataError> {
    let field = |f: &str, why: String| bad(file, f, why);
    let (Some(array), Some(kind)) = (args.first(), args.get(1)) else {
        return Err(field("SCALARS", "not 'SCALARS name type'".into()));
    };
    let stored = legacy_type(kind).map_err(|why| field("SCALARS", why))?;
    if let Some(components) = args.get(2) {
        if *components != "1" {
            return Err(field(
                "SCALARS",
                format!("{components} components: caveray reads one value a point"),
            ));
        }
    }
    let voxels = voxel_count(dims)?;
    if count != voxels {
        return Err(field(
            "POINT_DATA",
            format!(
                "{count} points; DIMENSIONS {} {} {} make {voxels}",
                dims.x, dims.y, dims.z
            ),
        ));
    }
    reader.lookup_table();
    let too_many = || out_of_memory(voxels.saturating_mul(stored.bytes())).to_string();
    let n = usize::try_from(voxels).map_err(|_| field("SCALARS", too_many()))?;
    let scalars = if binary {
        let bytes =
            usize::try_from(voxels * stored.bytes()).map_err(|_| field("SCALARS", too_many()))?;
        let data = reader.take(bytes).ok_or_else(|| {
            field(
                "SCALARS",
                format!(
                    "{n} {} values need {bytes} bytes; the file holds {}",
                    stored.name(),
                    reader.rest().len()
                ),
            )
        })?;
        Scalars::Binary(Cow::Borrowed(data), true)
    } else {
        Scalars::Text(reader.numbers(n).map_err(|why| field("SCALARS", why))?)
    };
    Ok((stored, scalars, array.to_string()))
}

/// Moves past the data of an attribute other than the point scalars,
/// `count` tuples of it, as its `key` line (`args`) describes them.
fn skip_attribute(
    reader: &mut Reader,
    key: &str,
    args: &[&str],
    binary: bool,
    count: u64,
) -> Result<(), String> {
    let type_at = |i: usize| {
        args.get(i)
            .ok_or_else(|| format!("no type in '{key} {}'", args.join(" ")))
            .and_then(|t| legacy_type(t))
    };
    let number = |i: usize| -> Result<u64, String> {
        args.get(i)
            .and_then(|n| n.parse().ok())
            .ok_or_else(|| format!("'{key} {}' lacks a number", args.join(" ")))
    };
    let (stored, per_tuple) = match key {
        "SCALARS" => {
            let per_tuple = if args.len() > 2 { number(2)? } else { 1 };
            reader.lookup_table();
            (type_at(1)?, per_tuple)
        }
        "VECTORS" | "NORMALS" => (type_at(1)?, 3),
        "TENSORS" => (type_at(1)?, 9),
        _ => (type_at(2)?, number(1)?),
    };
    reader.skip(count.saturating_mul(per_tuple), stored, binary)
}

/// Moves past the data of a `FIELD name n` line (`args`): n arrays, each
/// a line `name components tuples type` and its values.
fn skip_field(reader: &mut Reader, args: &[&str], binary: bool) -> Result<(), String> {
    let arrays: u64 = args
        .get(1)
        .and_then(|n| n.parse().ok())
        .ok_or_else(|| format!("'FIELD {}' is not 'FIELD name arrays'", args.join(" ")))?;
    for _ in 0..arrays {
        let line = reader
            .line()
            .and_then(|l| std::str::from_utf8(l).ok())
            .ok_or("the file ends inside a FIELD")?;
        let words: Vec<&str> = line.split_whitespace().collect();
        let number = |i: usize| words.get(i).and_then(|n| n.parse::<u64>().ok());
        let (Some(components), Some(tuples), Some(kind)) = (number(1), number(2), words.get(3))
        else {
            return Err(format!("'{line}' is not 'name components tuples type'"));
        };
        reader.skip(
            components.saturating_mul(tuples),
            legacy_type(kind)?,
            binary,
        )?;
    }
    Ok(())
}

/// A legacy file's type name.
fn legacy_type(name: &str) -> Result<Stored, String> {
    Ok(match name.to_ascii_lowercase().as_str() {
        "unsigned_char" => Stored::U8,
        "char" | "signed_char" => Stored::I8,
        "unsigned_short" => Stored::U16,
        "short" => Stored::I16,
        "unsigned_int" => Stored::U32,
        "int" => Stored::I32,
        "float" => Stored::F32,
        "double" => Stored::F64,
        _ => {
            return Err(format!(
                "'{name}' is not a type caveray reads (unsigned_char, char, unsigned_short, short, unsigned_int, int, float, double)"
            ))
        }
    })
}

/// Three finite numbers, as a legacy header line gives them.
fn three(args: &[&str]) -> Option<[f64; 3]> {
    let v: Vec<f64> = args
        .iter()
        .map(|s| s.parse::<f64>().ok().filter(|v| v.is_finite()))
        .collect::<Option<_>>()?;
    v.try_into().ok()
}

pub(super) fn text<'a>(line: &'a [u8], file: &str) -> Result<&'a str, DataError> {
    std::str::from_utf8(line)
        .map_err(|_| bad(file, "header", "a header line is not text (UTF-8)".into()))
}

/// A position in a file's bytes, read as lines, words or raw bytes.
pub(super) struct Reader<'a> {
    pub(super) bytes: &'a [u8],
    pub(super) at: usize,
}

impl<'a> Reader<'a> {
    fn rest(&self) -> &'a [u8] {
        self.bytes.get(self.at..).unwrap_or_default()
    }

    /// The next line, without its end; `None` at the end of the file.
    pub(super) fn line(&mut self) -> Option<&'a [u8]> {
        let rest = self.rest();
        if rest.is_empty() {
            return None;
        }
        let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        self.at += (end + 1).min(rest.len());
        let line = &rest[..end];
        Some(line.strip_suffix(b"\r").unwrap_or(line))
    }

    /// Moves past a `LOOKUP_TABLE` line, which may follow `SCALARS`.
    pub(super) fn lookup_table(&mut self) {
        let before = self.at;
        let table = self.line().and_then(|l| l.trim_ascii_start().get(..12));
        if !table.is_some_and(|k| k.eq_ignore_ascii_case(b"LOOKUP_TABLE")) {
            self.at = before;
        }
    }

    /// The next whitespace-separated word.
    pub(super) fn word(&mut self) -> Option<&'a [u8]> {
        let rest = self.rest();
        let start = rest.iter().position(|b| !b.is_ascii_whitespace())?;
        let len = rest[start..]
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(rest.len() - start);
        self.at += start + len;
        Some(&rest[start..start + len])
    }

    /// The next `n` bytes.
    pub(super) fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let taken = self.rest().get(..n)?;
        self.at += n;
        Some(taken)
    }

    /// The next `n` numbers as text; their buffer no larger than the
    /// text can fill (a number and a space a value), whatever `n` is.
    pub(super) fn numbers(&mut self, n: usize) -> Result<Vec<f32>, String> {
        let most = n.min(self.rest().len().div_ceil(2));
        let mut values = Vec::new();
        values
            .try_reserve_exact(most)
            .map_err(|_| out_of_memory(most as u64 * 4).to_string())?;
        for got in 0..n {
            let word = self
                .word()
                .ok_or_else(|| format!("{got} values; {n} are needed"))?;
            let value = std::str::from_utf8(word)
                .ok()
                .and_then(|w| w.parse::<f64>().ok())
                .ok_or_else(|| format!("'{}' is not a number", String::from_utf8_lossy(word)))?;
            values.push(value as f32);
        }
        Ok(values)
    }

    /// Moves past `n` values of `stored`, as text or binary.
    fn skip(&mut self, n: u64, stored: Stored, binary: bool) -> Result<(), String> {
        let short = || format!("the file ends within {n} {} values", stored.name());
        if binary {
            let bytes = usize::try_from(n.saturating_mul(stored.bytes())).map_err(|_| short())?;
            self.take(bytes).ok_or_else(short)?;
        } else {
            for _ in 0..n {
                self.word().ok_or_else(short)?;
            }
        }
        Ok(())
    }
}

/// How an XML file stores its binary arrays.
#[derive(Clone, Copy)]
pub(super) struct Layout {
    /// The bytes of a header word (`header_type`): 4 or 8.
    pub(super) word: usize,
    pub(super) big_endian: bool,
    pub(super) zlib: bool,
}

impl Layout {
    fn word(self, bytes: &[u8]) -> u64 {
        let fold = |a: u64, &b: &u8| a << 8 | u64::from(b);
        if self.big_endian {
            bytes.iter().fold(0, fold)
        } else {
            bytes.iter().rev().fold(0, fold)
        }
    }
}

/// An XML file: its header parsed as XML, its one piece's point array
/// read inline or from the appended data.
fn xml(bytes: &[u8], name: &str, map: Option<&Arc<Mapping>>) -> Result<VolumeFile, DataError> {
    let field = |f: &str, why: String| bad(name, f, why);
    // Raw appended data is not text, let alone XML: the document is what
    // comes before it, closed.
    let appended = find(bytes, b"<AppendedData");
    let head = appended.map_or(bytes, |at| &bytes[..at]);
    let head = std::str::from_utf8(head)
        .map_err(|_| field("xml", "the XML is not text (UTF-8)".into()))?;
    let closed;
    let head = if appended.is_some() {
        closed = format!("{head}</VTKFile>");
        closed.as_str()
    } else {
        head
    };
    let doc = roxmltree::Document::parse(head).map_err(|e| field("xml", e.to_string()))?;
    let root = doc.root_element();
    if root.tag_name().name() != "VTKFile" {
        return Err(field(
            "VTKFile",
            "missing: the root element is another".into(),
        ));
    }
    let kind = root.attribute("type").unwrap_or("");
    if kind != "ImageData" {
        return Err(field(
            "type",
            format!("'{kind}': caveray reads ImageData (.vti)"),
        ));
    }
    let layout = xml_layout(root, name)?;
    let big_endian = layout.big_endian;
    let Some(image) = child(root, "ImageData").into_iter().next() else {
        return Err(field("ImageData", "missing".into()));
    };
    let numbers = |node: roxmltree::Node<'_, '_>,
                   key: &str,
                   n: usize|
     -> Result<Option<Vec<f64>>, DataError> {
        let Some(value) = node.attribute(key) else {
            return Ok(None);
        };
        let v: Vec<f64> = value
            .split_whitespace()
            .map(|s| s.parse::<f64>().ok().filter(|v| v.is_finite()))
            .collect::<Option<_>>()
            .filter(|v: &Vec<f64>| v.len() == n)
            .ok_or_else(|| field(key, format!("'{value}' is not {n} finite numbers")))?;
        Ok(Some(v))
    };
    let extent =
        numbers(image, "WholeExtent", 6)?.ok_or_else(|| field("WholeExtent", "missing".into()))?;
    let mut size = [1u32; 3];
    for (k, s) in size.iter_mut().enumerate() {
        let n = extent[2 * k + 1] - extent[2 * k] + 1.0;
        if extent[2 * k].fract() != 0.0
            || !(1.0..=f64::from(u32::MAX)).contains(&n)
            || n.fract() != 0.0
        {
            return Err(field(
                "WholeExtent",
                format!(
                    "{} to {} along axis {k} is not an extent of 1 or more points",
                    extent[2 * k],
                    extent[2 * k + 1]
                ),
            ));
        }
        *s = n as u32;
    }
    let dims = UVec3::from_array(size);
    let voxels = voxel_count(dims)?;
    let origin = numbers(image, "Origin", 3)?.map_or(DVec3::ZERO, |o| DVec3::from_slice(&o));
    let spacing = numbers(image, "Spacing", 3)?.map_or(DVec3::ONE, |s| DVec3::from_slice(&s));
    if spacing.cmpeq(DVec3::ZERO).any() {
        return Err(field("Spacing", format!("{spacing}: a spacing is 0")));
    }
    // Direction is written row by row.
    let direction = numbers(image, "Direction", 9)?
        .map_or(DMat3::IDENTITY, |d| DMat3::from_cols_slice(&d).transpose());
    let m = direction * DMat3::from_diagonal(spacing);
    // Index 0 is the extent's first point, which need not be point 0.
    let first = DVec3::new(extent[0], extent[2], extent[4]);
    let affine = DMat4::from_cols(
        m.x_axis.extend(0.0),
        m.y_axis.extend(0.0),
        m.z_axis.extend(0.0),
        (origin + m * first).extend(1.0),
    );
    let det = m.determinant();
    if !affine.is_finite() || det == 0.0 || !det.is_finite() {
        return Err(field(
            "Direction",
            "the spacing and direction span no volume".into(),
        ));
    }
    let pieces = child(image, "Piece");
    let piece = match pieces.as_slice() {
        [piece] => *piece,
        [] => return Err(field("Piece", "missing".into())),
        more => {
            return Err(field(
                "Piece",
                format!(
                    "{} pieces: caveray reads image data in one piece",
                    more.len()
                ),
            ))
        }
    };
    if let Some(part) = numbers(piece, "Extent", 6)? {
        if part != extent {
            return Err(field(
                "Extent",
                format!("the piece's {part:?} is not the WholeExtent {extent:?}: caveray reads a piece that covers it"),
            ));
        }
    }
    let point_data = child(piece, "PointData").into_iter().next();
    let arrays = point_data
        .map(|p| child(p, "DataArray"))
        .unwrap_or_default();
    let named = point_data
        .and_then(|p| p.attribute("Scalars"))
        .and_then(|s| arrays.iter().find(|a| a.attribute("Name") == Some(s)));
    let Some(&array) = named.or(arrays.first()) else {
        let cells = child(piece, "CellData")
            .iter()
            .any(|c| !child(*c, "DataArray").is_empty());
        return Err(if cells {
            field(
                "CellData",
                "the file has cell data only: caveray samples values at points (PointData)".into(),
            )
        } else {
            field("PointData", "missing: no DataArray at points".into())
        });
    };
    let array_name = array.attribute("Name").unwrap_or("").to_string();
    let kind = array.attribute("type").unwrap_or("");
    let stored = match kind {
        "Int8" => Stored::I8,
        "UInt8" => Stored::U8,
        "Int16" => Stored::I16,
        "UInt16" => Stored::U16,
        "Int32" => Stored::I32,
        "UInt32" => Stored::U32,
        "Float32" => Stored::F32,
        "Float64" => Stored::F64,
        _ => {
            return Err(field(
                "type",
                format!("'{kind}': caveray reads Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32 and Float64 arrays"),
            ))
        }
    };
    if let Some(components) = array.attribute("NumberOfComponents") {
        if components != "1" {
            return Err(field(
                "NumberOfComponents",
                format!("{components}: caveray reads one value a point"),
            ));
        }
    }
    let too_many = || out_of_memory(voxels.saturating_mul(stored.bytes())).to_string();
    let n = usize::try_from(voxels).map_err(|_| field("DataArray", too_many()))?;
    let want =
        usize::try_from(voxels * stored.bytes()).map_err(|_| field("DataArray", too_many()))?;
    let in_array = |why: String| field("DataArray", format!("'{array_name}': {why}"));
    let format = array.attribute("format").unwrap_or("");
    let (encoding, scalars) = match format {
        "ascii" => {
            let text = array.text().unwrap_or("");
            let mut reader = Reader {
                bytes: text.as_bytes(),
                at: 0,
            };
            let values = reader.numbers(n).map_err(in_array)?;
            if reader.word().is_some() {
                return Err(in_array(format!("more than the {n} values the grid needs")));
            }
            ("ascii", Scalars::Text(values))
        }
        "binary" => {
            let text = array.text().unwrap_or("");
            let mut stream = Stream::base64(text.as_bytes());
            let data = array_bytes(&mut stream, layout, want).map_err(in_array)?;
            (
                "binary",
                Scalars::Binary(Cow::Owned(data.into_owned()), big_endian),
            )
        }
        "appended" => {
            let offset = array
                .attribute("offset")
                .and_then(|o| o.parse::<usize>().ok())
                .ok_or_else(|| field("offset", "missing or not a number of bytes".into()))?;
            let at = appended.ok_or_else(|| field("AppendedData", "missing".into()))?;
            let (raw, data) = appended_data(bytes, at).map_err(|why| field("AppendedData", why))?;
            let data = data.get(offset..).ok_or_else(|| {
                field(
                    "offset",
                    format!(
                        "{offset} lies beyond the {} bytes of appended data",
                        data.len()
                    ),
                )
            })?;
            let mut stream = if raw {
                Stream::Raw { bytes: data, at: 0 }
            } else {
                let end = find(data, b"</AppendedData").unwrap_or(data.len());
                Stream::base64(&data[..end])
            };
            let values = array_bytes(&mut stream, layout, want).map_err(in_array)?;
            // Appended base64 shows as `appended`, appended bytes as `raw`.
            (
                if raw { "raw" } else { "appended" },
                Scalars::Binary(values, big_endian),
            )
        }
        other => {
            return Err(field(
                "format",
                format!("'{other}' is not ascii, binary or appended"),
            ))
        }
    };
    Grid {
        dims,
        stored,
        scalars,
        affine,
        details: vec![
            ("flavour", Value::from("xml")),
            ("encoding", Value::from(encoding)),
            ("compressed", Value::from(layout.zlib)),
            ("array", Value::from(array_name)),
            ("spacing", Value::from(spacing.to_array().to_vec())),
            ("origin", Value::from(origin.to_array().to_vec())),
        ],
    }
    .into_file(VolumeFormat::VtkXml, name, map)
}

/// How an XML file's root says its binary arrays are stored.
pub(super) fn xml_layout(root: roxmltree::Node<'_, '_>, name: &str) -> Result<Layout, DataError> {
    let field = |f: &str, why: String| bad(name, f, why);
    let big_endian = match root.attribute("byte_order") {
        None | Some("LittleEndian") => false,
        Some("BigEndian") => true,
        Some(other) => {
            return Err(field(
                "byte_order",
                format!("'{other}' is neither LittleEndian nor BigEndian"),
            ))
        }
    };
    let word = match root.attribute("header_type") {
        None | Some("UInt32") => 4,
        Some("UInt64") => 8,
        Some(other) => {
            return Err(field(
                "header_type",
                format!("'{other}' is neither UInt32 nor UInt64"),
            ))
        }
    };
    let zlib = match root.attribute("compressor") {
        None | Some("") => false,
        Some("vtkZLibDataCompressor") => true,
        Some(other) => {
            return Err(field(
                "compressor",
                format!(
                    "'{other}': caveray reads zlib (vtkZLibDataCompressor) or uncompressed data"
                ),
            ))
        }
    };
    Ok(Layout {
        word,
        big_endian,
        zlib,
    })
}

/// Whether the `<AppendedData ...>` tag at `at` of `bytes` says its data
/// is raw (else base64), and the data: what follows the `_` after it.
pub(super) fn appended_data(bytes: &[u8], at: usize) -> Result<(bool, &[u8]), String> {
    let rest = bytes.get(at..).unwrap_or_default();
    let close = rest
        .iter()
        .position(|&b| b == b'>')
        .ok_or("its tag is not closed")?;
    let tag = String::from_utf8_lossy(&rest[..close]);
    let encoding = tag
        .split_once("encoding=")
        .and_then(|(_, v)| v.get(1..))
        .and_then(|v| v.split(['"', '\'']).next())
        .unwrap_or("");
    let raw = match encoding {
        "raw" => true,
        "base64" => false,
        other => return Err(format!("encoding '{other}' is neither raw nor base64")),
    };
    let after = rest[close + 1..].trim_ascii_start();
    let data = after
        .strip_prefix(b"_")
        .ok_or("no '_' marks where its data begins")?;
    Ok((raw, data))
}

/// Where a binary array's bytes come from: raw appended data, or base64
/// text decoded as it is taken.
pub(super) enum Stream<'a> {
    Raw {
        bytes: &'a [u8],
        at: usize,
    },
    /// VTK encodes an array's header and its data as separate base64
    /// runs, each padded, which one decoder does not take as a whole;
    /// `spare` holds what a run decoded beyond what was taken from it,
    /// where a writer encoded them as one.
    Base64 {
        text: Cow<'a, [u8]>,
        at: usize,
        spare: Vec<u8>,
    },
}

impl<'a> Stream<'a> {
    pub(super) fn base64(text: &'a [u8]) -> Self {
        let text = text.trim_ascii();
        let text = if text.iter().any(u8::is_ascii_whitespace) {
            Cow::Owned(
                text.iter()
                    .copied()
                    .filter(|b| !b.is_ascii_whitespace())
                    .collect(),
            )
        } else {
            Cow::Borrowed(text)
        };
        Stream::Base64 {
            text,
            at: 0,
            spare: Vec::new(),
        }
    }

    /// The next `n` bytes; why not, where there are fewer.
    fn take(&mut self, n: usize) -> Result<Cow<'a, [u8]>, String> {
        match self {
            Stream::Raw { bytes, at } => {
                let rest = bytes.get(*at..).unwrap_or_default();
                let taken = rest.get(..n).ok_or_else(|| {
                    format!("the data ends {} bytes short of {n}", n - rest.len())
                })?;
                *at += n;
                Ok(Cow::Borrowed(taken))
            }
            Stream::Base64 { text, at, spare } => {
                let mut out = std::mem::take(spare);
                if out.len() >= n {
                    *spare = out.split_off(n);
                    return Ok(Cow::Owned(out));
                }
                let most = (text.len() - *at) / 4 * 3 + out.len();
                if n > most {
                    return Err(format!(
                        "the base64 data holds at most {most} more bytes; {n} are needed"
                    ));
                }
                out.try_reserve_exact(n - out.len() + 2)
                    .map_err(|_| out_of_memory(n as u64).to_string())?;
                while out.len() < n {
                    // Whole groups, up to the end of the run they are in.
                    let groups = (n - out.len()).div_ceil(3);
                    let mut end = *at;
                    for _ in 0..groups {
                        let Some(group) = text.get(end..end + 4) else {
                            break;
                        };
                        end += 4;
                        if group.contains(&b'=') {
                            break;
                        }
                    }
                    if end == *at {
                        return Err(format!(
                            "the base64 data ends {} bytes short",
                            n - out.len()
                        ));
                    }
                    base64::engine::general_purpose::STANDARD
                        .decode_vec(&text[*at..end], &mut out)
                        .map_err(|e| format!("not base64: {e}"))?;
                    *at = end;
                }
                *spare = out.split_off(n);
                Ok(Cow::Owned(out))
            }
        }
    }
}

/// The `want` bytes of a binary array from `stream`, at its header: one
/// word giving their size, or, compressed, the number of blocks, their
/// size, the last one's and each one's compressed size, then the blocks.
pub(super) fn array_bytes<'a>(
    stream: &mut Stream<'a>,
    layout: Layout,
    want: usize,
) -> Result<Cow<'a, [u8]>, String> {
    let w = layout.word;
    if !layout.zlib {
        let size = layout.word(&stream.take(w)?);
        if size != want as u64 {
            return Err(format!("{size} bytes; the grid needs {want}"));
        }
        return stream.take(want);
    }
    let head = stream.take(3 * w)?;
    let (blocks, block, last) = (
        layout.word(&head[..w]),
        layout.word(&head[w..2 * w]),
        layout.word(&head[2 * w..]),
    );
    let sizes_len = usize::try_from(blocks)
        .ok()
        .and_then(|b| b.checked_mul(w))
        .ok_or_else(|| format!("{blocks} blocks"))?;
    let sizes = stream.take(sizes_len)?;
    let last_block = if last == 0 { block } else { last };
    let total = match blocks.checked_sub(1) {
        None => Some(0),
        Some(full) => full
            .checked_mul(block)
            .and_then(|t| t.checked_add(last_block)),
    };
    if total != Some(want as u64) {
        return Err(format!(
            "{blocks} compressed blocks of {block} bytes (the last {last_block}) do not make the {want} bytes the grid needs"
        ));
    }
    let compressed_sizes: Vec<usize> = sizes
        .chunks_exact(w)
        .map(|c| usize::try_from(layout.word(c)).unwrap_or(usize::MAX))
        .collect();
    let compressed_len = compressed_sizes
        .iter()
        .try_fold(0usize, |a, &c| a.checked_add(c))
        .ok_or("the compressed sizes overflow")?;
    let compressed = stream.take(compressed_len)?;
    let mut out = Vec::new();
    // One reservation for all the blocks, as large as they can inflate to.
    let most = compressed_len.saturating_mul(ZLIB_MAX_RATIO).min(want);
    out.try_reserve_exact(most)
        .map_err(|_| out_of_memory(most as u64).to_string())?;
    let mut at = 0;
    for (i, &size) in compressed_sizes.iter().enumerate() {
        let expect = if i + 1 == compressed_sizes.len() {
            last_block
        } else {
            block
        } as usize;
        let before = out.len();
        inflate(&compressed[at..at + size], &mut out, expect)
            .map_err(|e| format!("compressed block {i}: {e}"))?;
        if out.len() - before != expect {
            return Err(format!(
                "compressed block {i} inflates to {} of its {expect} bytes",
                out.len() - before
            ));
        }
        at += size;
    }
    Ok(Cow::Owned(out))
}

/// The elements named `tag` in `node`.
pub(super) fn child<'a, 'i>(
    node: roxmltree::Node<'a, 'i>,
    tag: &str,
) -> Vec<roxmltree::Node<'a, 'i>> {
    node.children().filter(|n| n.has_tag_name(tag)).collect()
}
