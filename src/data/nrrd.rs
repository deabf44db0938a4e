//! NRRD volumes (`.nrrd`, and `.nhdr` with its detached data): the text
//! header's fields checked one by one, raw or gzip-compressed voxels of
//! the scalar types, and the index-to-world map its space directions and
//! origin give, turned into RAS+ where the space is LPS (as 3D Slicer and
//! ITK write it), so that a scan lands where the scanner put it.

use std::io::Read;
use std::path::{Path, PathBuf};

use glam::{DMat4, DVec3, Mat4, UVec3};

use super::files::{self, find};
use super::stored::{voxel_count, Stored};
use super::{bad, DataError};
use crate::scene::StructuredVolume;

/// The most a header may hold.
const HEADER_LIMIT: usize = 1 << 16;

/// What a NRRD header says about its volume, besides the voxels.
#[derive(Clone, Debug, PartialEq)]
pub struct NrrdHeader {
    pub dims: UVec3,
    /// The stored type's name (`int16`, `float32`, ...).
    pub dtype: &'static str,
    /// Voxel index (i, j, k) to world (x, y, z): RAS+ where the file names
    /// an anatomical space, else its own axes.
    pub affine: DMat4,
    /// The `space` field as written (empty where there is none).
    pub space: String,
    /// `raw` or `gzip`.
    pub encoding: &'static str,
    /// Whether `affine` is anatomical (RAS+), so that superior is up.
    pub anatomical: bool,
    /// The world's unit: the `space units` field where all three agree,
    /// else `mm` in an anatomical space (as 3D Slicer takes it), else
    /// `unknown`.
    pub units: &'static str,
    data_file: Option<PathBuf>,
    byte_skip: u64,
    big_endian: bool,
    stored: Stored,
}

/// A NRRD volume: its voxels (index space: origin 0, spacing 1) and header.
pub struct Nrrd {
    pub volume: StructuredVolume,
    pub header: NrrdHeader,
}

impl Nrrd {
    /// The voxel-index-to-world map as the renderers take it.
    pub fn transform(&self) -> Mat4 {
        self.header.affine.as_mat4()
    }
}

/// Loads the NRRD volume at `path` (`.nrrd`, or a `.nhdr` whose `data
/// file` holds the voxels).
pub fn load_nrrd(path: &Path) -> Result<Nrrd, DataError> {
    let file = path.display().to_string();
    let io = |file: &str| {
        let file = file.to_string();
        move |source: std::io::Error| DataError::Io { file, source }
    };
    let (mut handle, len) = files::open_regular(path).map_err(io(&file))?;
    let mut head = vec![0u8; HEADER_LIMIT.min(len as usize)];
    handle.read_exact(&mut head).map_err(io(&file))?;
    let (header, data_at) = parse_nrrd_header(&head, path)?;
    let data_path = header
        .data_file
        .clone()
        .unwrap_or_else(|| path.to_path_buf());
    let start = match header.data_file {
        Some(_) => 0,
        None => data_at as u64,
    };
    if let Some(nrrd) = mapped(&header, &data_path, start) {
        return nrrd;
    }
    match &header.data_file {
        None => {
            drop(head);
            let mut handle = handle;
            // Back to where the voxels begin.
            use std::io::Seek;
            handle
                .seek(std::io::SeekFrom::Start(data_at as u64))
                .map_err(io(&file))?;
            let rest = len.saturating_sub(data_at as u64);
            read_voxels(header, handle, Some(rest), &file)
        }
        Some(data) => {
            let data_name = data.display().to_string();
            let (handle, len) = files::open_regular(data).map_err(io(&data_name))?;
            read_voxels(header, handle, Some(len), &data_name)
        }
    }
}

/// The volume of `header` with its raw voxels mapped from `data` (they
/// begin `start` bytes in, before the byte skip), where they can be; None
/// leaves the reading, and the reporting of what is wrong, to
/// `read_voxels`.
fn mapped(header: &NrrdHeader, data: &Path, start: u64) -> Option<Result<Nrrd, DataError>> {
    if header.encoding != "raw" {
        return None;
    }
    let offset = start.checked_add(header.byte_skip)?;
    let volume =
        header
            .stored
            .mapped_grid(data, offset, header.dims, header.big_endian, (1.0, 0.0))?;
    Some(volume.map(|volume| Nrrd {
        volume,
        header: header.clone(),
    }))
}

/// A NRRD file with attached voxels held in memory, as `load_nrrd`
/// reads one (for the fuzz target).
pub fn parse_nrrd(bytes: &[u8], name: &str) -> Result<Nrrd, DataError> {
    let head = &bytes[..bytes.len().min(HEADER_LIMIT)];
    let (header, data_at) = parse_nrrd_header(head, Path::new(name))?;
    if header.data_file.is_some() {
        return Err(bad(
            name,
            "data file",
            "the voxels are in another file".into(),
        ));
    }
    let rest = &bytes[data_at.min(bytes.len())..];
    read_voxels(header, rest, Some(rest.len() as u64), name)
}

/// The voxels `header` describes from `source` (its length `len`, where
/// known, checked before reading).
fn read_voxels(
    header: NrrdHeader,
    source: impl Read,
    len: Option<u64>,
    file: &str,
) -> Result<Nrrd, DataError> {
    let io = |source: std::io::Error| DataError::Io {
        file: file.to_string(),
        source,
    };
    let voxels = u64::from(header.dims.x) * u64::from(header.dims.y) * u64::from(header.dims.z);
    let bytes = voxels * header.stored.bytes();
    let short = |got: u64| {
        bad(
            file,
            "voxels",
            format!(
                "{}x{}x{} {} needs {bytes} bytes after a byte skip of {}; the data holds {got}",
                header.dims.x, header.dims.y, header.dims.z, header.dtype, header.byte_skip
            ),
        )
    };
    let mut reader: Box<dyn Read> = if header.encoding == "gzip" {
        Box::new(flate2::read::GzDecoder::new(std::io::BufReader::new(
            source,
        )))
    } else {
        if let Some(len) = len {
            if len < header.byte_skip.saturating_add(bytes) {
                return Err(short(len.saturating_sub(header.byte_skip)));
            }
        }
        Box::new(std::io::BufReader::new(source))
    };
    let skipped = std::io::copy(
        &mut (&mut reader).take(header.byte_skip),
        &mut std::io::sink(),
    )
    .map_err(io)?;
    if skipped < header.byte_skip {
        return Err(short(0));
    }
    if header.encoding == "raw" {
        // Checked against the data's length above: read once, into a
        // buffer of their own type.
        let volume = header.stored.read_grid(
            header.dims,
            &[],
            &mut reader.take(bytes),
            header.big_endian,
            (1.0, 0.0),
            file,
        )?;
        return Ok(Nrrd { volume, header });
    }
    // gzip: the buffer grows as the voxels arrive.
    let mut data = Vec::new();
    reader.take(bytes).read_to_end(&mut data).map_err(io)?;
    if (data.len() as u64) < bytes {
        return Err(short(data.len() as u64));
    }
    let volume = header
        .stored
        .grid(header.dims, &data, header.big_endian, (1.0, 0.0), file)?;
    Ok(Nrrd { volume, header })
}

/// The header at the start of `head` (the file `path`'s first bytes) and
/// where its attached voxels begin.
pub fn parse_nrrd_header(head: &[u8], path: &Path) -> Result<(NrrdHeader, usize), DataError> {
    let file = path.display().to_string();
    let field = |name: &str, why: String| bad(&file, name, why);
    if !head.starts_with(b"NRRD000") || head.len() < 8 || !(b'1'..=b'5').contains(&head[7]) {
        return Err(field(
            "magic",
            "the file does not begin NRRD0001 to NRRD0005".into(),
        ));
    }
    // The header ends at the first empty line; a detached header may end
    // with the file.
    let (end, data_at) = match find(head, b"\n\n") {
        Some(i) => (i, i + 2),
        None => match find(head, b"\r\n\r\n") {
            Some(i) => (i, i + 4),
            None => (head.len(), head.len()),
        },
    };
    let text = std::str::from_utf8(&head[..end])
        .map_err(|_| field("header", "it is not text (UTF-8)".into()))?;
    let mut fields: Vec<(String, String)> = Vec::new();
    for line in text.lines().skip(1) {
        let line = line.trim_end_matches('\r');
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        if let Some((key, _)) = line.split_once(":=") {
            if !key.contains(':') {
                continue;
            }
        }
        let Some((key, value)) = line.split_once(": ") else {
            return Err(field(
                "header",
                format!("'{line}' is not a 'field: value' line"),
            ));
        };
        fields.push((key.trim().to_lowercase(), value.trim().to_string()));
    }
    let get = |name: &str| {
        fields
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    };
    let need = |name: &str| get(name).ok_or_else(|| field(name, "missing".into()));
    let stored = match need("type")? {
        "signed char" | "int8" | "int8_t" => Stored::I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => Stored::U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            Stored::I16
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => {
            Stored::U16
        }
        "int" | "signed int" | "int32" | "int32_t" => Stored::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => Stored::U32,
        "float" => Stored::F32,
        "double" => Stored::F64,
        other => {
            return Err(field(
                "type",
                format!("'{other}' is not a scalar type caveray reads (8, 16 or 32-bit integers, float, double)"),
            ))
        }
    };
    let dimension: usize = need("dimension")?
        .parse()
        .map_err(|_| field("dimension", "not a whole number".into()))?;
    let sizes: Vec<u64> = need("sizes")?
        .split_whitespace()
        .map(|s| s.parse::<u64>())
        .collect::<Result<_, _>>()
        .map_err(|_| field("sizes", "not whole numbers".into()))?;
    if sizes.len() != dimension {
        return Err(field(
            "sizes",
            format!("{} sizes for dimension {dimension}", sizes.len()),
        ));
    }
    if !(1..=3).contains(&dimension) {
        return Err(field(
            "dimension",
            format!("{dimension}: caveray reads volumes of 1 to 3 axes"),
        ));
    }
    let mut size = [1u32; 3];
    for (k, &n) in sizes.iter().enumerate() {
        if !(1..=u64::from(u32::MAX)).contains(&n) {
            return Err(field("sizes", format!("{n} voxels along axis {k}")));
        }
        size[k] = n as u32;
    }
    let dims = UVec3::from_array(size);
    voxel_count(dims)?;
    let encoding = match need("encoding")? {
        "raw" => "raw",
        "gzip" | "gz" => "gzip",
        other => {
            return Err(field(
                "encoding",
                format!("'{other}': caveray reads raw and gzip"),
            ))
        }
    };
    let big_endian = match get("endian") {
        Some("big") => true,
        Some("little") => false,
        None if stored.bytes() == 1 => false,
        None => {
            return Err(field(
                "endian",
                "missing for a type wider than a byte".into(),
            ))
        }
        Some(other) => return Err(field("endian", format!("'{other}' is not little or big"))),
    };
    let byte_skip = match get("byte skip").or(get("byteskip")) {
        None => 0,
        Some(s) => s.parse::<u64>().map_err(|_| {
            field(
                "byte skip",
                format!("'{s}': caveray reads a skip of 0 or more bytes"),
            )
        })?,
    };
    if get("line skip")
        .or(get("lineskip"))
        .is_some_and(|s| s != "0")
    {
        return Err(field("line skip", "not read by caveray".into()));
    }
    let space = get("space").unwrap_or("").to_string();
    // To RAS+: LPS and LAS flip their first axes.
    let flip = match space.to_lowercase().as_str() {
        "right-anterior-superior" | "ras" | "scanner-xyz" => Some(DVec3::ONE),
        "left-posterior-superior" | "lps" => Some(DVec3::new(-1.0, -1.0, 1.0)),
        "left-anterior-superior" | "las" => Some(DVec3::new(-1.0, 1.0, 1.0)),
        _ => None,
    };
    let mut columns = [DVec3::X, DVec3::Y, DVec3::Z];
    if let Some(directions) = get("space directions") {
        let parsed: Vec<&str> = directions.split_whitespace().collect();
        if parsed.len() != dimension {
            return Err(field(
                "space directions",
                format!("{} directions for dimension {dimension}", parsed.len()),
            ));
        }
        for (k, d) in parsed.iter().enumerate() {
            columns[k] = vector(d).ok_or_else(|| {
                field("space directions", format!("'{d}' is not a vector (x,y,z)"))
            })?;
        }
    } else if let Some(spacings) = get("spacings") {
        for (k, s) in spacings.split_whitespace().enumerate().take(3) {
            let v: f64 = s
                .parse()
                .map_err(|_| field("spacings", format!("'{s}' is not a number")))?;
            columns[k] *= v;
        }
    }
    let origin = match get("space origin") {
        Some(o) => vector(o)
            .ok_or_else(|| field("space origin", format!("'{o}' is not a vector (x,y,z)")))?,
        None => DVec3::ZERO,
    };
    let turn = flip.unwrap_or(DVec3::ONE);
    let affine = DMat4::from_cols(
        (columns[0] * turn).extend(0.0),
        (columns[1] * turn).extend(0.0),
        (columns[2] * turn).extend(0.0),
        (origin * turn).extend(1.0),
    );
    let det = glam::DMat3::from_mat4(affine).determinant();
    if !affine.is_finite() || det == 0.0 || !det.is_finite() {
        return Err(field(
            "space directions",
            "they are not finite or span no volume".into(),
        ));
    }
    let units = match get("space units") {
        Some(given) => {
            let named: Vec<&str> = given
                .split_whitespace()
                .map(|u| u.trim_matches('"'))
                .collect();
            let unit = match named.first().copied() {
                Some("mm") => "mm",
                Some("m") => "m",
                Some("um" | "µm") => "um",
                _ => "unknown",
            };
            if named.iter().all(|u| *u == named[0]) {
                unit
            } else {
                "unknown"
            }
        }
        None if flip.is_some() => "mm",
        None => "unknown",
    };
    let data_file = match get("data file").or(get("datafile")) {
        None => None,
        Some(name) if name.starts_with("LIST") || name.contains('%') || name.contains(' ') => {
            return Err(field(
                "data file",
                format!("'{name}': caveray reads one data file"),
            ))
        }
        Some(name) => Some(path.parent().unwrap_or(Path::new("")).join(name)),
    };
    if data_file.is_none() && data_at >= head.len() && end == head.len() {
        return Err(field(
            "header",
            "no empty line ends it and no data file is named".into(),
        ));
    }
    Ok((
        NrrdHeader {
            dims,
            dtype: stored.name(),
            affine,
            space,
            encoding,
            anatomical: flip.is_some(),
            units,
            data_file,
            byte_skip,
            big_endian,
            stored,
        },
        data_at,
    ))
}

/// `(x,y,z)` as NRRD writes a vector.
fn vector(s: &str) -> Option<DVec3> {
    let inner = s.trim().strip_prefix('(')?.strip_suffix(')')?;
    let v: Vec<f64> = inner
        .split(',')
        .map(|p| p.trim().parse().ok())
        .collect::<Option<_>>()?;
    (v.len() == 3).then(|| DVec3::new(v[0], v[1], v[2]))
}
