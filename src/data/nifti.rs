//! NIfTI-1 and NIfTI-2 volumes (`.nii`, `.nii.gz`, `.hdr` with its `.img`):
//! the header checked field by field, the voxels as the file's scaling
//! says, and the index-to-world map its sform (preferred, as the format's
//! readers do) or qform gives, so that a scan lands where the scanner put
//! it. Every size is checked against the file before anything is read.

use std::io::Read;
use std::path::{Path, PathBuf};

use glam::{DMat3, DMat4, DVec3, DVec4, Mat4, UVec3};

use super::files;
use super::stored::{voxel_count, Stored};
use super::{bad, DataError};
use crate::scene::StructuredVolume;

const NIFTI1_HEADER: usize = 348;
const NIFTI2_HEADER: usize = 540;

/// What a NIfTI file says about its volume, besides the voxels.
#[derive(Clone, Debug, PartialEq)]
pub struct NiftiHeader {
    /// 1 or 2.
    pub version: u8,
    pub dims: UVec3,
    /// The stored type's name (`int16`, `float32`, ...).
    pub dtype: &'static str,
    /// Voxel spacing as `pixdim` gives it, in `units`.
    pub spacing: DVec3,
    /// Voxel index (i, j, k) to world (x, y, z) in `units`: RAS+ for
    /// scanner and template spaces.
    pub affine: DMat4,
    /// Which map gave `affine`: `sform`, `qform` or `pixdim` (neither set).
    pub placed_by: &'static str,
    /// `mm`, `m`, `um` or `unknown`.
    pub units: &'static str,
    /// Stored values are read as `value * slope + intercept`.
    pub slope: f64,
    pub intercept: f64,
    /// Where the voxels begin, in the data file.
    pub offset: u64,
    /// The file the voxels are in (the `.img` of a pair).
    pub data_file: PathBuf,
    big_endian: bool,
    stored: Stored,
}

/// A NIfTI volume: its voxels (index space: origin 0, spacing 1) and header.
pub struct Nifti {
    pub volume: StructuredVolume,
    pub header: NiftiHeader,
}

impl Nifti {
    /// The voxel-index-to-world map as the renderers take it.
    pub fn transform(&self) -> Mat4 {
        self.header.affine.as_mat4()
    }
}

/// Loads the NIfTI volume at `path` (`.nii`, `.nii.gz`, or either file of a
/// `.hdr`/`.img` pair).
pub fn load_nifti(path: &Path) -> Result<Nifti, DataError> {
    let header_path = header_file(path);
    let file = header_path.display().to_string();
    let io = |file: &str| {
        let file = file.to_string();
        move |source: std::io::Error| DataError::Io { file, source }
    };
    let (handle, len) = files::open_regular(&header_path).map_err(io(&file))?;
    let gzipped = is_gz(&header_path);
    let mut reader = maybe_gunzip(handle, gzipped);
    let known = (!gzipped).then_some(len);
    let (header, head) = read_header(&mut reader, &header_path)?;
    if header.data_file == header_path {
        if let Some(nifti) = mapped(&header, gzipped, true) {
            return nifti;
        }
        return read_voxels(header, head, &mut reader, known);
    }
    let data_file = header.data_file.display().to_string();
    let (handle, len) = files::open_regular(&header.data_file).map_err(io(&data_file))?;
    let gzipped = is_gz(&header.data_file);
    if let Some(nifti) = mapped(&header, gzipped, false) {
        return nifti;
    }
    let mut reader = maybe_gunzip(handle, gzipped);
    read_voxels(header, Vec::new(), &mut reader, (!gzipped).then_some(len))
}

/// A single-file NIfTI volume (`.nii`, or gzipped where `name` ends in
/// `.gz`) held in memory, as `load_nifti` reads a file.
pub fn parse_nifti(bytes: &[u8], name: &str) -> Result<Nifti, DataError> {
    let path = Path::new(name);
    let gzipped = is_gz(path);
    let mut reader: Box<dyn Read + '_> = if gzipped {
        Box::new(flate2::read::GzDecoder::new(bytes))
    } else {
        Box::new(bytes)
    };
    let (header, head) = read_header(&mut reader, path)?;
    if header.data_file != path {
        return Err(bad(
            name,
            "magic",
            "a .hdr/.img pair keeps its voxels in the .img file".into(),
        ));
    }
    read_voxels(
        header,
        head,
        &mut reader,
        (!gzipped).then_some(bytes.len() as u64),
    )
}

/// The volume of `header` with its voxels mapped from the data file, where
/// they can be (uncompressed, in a type and byte order kept as stored,
/// after the header where it shares their file); None leaves the reading,
/// and the reporting of what is wrong, to `read_voxels`.
fn mapped(header: &NiftiHeader, gzipped: bool, single: bool) -> Option<Result<Nifti, DataError>> {
    let header_len = if header.version == 1 {
        NIFTI1_HEADER
    } else {
        NIFTI2_HEADER
    } as u64;
    if gzipped || (single && header.offset < header_len) {
        return None;
    }
    let volume = header.stored.mapped_grid(
        &header.data_file,
        header.offset,
        header.dims,
        header.big_endian,
        (header.slope, header.intercept),
    )?;
    Some(volume.map(|volume| Nifti {
        volume,
        header: header.clone(),
    }))
}

fn maybe_gunzip(file: std::fs::File, gzipped: bool) -> Box<dyn Read> {
    let buffered = std::io::BufReader::new(file);
    if gzipped {
        Box::new(flate2::read::GzDecoder::new(buffered))
    } else {
        Box::new(buffered)
    }
}

/// The header at the start of `reader`, and the bytes read for it (the
/// longer header's size, or all there were).
fn read_header(reader: &mut dyn Read, path: &Path) -> Result<(NiftiHeader, Vec<u8>), DataError> {
    let mut head = vec![0u8; NIFTI2_HEADER];
    let got = read_up_to(reader, &mut head).map_err(|source| DataError::Io {
        file: path.display().to_string(),
        source,
    })?;
    head.truncate(got);
    Ok((parse_nifti_header(&head, path)?, head))
}

/// The volume of `header`, its voxels at `header.offset` of the data file:
/// `head` holds the file's first bytes, already read, `reader` the rest;
/// `len` the file's length where it is known, checked before reading.
fn read_voxels(
    header: NiftiHeader,
    head: Vec<u8>,
    reader: &mut dyn Read,
    len: Option<u64>,
) -> Result<Nifti, DataError> {
    let file = header.data_file.display().to_string();
    let voxels = u64::from(header.dims.x) * u64::from(header.dims.y) * u64::from(header.dims.z);
    let bytes = voxels * header.stored.bytes();
    let header_len = if header.version == 1 {
        NIFTI1_HEADER
    } else {
        NIFTI2_HEADER
    } as u64;
    // A single file's voxels follow its header (and its extensions).
    if !head.is_empty() && header.offset < header_len {
        return Err(bad(
            &file,
            "vox_offset",
            format!("{} lies inside the {header_len}-byte header", header.offset),
        ));
    }
    if let Some(len) = len {
        if len < header.offset.saturating_add(bytes) {
            return Err(short(
                &file,
                &header,
                bytes,
                len.saturating_sub(header.offset),
            ));
        }
    }
    let io = |source: std::io::Error| DataError::Io {
        file: file.clone(),
        source,
    };
    // What was read with the header of the voxels, and what lies before
    // them still.
    let consumed = head.len() as u64;
    let skip = header.offset.saturating_sub(consumed);
    let from = header.offset.min(consumed) as usize;
    let mut data = head[from..].to_vec();
    data.truncate(bytes.min(data.len() as u64) as usize);
    let skipped = std::io::copy(&mut reader.take(skip), &mut std::io::sink()).map_err(io)?;
    if skipped < skip {
        return Err(short(&file, &header, bytes, 0));
    }
    let scaling = (header.slope, header.intercept);
    if len.is_some() {
        // The file's length held the voxels: they are read once, into a
        // buffer of their own type.
        let missing = bytes - data.len() as u64;
        let volume = header.stored.read_grid(
            header.dims,
            &data,
            &mut reader.take(missing),
            header.big_endian,
            scaling,
            &file,
        )?;
        return Ok(Nifti { volume, header });
    }
    // Compressed: the buffer grows as the voxels arrive, so a small file
    // that claims a large volume costs no more than it holds.
    let missing = bytes - data.len() as u64;
    reader.take(missing).read_to_end(&mut data).map_err(io)?;
    if (data.len() as u64) < bytes {
        return Err(short(&file, &header, bytes, data.len() as u64));
    }
    let volume = header
        .stored
        .grid(header.dims, &data, header.big_endian, scaling, &file)?;
    Ok(Nifti { volume, header })
}

/// The header of a NIfTI-1 or NIfTI-2 file that begins with `head`, the
/// file being `path` (for a pair's data file and for messages).
pub fn parse_nifti_header(head: &[u8], path: &Path) -> Result<NiftiHeader, DataError> {
    let file = path.display().to_string();
    let field = |name: &str, why: String| bad(&file, name, why);
    if head.len() < 4 {
        return Err(field(
            "sizeof_hdr",
            format!("the file has {} bytes", head.len()),
        ));
    }
    let size_le = i32::from_le_bytes([head[0], head[1], head[2], head[3]]);
    let size_be = i32::from_be_bytes([head[0], head[1], head[2], head[3]]);
    let (version, big_endian) = match (size_le, size_be) {
        (348, _) => (1, false),
        (_, 348) => (1, true),
        (540, _) => (2, false),
        (_, 540) => (2, true),
        _ => {
            return Err(field(
                "sizeof_hdr",
                format!("{size_le} is neither 348 (NIfTI-1) nor 540 (NIfTI-2)"),
            ))
        }
    };
    let need = if version == 1 {
        NIFTI1_HEADER
    } else {
        NIFTI2_HEADER
    };
    if head.len() < need {
        return Err(field(
            "header",
            format!("{} bytes; a NIfTI-{version} header has {need}", head.len()),
        ));
    }
    let r = Fields { head, big_endian };
    let (magic_at, dims, datatype, pixdim, offset, slope, intercept) = if version == 1 {
        let dim: Vec<i64> = (0..8).map(|i| i64::from(r.i16(40 + 2 * i))).collect();
        let pixdim: Vec<f64> = (0..8).map(|i| f64::from(r.f32(76 + 4 * i))).collect();
        let offset = f64::from(r.f32(108));
        (
            344,
            dim,
            i32::from(r.i16(70)),
            pixdim,
            offset,
            f64::from(r.f32(112)),
            f64::from(r.f32(116)),
        )
    } else {
        let dim: Vec<i64> = (0..8).map(|i| r.i64(16 + 8 * i)).collect();
        let pixdim: Vec<f64> = (0..8).map(|i| r.f64(104 + 8 * i)).collect();
        (
            4,
            dim,
            i32::from(r.i16(12)),
            pixdim,
            r.i64(168) as f64,
            r.f64(176),
            r.f64(184),
        )
    };
    let magic = &head[magic_at..magic_at + 4];
    let pair = match magic {
        b"n+1\0" | b"n+2\0" => false,
        b"ni1\0" | b"ni2\0" => true,
        _ => {
            return Err(field(
                "magic",
                format!(
                    "{:?} is not n+{version} or ni{version}",
                    String::from_utf8_lossy(magic)
                ),
            ))
        }
    };
    let ndim = dims[0];
    if !(1..=7).contains(&ndim) {
        return Err(field(
            "dim[0]",
            format!("{ndim} dimensions; NIfTI has 1 to 7"),
        ));
    }
    let mut size = [1u32; 3];
    for (k, s) in size.iter_mut().enumerate().take(ndim.min(3) as usize) {
        let n = dims[k + 1];
        if !(1..=i64::from(u32::MAX)).contains(&n) {
            return Err(field(&format!("dim[{}]", k + 1), format!("{n} voxels")));
        }
        *s = n as u32;
    }
    if let Some(k) = (4..=ndim as usize).find(|&k| dims[k] > 1) {
        return Err(field(
            &format!("dim[{k}]"),
            format!(
                "{} along dimension {k}: caveray reads one 3D volume, not a series of them",
                dims[k]
            ),
        ));
    }
    let dims3 = UVec3::from_array(size);
    voxel_count(dims3)?;
    let stored = match datatype {
        2 => Stored::U8,
        4 => Stored::I16,
        8 => Stored::I32,
        16 => Stored::F32,
        64 => Stored::F64,
        256 => Stored::I8,
        512 => Stored::U16,
        768 => Stored::U32,
        other => {
            return Err(field(
                "datatype",
                format!("{other} is not a scalar type caveray reads (uint8, int8, int16, uint16, int32, uint32, float32, float64)"),
            ))
        }
    };
    if !(0.0..=1e15).contains(&offset) {
        return Err(field("vox_offset", format!("{offset}")));
    }
    let spacing = DVec3::new(pixdim[1], pixdim[2], pixdim[3]);
    let units_code = if version == 1 {
        i32::from(head[123]) & 7
    } else {
        r.i32(500) & 7
    };
    let units = match units_code {
        1 => "m",
        2 => "mm",
        3 => "um",
        _ => "unknown",
    };
    let (qform_code, sform_code) = if version == 1 {
        (i32::from(r.i16(252)), i32::from(r.i16(254)))
    } else {
        (r.i32(344), r.i32(348))
    };
    let (affine, placed_by) = if sform_code > 0 {
        let row = |at: usize| -> DVec4 {
            if version == 1 {
                DVec4::new(
                    f64::from(r.f32(at)),
                    f64::from(r.f32(at + 4)),
                    f64::from(r.f32(at + 8)),
                    f64::from(r.f32(at + 12)),
                )
            } else {
                DVec4::new(r.f64(at), r.f64(at + 8), r.f64(at + 16), r.f64(at + 24))
            }
        };
        let (x, y, z) = if version == 1 {
            (row(280), row(296), row(312))
        } else {
            (row(400), row(432), row(464))
        };
        (
            DMat4::from_cols_array_2d(&[
                x.to_array(),
                y.to_array(),
                z.to_array(),
                [0.0, 0.0, 0.0, 1.0],
            ])
            .transpose(),
            "sform",
        )
    } else if qform_code > 0 {
        let q = |i: usize| {
            if version == 1 {
                f64::from(r.f32(256 + 4 * i))
            } else {
                r.f64(352 + 8 * i)
            }
        };
        let (b, c, d) = (q(0), q(1), q(2));
        let offset = DVec3::new(q(3), q(4), q(5));
        let qfac = if pixdim[0] < 0.0 { -1.0 } else { 1.0 };
        (quaternion_affine((b, c, d), offset, spacing, qfac), "qform")
    } else {
        (DMat4::from_diagonal(spacing.extend(1.0)), "pixdim")
    };
    if !affine.is_finite() {
        return Err(field(placed_by, "its map is not finite".into()));
    }
    let det = DMat3::from_mat4(affine).determinant();
    if det == 0.0 || !det.is_finite() {
        return Err(field(
            placed_by,
            "its map is singular (a zero spacing?)".into(),
        ));
    }
    let (slope, intercept) = if slope.is_finite() && slope != 0.0 {
        (
            slope,
            if intercept.is_finite() {
                intercept
            } else {
                0.0
            },
        )
    } else {
        (1.0, 0.0)
    };
    let data_file = if pair {
        image_file(path)
    } else {
        path.to_path_buf()
    };
    Ok(NiftiHeader {
        version,
        dims: dims3,
        dtype: stored.name(),
        spacing,
        affine,
        placed_by,
        units,
        slope,
        intercept,
        offset: offset as u64,
        data_file,
        big_endian,
        stored,
    })
}

/// The qform's map: the rotation of unit quaternion (a, b, c, d), a from
/// the other three, times the spacing (the third negated by `qfac`), then
/// the offset (the NIfTI-1 header's method 2).
fn quaternion_affine(
    (b, c, d): (f64, f64, f64),
    offset: DVec3,
    spacing: DVec3,
    qfac: f64,
) -> DMat4 {
    // As nifti1_io does: a rotation of (nearly) 180 degrees has a = 0, and
    // its axis is renormalised (b, c and d were stored in single
    // precision, so 1 - b^2 - c^2 - d^2 is noise there).
    let w2 = 1.0 - (b * b + c * c + d * d);
    let (a, b, c, d) = if w2 < 1e-7 {
        let n = (b * b + c * c + d * d).sqrt().max(f64::MIN_POSITIVE);
        (0.0, b / n, c / n, d / n)
    } else {
        (w2.sqrt(), b, c, d)
    };
    let rotation = DMat3::from_cols(
        DVec3::new(
            a * a + b * b - c * c - d * d,
            2.0 * (b * c + a * d),
            2.0 * (b * d - a * c),
        ),
        DVec3::new(
            2.0 * (b * c - a * d),
            a * a + c * c - b * b - d * d,
            2.0 * (c * d + a * b),
        ),
        DVec3::new(
            2.0 * (b * d + a * c),
            2.0 * (c * d - a * b),
            a * a + d * d - c * c - b * b,
        ),
    );
    let scale = DMat3::from_diagonal(DVec3::new(spacing.x, spacing.y, spacing.z * qfac));
    let m = rotation * scale;
    DMat4::from_cols(
        m.x_axis.extend(0.0),
        m.y_axis.extend(0.0),
        m.z_axis.extend(0.0),
        offset.extend(1.0),
    )
}

/// Header fields at byte offsets, in the file's byte order.
struct Fields<'a> {
    head: &'a [u8],
    big_endian: bool,
}

impl Fields<'_> {
    fn bytes<const N: usize>(&self, at: usize) -> [u8; N] {
        let mut b = [0u8; N];
        b.copy_from_slice(&self.head[at..at + N]);
        if self.big_endian {
            b.reverse();
        }
        b
    }
    fn i16(&self, at: usize) -> i16 {
        i16::from_le_bytes(self.bytes(at))
    }
    fn i32(&self, at: usize) -> i32 {
        i32::from_le_bytes(self.bytes(at))
    }
    fn i64(&self, at: usize) -> i64 {
        i64::from_le_bytes(self.bytes(at))
    }
    fn f32(&self, at: usize) -> f32 {
        f32::from_le_bytes(self.bytes(at))
    }
    fn f64(&self, at: usize) -> f64 {
        f64::from_le_bytes(self.bytes(at))
    }
}

fn is_gz(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"))
}

/// The header of a pair given either file (`x.img` -> `x.hdr`).
fn header_file(path: &Path) -> PathBuf {
    swap_extension(path, "img", "hdr")
}

/// The data file of a pair whose header is `path`.
fn image_file(path: &Path) -> PathBuf {
    swap_extension(path, "hdr", "img")
}

fn swap_extension(path: &Path, from: &str, to: &str) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let lower = name.to_lowercase();
    for gz in ["", ".gz"] {
        let suffix = format!(".{from}{gz}");
        if lower.ends_with(&suffix) {
            let stem = &name[..name.len() - suffix.len()];
            return path.with_file_name(format!("{stem}.{to}{gz}"));
        }
    }
    path.to_path_buf()
}

/// Reads into `buf` until it is full or the stream ends; the bytes read.
fn read_up_to(reader: &mut dyn Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match reader.read(&mut buf[got..])? {
            0 => break,
            n => got += n,
        }
    }
    Ok(got)
}

fn short(file: &str, header: &NiftiHeader, bytes: u64, got: u64) -> DataError {
    bad(
        file,
        "voxels",
        format!(
            "{}x{}x{} {} needs {bytes} bytes from vox_offset {}; the file holds {got}",
            header.dims.x, header.dims.y, header.dims.z, header.dtype, header.offset
        ),
    )
}
