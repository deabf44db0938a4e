//! VTK unstructured grids: XML `.vtu` files (`UnstructuredGrid`, arrays as
//! text, base64 inline or appended, raw appended, zlib-compressed) and
//! legacy `.vtk` files of `DATASET UNSTRUCTURED_GRID` (ASCII or BINARY,
//! the 4.x `CELLS` counts or the 5.x `OFFSETS`/`CONNECTIVITY` layout).
//! Their tetrahedra, hexahedra, wedges and pyramids (and voxels, turned
//! into hexahedra) become an unstructured volume with one point or cell
//! array as its values; cells of lower dimension (surfaces, lines,
//! vertices) are left out and counted; other solid cells (quadratic ones)
//! are refused by name. Every size is checked against the file before a
//! buffer is reserved.

use std::borrow::Cow;
use std::path::Path;

use glam::Vec3;

use super::files::{self, find};
use super::stored::out_of_memory;
use super::vtk::{
    appended_data, array_bytes, child, legacy_header, text, xml_layout, Reader, Stream,
};
use super::{bad, DataError};
use crate::scene::{check_counts, MeshInput, MeshValues, UnstructuredVolume};

/// An unstructured grid read from a file.
#[derive(Debug)]
pub struct MeshFile {
    pub mesh: UnstructuredVolume,
    /// "xml" or "legacy".
    pub flavour: &'static str,
    /// The array sampled, and whether it sits at cells (else points).
    pub array: String,
    pub at_cells: bool,
    /// Every one-component array the file has, and whether at cells.
    pub arrays: Vec<(String, bool)>,
    /// Cells of lower dimension left out (triangles, quads, lines, ...).
    pub skipped: u64,
}

/// Whether `bytes` (a file's start) is a VTK unstructured grid.
pub fn is_vtk_mesh(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(4096)];
    if head.starts_with(b"# vtk DataFile") {
        return find(&head.to_ascii_uppercase(), b"UNSTRUCTURED_GRID").is_some();
    }
    find(head, b"UnstructuredGrid").is_some() && find(head, b"<VTKFile").is_some()
}

/// Loads the unstructured grid at `path`, sampling the array named
/// `array` (else the first point array, else the first cell array).
pub fn load_vtk_mesh(path: &Path, array: Option<&str>) -> Result<MeshFile, DataError> {
    let file = path.display().to_string();
    let io = |source| DataError::Io {
        file: file.clone(),
        source,
    };
    let (handle, len) = files::open_regular(path).map_err(io)?;
    let bytes = files::read_len(handle, len).map_err(io)?;
    parse_vtk_mesh(&bytes, &file, array)
}

/// `load_vtk_mesh` of a file held in memory (for the fuzz target).
pub fn parse_vtk_mesh(
    bytes: &[u8],
    name: &str,
    array: Option<&str>,
) -> Result<MeshFile, DataError> {
    let parts = if bytes.starts_with(b"# vtk DataFile") {
        legacy(bytes, name)?
    } else {
        xml(bytes, name)?
    };
    parts.into_file(name, array)
}

/// VTK's linear solid cells caveray samples, by code, and how many
/// vertices each has; voxels (11) are hexahedra with vertices 2 and 3, 6
/// and 7 swapped.
fn solid(code: u64) -> Option<usize> {
    match code {
        10 => Some(4),
        11 | 12 => Some(8),
        13 => Some(6),
        14 => Some(5),
        _ => None,
    }
}

/// A VTK cell type's name, for refusals.
fn cell_name(code: u64) -> String {
    match code {
        24 => "quadratic tetrahedron".into(),
        25 => "quadratic hexahedron".into(),
        26 => "quadratic wedge".into(),
        27 => "quadratic pyramid".into(),
        42 => "polyhedron".into(),
        other => format!("type {other}"),
    }
}

/// Whether a VTK cell type is of lower dimension than a volume (points,
/// lines, polygons, and their quadratic kin), left out of a volume mesh.
fn lower_dimension(code: u64) -> bool {
    matches!(
        code,
        1..=9 | 21 | 22 | 23 | 28 | 30 | 31 | 34 | 35 | 36 | 37 | 68 | 69 | 70
    )
}

/// What a file holds, before it is checked as a mesh.
struct Parts {
    flavour: &'static str,
    positions: Vec<Vec3>,
    /// Each cell's first entry in `connectivity`, and one past the last.
    offsets: Vec<u64>,
    connectivity: Vec<u64>,
    types: Vec<u64>,
    /// One-component arrays: name, at cells, values.
    arrays: Vec<(String, bool, Vec<f32>)>,
}

impl Parts {
    fn into_file(self, name: &str, wanted: Option<&str>) -> Result<MeshFile, DataError> {
        let field = |f: &str, why: String| bad(name, f, why);
        let cells = self.types.len();
        if self.offsets.len() != cells + 1 {
            return Err(field(
                "offsets",
                format!(
                    "{} cell ends for {cells} cell types",
                    self.offsets.len() - 1
                ),
            ));
        }
        let chosen = match wanted {
            Some(w) => Some(self.arrays.iter().position(|a| a.0 == w).ok_or_else(|| {
                let names: Vec<&str> = self.arrays.iter().map(|a| a.0.as_str()).collect();
                field(
                    "array",
                    format!("no array named '{w}' (arrays: {})", names.join(", ")),
                )
            })?),
            None => self
                .arrays
                .iter()
                .position(|a| !a.1)
                .or_else(|| (!self.arrays.is_empty()).then_some(0)),
        };
        let chosen = chosen.ok_or_else(|| {
            field(
                "PointData",
                "no one-component point or cell array to sample".into(),
            )
        })?;
        let (array, at_cells, values) = &self.arrays[chosen];
        let mut input = MeshInput {
            positions: self.positions,
            ..MeshInput::default()
        };
        let mut cell_values = Vec::new();
        let mut skipped = 0u64;
        for (c, &code) in self.types.iter().enumerate() {
            let (start, end) = (self.offsets[c], self.offsets[c + 1]);
            if end < start || end > self.connectivity.len() as u64 {
                return Err(field(
                    "offsets",
                    format!(
                        "cell {c} ends at {end}, outside {start}..={}",
                        self.connectivity.len()
                    ),
                ));
            }
            let Some(n) = solid(code) else {
                if lower_dimension(code) {
                    skipped += 1;
                    continue;
                }
                return Err(field(
                    "types",
                    format!(
                        "cell {c} is a {}: caveray samples tetrahedra, hexahedra, voxels, wedges and pyramids",
                        cell_name(code)
                    ),
                ));
            };
            let ids = &self.connectivity[start as usize..end as usize];
            if ids.len() != n {
                return Err(field(
                    "connectivity",
                    format!(
                        "cell {c} (VTK type {code}) has {} points; it needs {n}",
                        ids.len()
                    ),
                ));
            }
            let mut corner = [0u32; 8];
            for (k, &id) in ids.iter().enumerate() {
                corner[k] = u32::try_from(id)
                    .map_err(|_| field("connectivity", format!("cell {c} refers to point {id}")))?;
            }
            if code == 11 {
                corner.swap(2, 3);
                corner.swap(6, 7);
            }
            input.cell_index.push(input.index.len() as u32);
            input
                .cell_type
                .push(if code == 11 { 12 } else { code as u32 });
            input.index.extend_from_slice(&corner[..n]);
            if *at_cells {
                cell_values.push(values[c]);
            }
        }
        let values = if *at_cells {
            MeshValues::PerCell(cell_values)
        } else {
            MeshValues::PerVertex(values.clone())
        };
        let mesh =
            UnstructuredVolume::new(input, values).map_err(|e| field("cells", e.to_string()))?;
        Ok(MeshFile {
            mesh,
            flavour: self.flavour,
            array: array.clone(),
            at_cells: *at_cells,
            arrays: self.arrays.iter().map(|a| (a.0.clone(), a.1)).collect(),
            skipped,
        })
    }
}

/// Numbers of a VTK type, as the file stores them.
#[derive(Clone, Copy)]
enum Kind {
    Int(usize, bool),
    Float(usize),
}

impl Kind {
    fn of_xml(name: &str) -> Option<Self> {
        Some(match name {
            "Int8" => Kind::Int(1, true),
            "UInt8" => Kind::Int(1, false),
            "Int16" => Kind::Int(2, true),
            "UInt16" => Kind::Int(2, false),
            "Int32" => Kind::Int(4, true),
            "UInt32" => Kind::Int(4, false),
            "Int64" => Kind::Int(8, true),
            "UInt64" => Kind::Int(8, false),
            "Float32" => Kind::Float(4),
            "Float64" => Kind::Float(8),
            _ => return None,
        })
    }

    fn of_legacy(name: &str) -> Option<Self> {
        Some(match name.to_ascii_lowercase().as_str() {
            "char" | "signed_char" => Kind::Int(1, true),
            "unsigned_char" => Kind::Int(1, false),
            "short" => Kind::Int(2, true),
            "unsigned_short" => Kind::Int(2, false),
            "int" => Kind::Int(4, true),
            "unsigned_int" => Kind::Int(4, false),
            "long" | "vtktypeint64" | "vtkidtype" => Kind::Int(8, true),
            "unsigned_long" | "vtktypeuint64" => Kind::Int(8, false),
            "float" => Kind::Float(4),
            "double" => Kind::Float(8),
            _ => return None,
        })
    }

    fn bytes(self) -> usize {
        match self {
            Kind::Int(n, _) | Kind::Float(n) => n,
        }
    }

    /// The little-endian bits of the number in `b` (`bytes()` long).
    fn bits(b: &[u8], big_endian: bool) -> u64 {
        let mut w = [0u8; 8];
        w[..b.len()].copy_from_slice(b);
        if big_endian {
            w[..b.len()].reverse();
        }
        u64::from_le_bytes(w)
    }

    /// Whether a signed integer's sign bit is set.
    fn negative(self, raw: u64) -> bool {
        matches!(self, Kind::Int(n, true) if raw >> (8 * n - 1) & 1 == 1)
    }

    /// The number in `b` (`bytes()` long).
    fn value(self, b: &[u8], big_endian: bool) -> f64 {
        let raw = Self::bits(b, big_endian);
        match self {
            Kind::Float(4) => f64::from(f32::from_bits(raw as u32)),
            Kind::Float(_) => f64::from_bits(raw),
            Kind::Int(n, _) if self.negative(raw) => {
                // Sign-extended from n bytes.
                (raw | u64::MAX.checked_shl(8 * n as u32).unwrap_or(0)) as i64 as f64
            }
            Kind::Int(..) => raw as f64,
        }
    }

    /// The whole number in `b`; a negative or fractional one is u64::MAX
    /// (and then refused as an index).
    fn whole(self, b: &[u8], big_endian: bool) -> u64 {
        let raw = Self::bits(b, big_endian);
        match self {
            Kind::Int(..) if self.negative(raw) => u64::MAX,
            Kind::Int(..) => raw,
            Kind::Float(_) => {
                let v = self.value(b, big_endian);
                if v >= 0.0 && v.fract() == 0.0 && v < 1.8e19 {
                    v as u64
                } else {
                    u64::MAX
                }
            }
        }
    }
}

/// A vector reserved fallibly for `n` items.
fn reserve<T>(n: usize) -> Result<Vec<T>, String> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        out_of_memory((n as u64).saturating_mul(std::mem::size_of::<T>() as u64)).to_string()
    })?;
    Ok(v)
}

/// Decoded numbers of one array.
enum Numbers {
    Whole(Vec<u64>),
    Real(Vec<f32>),
}

fn decode(data: &[u8], kind: Kind, big_endian: bool, whole: bool) -> Result<Numbers, String> {
    let n = data.len() / kind.bytes();
    let chunks = data.chunks_exact(kind.bytes());
    Ok(if whole {
        let mut v = reserve(n)?;
        v.extend(chunks.map(|c| kind.whole(c, big_endian)));
        Numbers::Whole(v)
    } else {
        let mut v = reserve(n)?;
        v.extend(chunks.map(|c| kind.value(c, big_endian) as f32));
        Numbers::Real(v)
    })
}

fn text_numbers(words: &mut Reader<'_>, n: usize, whole: bool) -> Result<Numbers, String> {
    let most = n.min(words.bytes.len().saturating_sub(words.at).div_ceil(2));
    if whole {
        let mut v = reserve(most)?;
        for got in 0..n {
            let w = words
                .word()
                .ok_or_else(|| format!("{got} numbers; {n} are needed"))?;
            let s = std::str::from_utf8(w).unwrap_or("");
            let x = s
                .parse::<u64>()
                .ok()
                .or_else(|| s.parse::<i64>().ok().map(|_| u64::MAX))
                .ok_or_else(|| format!("'{}' is not a whole number", String::from_utf8_lossy(w)))?;
            v.push(x);
        }
        Ok(Numbers::Whole(v))
    } else {
        words.numbers(n).map(Numbers::Real)
    }
}

fn whole(n: Numbers) -> Vec<u64> {
    match n {
        Numbers::Whole(v) => v,
        Numbers::Real(v) => v.into_iter().map(|x| x as u64).collect(),
    }
}

fn real(n: Numbers) -> Vec<f32> {
    match n {
        Numbers::Real(v) => v,
        Numbers::Whole(v) => v.into_iter().map(|x| x as f32).collect(),
    }
}

fn positions_of(xyz: Vec<f32>, name: &str) -> Result<Vec<Vec3>, DataError> {
    let mut out = reserve(xyz.len() / 3).map_err(|why| bad(name, "Points", why))?;
    out.extend(xyz.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
    Ok(out)
}

fn xml(bytes: &[u8], name: &str) -> Result<Parts, DataError> {
    let field = |f: &str, why: String| bad(name, f, why);
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
    let kind = root.attribute("type").unwrap_or("");
    if root.tag_name().name() != "VTKFile" || kind != "UnstructuredGrid" {
        return Err(field(
            "type",
            format!("'{kind}': this reader takes UnstructuredGrid (.vtu)"),
        ));
    }
    let layout = xml_layout(root, name)?;
    let big_endian = layout.big_endian;
    let grid = child(root, "UnstructuredGrid")
        .into_iter()
        .next()
        .ok_or_else(|| field("UnstructuredGrid", "missing".into()))?;
    let pieces = child(grid, "Piece");
    let piece = match pieces[..] {
        [one] => one,
        [] => return Err(field("Piece", "missing".into())),
        _ => {
            return Err(field(
                "Piece",
                format!("{} pieces: caveray reads files of one", pieces.len()),
            ))
        }
    };
    let count = |key: &str| -> Result<u64, DataError> {
        piece
            .attribute(key)
            .and_then(|v| v.trim().parse::<u64>().ok())
            .ok_or_else(|| field(key, "missing or not a whole number".into()))
    };
    let (points, cells) = (count("NumberOfPoints")?, count("NumberOfCells")?);
    check_counts(points, 0, cells).map_err(|e| field("Piece", e.to_string()))?;
    // An array's numbers: `n` values of `components` each.
    let read = |array: roxmltree::Node<'_, '_>,
                n: u64,
                whole: bool|
     -> Result<Numbers, DataError> {
        let array_name = array.attribute("Name").unwrap_or("").to_string();
        let in_array = |why: String| field("DataArray", format!("'{array_name}': {why}"));
        let kind_name = array.attribute("type").unwrap_or("");
        let kind = Kind::of_xml(kind_name).ok_or_else(|| {
            in_array(format!(
                "type '{kind_name}' is not a number type VTK writes"
            ))
        })?;
        let n = usize::try_from(n).map_err(|_| in_array(format!("{n} values")))?;
        let want = n
            .checked_mul(kind.bytes())
            .ok_or_else(|| in_array(format!("{n} values")))?;
        match array.attribute("format").unwrap_or("") {
            "ascii" => {
                let text = array.text().unwrap_or("");
                let mut reader = Reader {
                    bytes: text.as_bytes(),
                    at: 0,
                };
                text_numbers(&mut reader, n, whole).map_err(in_array)
            }
            "binary" => {
                let text = array.text().unwrap_or("");
                let mut stream = Stream::base64(text.as_bytes());
                let data = array_bytes(&mut stream, layout, want).map_err(in_array)?;
                decode(&data, kind, big_endian, whole).map_err(in_array)
            }
            "appended" => {
                let offset = array
                    .attribute("offset")
                    .and_then(|o| o.parse::<usize>().ok())
                    .ok_or_else(|| field("offset", "missing or not a number of bytes".into()))?;
                let at = appended.ok_or_else(|| field("AppendedData", "missing".into()))?;
                let (raw, data) =
                    appended_data(bytes, at).map_err(|why| field("AppendedData", why))?;
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
                let data: Cow<'_, [u8]> =
                    array_bytes(&mut stream, layout, want).map_err(in_array)?;
                decode(&data, kind, big_endian, whole).map_err(in_array)
            }
            other => Err(field(
                "format",
                format!("'{other}' is not ascii, binary or appended"),
            )),
        }
    };
    let points_node = child(piece, "Points")
        .into_iter()
        .next()
        .and_then(|p| child(p, "DataArray").into_iter().next())
        .ok_or_else(|| field("Points", "missing".into()))?;
    let positions = positions_of(real(read(points_node, 3 * points, false)?), name)?;
    let cells_node = child(piece, "Cells")
        .into_iter()
        .next()
        .ok_or_else(|| field("Cells", "missing".into()))?;
    let named = |n: &str| {
        child(cells_node, "DataArray")
            .into_iter()
            .find(|a| a.attribute("Name") == Some(n))
            .ok_or_else(|| field("Cells", format!("no '{n}' array")))
    };
    let ends = whole(read(named("offsets")?, cells, true)?);
    let types = whole(read(named("types")?, cells, true)?);
    let total = ends.last().copied().unwrap_or(0);
    check_counts(points, total, cells).map_err(|e| field("connectivity", e.to_string()))?;
    let connectivity = whole(read(named("connectivity")?, total, true)?);
    let mut offsets = reserve(ends.len() + 1).map_err(|why| field("offsets", why))?;
    offsets.push(0);
    offsets.extend(ends);
    let mut arrays = Vec::new();
    for (tag, at_cells, n) in [("PointData", false, points), ("CellData", true, cells)] {
        for data in child(piece, tag) {
            for array in child(data, "DataArray") {
                if array
                    .attribute("NumberOfComponents")
                    .is_some_and(|c| c.trim() != "1")
                {
                    continue;
                }
                let values = real(read(array, n, false)?);
                arrays.push((
                    array.attribute("Name").unwrap_or("").to_string(),
                    at_cells,
                    values,
                ));
            }
        }
    }
    Ok(Parts {
        flavour: "xml",
        positions,
        offsets,
        connectivity,
        types,
        arrays,
    })
}

fn legacy(bytes: &[u8], name: &str) -> Result<Parts, DataError> {
    let field = |f: &str, why: String| bad(name, f, why);
    let mut reader = Reader { bytes, at: 0 };
    let binary = legacy_header(&mut reader, name)?;
    // `n` numbers of `kind` from the reader: text or big-endian binary.
    let numbers = |reader: &mut Reader<'_>,
                   n: u64,
                   kind: Kind,
                   whole: bool,
                   what: &str|
     -> Result<Numbers, DataError> {
        let in_section = |why: String| field(what, why);
        let n = usize::try_from(n).map_err(|_| in_section(format!("{n} values")))?;
        if binary {
            let want = n
                .checked_mul(kind.bytes())
                .ok_or_else(|| in_section(format!("{n} values")))?;
            let data = reader
                .take(want)
                .ok_or_else(|| in_section(format!("the file ends within its {n} values")))?;
            let out = decode(data, kind, true, whole).map_err(in_section)?;
            // The line break after binary data.
            let rest = &reader.bytes[reader.at..];
            if rest.first() == Some(&b'\n') {
                reader.at += 1;
            }
            Ok(out)
        } else {
            text_numbers(reader, n, whole).map_err(in_section)
        }
    };
    let kind_of = |word: &str, what: &str| {
        Kind::of_legacy(word)
            .ok_or_else(|| field(what, format!("'{word}' is not a VTK number type")))
    };
    let mut positions = None;
    let mut offsets: Option<Vec<u64>> = None;
    let mut connectivity: Option<Vec<u64>> = None;
    let mut types = None;
    let mut arrays = Vec::new();
    let mut section: Option<(bool, u64)> = None;
    while let Some(line) = reader.line() {
        let line = text(line, name)?;
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some(first) = words.first() else { continue };
        let args = &words[1..];
        let arg = |i: usize| args.get(i).copied().unwrap_or("");
        let count = |i: usize, what: &str| {
            arg(i)
                .parse::<u64>()
                .map_err(|_| field(what, format!("'{}' is not a count", arg(i))))
        };
        match first.to_ascii_uppercase().as_str() {
            "DATASET" => {
                if !arg(0).eq_ignore_ascii_case("UNSTRUCTURED_GRID") {
                    return Err(field(
                        "DATASET",
                        format!("'{}': this reader takes UNSTRUCTURED_GRID", arg(0)),
                    ));
                }
            }
            "POINTS" => {
                let points = count(0, "POINTS")?;
                check_counts(points, 0, 0).map_err(|e| field("POINTS", e.to_string()))?;
                let kind = kind_of(arg(1), "POINTS")?;
                let xyz = real(numbers(&mut reader, 3 * points, kind, false, "POINTS")?);
                positions = Some(positions_of(xyz, name)?);
            }
            "CELLS" => {
                let (a, b) = (count(0, "CELLS")?, count(1, "CELLS")?);
                check_counts(0, b, a).map_err(|e| field("CELLS", e.to_string()))?;
                // 5.x: OFFSETS (a numbers) and CONNECTIVITY (b) follow as
                // sections of their own; 4.x: b numbers, each cell its
                // count then its points.
                let before = reader.at;
                let next = reader
                    .line()
                    .map(|l| String::from_utf8_lossy(l).to_ascii_uppercase());
                if next
                    .as_deref()
                    .is_some_and(|l| l.trim_start().starts_with("OFFSETS"))
                {
                    let kind_word = next
                        .as_deref()
                        .unwrap_or("")
                        .split_whitespace()
                        .nth(1)
                        .unwrap_or("")
                        .to_string();
                    let kind = kind_of(&kind_word, "OFFSETS")?;
                    offsets = Some(whole(numbers(&mut reader, a, kind, true, "OFFSETS")?));
                    // Past the end of the offsets' last line.
                    let mut line = String::new();
                    while line.trim().is_empty() {
                        match reader.line() {
                            Some(l) => line = String::from_utf8_lossy(l).to_string(),
                            None => break,
                        }
                    }
                    let kind_word = line.split_whitespace().nth(1).unwrap_or("").to_string();
                    if !line
                        .trim_start()
                        .to_ascii_uppercase()
                        .starts_with("CONNECTIVITY")
                    {
                        return Err(field("CONNECTIVITY", "missing after OFFSETS".into()));
                    }
                    let kind = kind_of(&kind_word, "CONNECTIVITY")?;
                    connectivity =
                        Some(whole(numbers(&mut reader, b, kind, true, "CONNECTIVITY")?));
                } else {
                    reader.at = before;
                    let list = whole(numbers(&mut reader, b, Kind::Int(4, true), true, "CELLS")?);
                    let mut ends = reserve(a as usize + 1).map_err(|why| field("CELLS", why))?;
                    let mut ids = reserve(list.len()).map_err(|why| field("CELLS", why))?;
                    ends.push(0u64);
                    let mut at = 0usize;
                    for c in 0..a {
                        let n = *list.get(at).ok_or_else(|| {
                            field("CELLS", format!("the list ends before cell {c}"))
                        })?;
                        let n = usize::try_from(n)
                            .ok()
                            .filter(|&n| n < list.len() && at + 1 + n <= list.len())
                            .ok_or_else(|| {
                                field(
                                    "CELLS",
                                    format!("cell {c} claims {n} points, past the list's end"),
                                )
                            })?;
                        ids.extend_from_slice(&list[at + 1..at + 1 + n]);
                        at += 1 + n;
                        ends.push(ids.len() as u64);
                    }
                    offsets = Some(ends);
                    connectivity = Some(ids);
                }
            }
            "CELL_TYPES" => {
                let n = count(0, "CELL_TYPES")?;
                check_counts(0, 0, n).map_err(|e| field("CELL_TYPES", e.to_string()))?;
                types = Some(whole(numbers(
                    &mut reader,
                    n,
                    Kind::Int(4, true),
                    true,
                    "CELL_TYPES",
                )?));
            }
            "POINT_DATA" => section = Some((false, count(0, "POINT_DATA")?)),
            "CELL_DATA" => section = Some((true, count(0, "CELL_DATA")?)),
            "SCALARS" => {
                let (at_cells, n) = section
                    .ok_or_else(|| field("SCALARS", "outside POINT_DATA or CELL_DATA".into()))?;
                let components = if args.len() > 2 {
                    count(2, "SCALARS")?
                } else {
                    1
                };
                let kind = kind_of(arg(1), "SCALARS")?;
                reader.lookup_table();
                let values = real(numbers(
                    &mut reader,
                    n.saturating_mul(components),
                    kind,
                    false,
                    "SCALARS",
                )?);
                if components == 1 {
                    arrays.push((arg(0).to_string(), at_cells, values));
                }
            }
            "FIELD" => {
                let (at_cells, n) = section
                    .ok_or_else(|| field("FIELD", "outside POINT_DATA or CELL_DATA".into()))?;
                let k = count(1, "FIELD")?;
                for _ in 0..k {
                    let Some(line) = reader.line() else { break };
                    let line = text(line, name)?;
                    let w: Vec<&str> = line.split_whitespace().collect();
                    if w.is_empty() {
                        continue;
                    }
                    let components = w.get(1).and_then(|c| c.parse::<u64>().ok()).unwrap_or(1);
                    let tuples = w.get(2).and_then(|c| c.parse::<u64>().ok()).unwrap_or(n);
                    let kind = kind_of(w.get(3).copied().unwrap_or(""), "FIELD")?;
                    let values = real(numbers(
                        &mut reader,
                        tuples.saturating_mul(components),
                        kind,
                        false,
                        "FIELD",
                    )?);
                    if components == 1 && tuples == n {
                        arrays.push((w[0].to_string(), at_cells, values));
                    }
                }
            }
            "VECTORS" | "NORMALS" | "TENSORS" => {
                let (_, n) = section
                    .ok_or_else(|| field(first, "outside POINT_DATA or CELL_DATA".into()))?;
                let per = if first.eq_ignore_ascii_case("TENSORS") {
                    9
                } else {
                    3
                };
                let kind = kind_of(arg(1), first)?;
                numbers(&mut reader, n.saturating_mul(per), kind, false, first)?;
            }
            // VTK 5's metadata blocks carry no numbers caveray needs.
            "METADATA" | "INFORMATION" | "NAME" | "DATA" => {}
            other => {
                return Err(field(
                    other,
                    "a section caveray does not read in an unstructured grid".into(),
                ));
            }
        }
    }
    let positions = positions.ok_or_else(|| field("POINTS", "missing".into()))?;
    Ok(Parts {
        flavour: "legacy",
        positions,
        offsets: offsets.ok_or_else(|| field("CELLS", "missing".into()))?,
        connectivity: connectivity.ok_or_else(|| field("CELLS", "missing".into()))?,
        types: types.ok_or_else(|| field("CELL_TYPES", "missing".into()))?,
        arrays,
    })
}
