//! DICOM series: a folder of single-frame slices (or one of its files,
//! which stands for its series), in the transfer syntaxes scanners and
//! PACS export (uncompressed, deflate, RLE, JPEG baseline, extended and
//! lossless; each file read by `dataset`). Slices are ordered by their
//! position along the slice normal, not by file name or instance number,
//! which exporters get wrong; the grid's map to the world comes from
//! ImageOrientationPatient, ImagePositionPatient and PixelSpacing, turned
//! from DICOM's LPS into RAS+ as the other readers' anatomical spaces are.
//! Values are the modality's (Hounsfield units for CT): stored bits, sign
//! and each slice's own rescale slope and intercept applied; the voxels
//! are kept in their stored type where one rescale holds for the series.

mod dataset;

use std::io::Read;
use std::path::{Path, PathBuf};

use glam::{DMat4, DVec3, UVec3};
use serde_json::Value;

use self::dataset::DataSet;
use super::files;
use super::format::VolumeFormat;
use super::stored::{out_of_memory, voxel_count, ZLIB_MAX_RATIO};
use super::volume_file::VolumeFile;
use super::{bad, DataError};
use crate::scene::{Scaling, StructuredVolume, Voxels};

/// The elements a slice is read from (group << 16 | element).
mod tags {
    pub const MODALITY: u32 = 0x0008_0060;
    pub const SLICE_THICKNESS: u32 = 0x0018_0050;
    pub const SPACING_BETWEEN_SLICES: u32 = 0x0018_0088;
    pub const SERIES_INSTANCE_UID: u32 = 0x0020_000E;
    pub const IMAGE_POSITION_PATIENT: u32 = 0x0020_0032;
    pub const IMAGE_ORIENTATION_PATIENT: u32 = 0x0020_0037;
    pub const SAMPLES_PER_PIXEL: u32 = 0x0028_0002;
    pub const NUMBER_OF_FRAMES: u32 = 0x0028_0008;
    pub const ROWS: u32 = 0x0028_0010;
    pub const COLUMNS: u32 = 0x0028_0011;
    pub const PIXEL_SPACING: u32 = 0x0028_0030;
    pub const BITS_ALLOCATED: u32 = 0x0028_0100;
    pub const BITS_STORED: u32 = 0x0028_0101;
    pub const PIXEL_REPRESENTATION: u32 = 0x0028_0103;
    pub const RESCALE_INTERCEPT: u32 = 0x0028_1052;
    pub const RESCALE_SLOPE: u32 = 0x0028_1053;
}

/// Files of a folder looked at: a series of more slices than this is a
/// stack no scanner writes to one folder.
const MAX_FILES: usize = 1 << 16;

/// How far apart two slices' steps may be, as a fraction of the series'
/// typical step, before the series counts as unevenly spaced (a slice
/// missing, or two series mixed): DICOM writes positions as decimal
/// strings of 16 characters at most, which round well inside this.
const STEP_TOLERANCE: f64 = 0.05;

/// What one slice's header says, read before its pixels.
#[derive(Clone, Debug)]
struct Slice {
    file: PathBuf,
    series: String,
    rows: u32,
    columns: u32,
    /// Unit vectors along a row (increasing column) and along a column
    /// (increasing row), in LPS.
    row_axis: DVec3,
    column_axis: DVec3,
    /// Between rows, between columns (PixelSpacing's order).
    pixel_spacing: [f64; 2],
    position: DVec3,
    bits_allocated: u16,
    bits_stored: u16,
    signed: bool,
    slope: f64,
    intercept: f64,
    thickness: Option<f64>,
    modality: String,
    transfer_syntax: String,
}

/// Loads the series at `path`: a folder (its largest series, where it
/// holds several) or one of its files (that file's series).
pub fn load_dicom(path: &Path) -> Result<VolumeFile, DataError> {
    let (folder, chosen) = if path.is_dir() {
        (path.to_path_buf(), None)
    } else {
        let slice = read_slice(path)?;
        let folder = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."))
            .to_path_buf();
        (folder, Some(slice.series))
    };
    let mut slices = Vec::new();
    let mut skipped = Vec::new();
    for file in folder_files(&folder)? {
        match read_slice(&file) {
            Ok(slice) => slices.push(slice),
            // Other files (a DICOMDIR, a report, a thumbnail) share series
            // folders; a broken slice shows as a gap when the series is
            // checked.
            Err(e) => skipped.push(e),
        }
    }
    let name = folder.display().to_string();
    let mut series: Vec<(String, Vec<Slice>)> = Vec::new();
    for slice in slices {
        match series.iter_mut().find(|(uid, _)| *uid == slice.series) {
            Some((_, members)) => members.push(slice),
            None => series.push((slice.series.clone(), vec![slice])),
        }
    }
    let count = series.len();
    let (uid, members) = match chosen {
        Some(uid) => series.into_iter().find(|(u, _)| *u == uid),
        None => series.into_iter().max_by_key(|(_, m)| m.len()),
    }
    .ok_or_else(|| {
        // A slice with a field at fault says so itself; files that are no
        // DICOM at all say the folder holds no series.
        let slice_at_fault = skipped
            .iter()
            .position(|e| matches!(e, DataError::Header { field, .. } if field != "file"));
        match (slice_at_fault, skipped.first()) {
            (Some(i), _) => skipped.swap_remove(i),
            (None, Some(e)) => bad(
                &name,
                "files",
                format!("no DICOM image slices in the folder (the first file: {e})"),
            ),
            (None, None) => bad(&name, "files", "no files in the folder".into()),
        }
    })?;
    let mut file = assemble(members, &name, |slice| read_pixels(&slice.file, slice))?;
    file.details.insert(0, ("series", Value::from(uid)));
    file.details.push(("series_in_folder", Value::from(count)));
    file.details
        .push(("files_skipped", Value::from(skipped.len())));
    if !path.is_dir() {
        file.format = VolumeFormat::Dicom;
    }
    Ok(file)
}

/// One DICOM file held in memory, read as a series of one slice (for the
/// fuzz target): the same header checks and decoding as a folder's.
pub fn parse_dicom(bytes: &[u8], name: &str) -> Result<VolumeFile, DataError> {
    let set = DataSet::parse(bytes, true).map_err(|why| bad(name, "file", why))?;
    let slice = slice_of(&set, Path::new(name))?;
    let decoded = decode(&set, &slice, bytes.len())?;
    assemble(vec![slice], name, |_| Ok(decoded.clone()))
}

/// The regular files of `folder`, sorted by name.
fn folder_files(folder: &Path) -> Result<Vec<PathBuf>, DataError> {
    let name = folder.display().to_string();
    let entries = std::fs::read_dir(folder).map_err(|source| DataError::Io {
        file: name.clone(),
        source,
    })?;
    let mut found = Vec::new();
    for entry in entries.flatten() {
        if entry.file_type().is_ok_and(|t| t.is_file()) {
            if found.len() == MAX_FILES {
                return Err(bad(
                    &name,
                    "files",
                    format!("more than {MAX_FILES} files; caveray reads one series a folder"),
                ));
            }
            found.push(entry.path());
        }
    }
    found.sort();
    Ok(found)
}

/// The header of the slice in `file`, its pixels left unread.
fn read_slice(file: &Path) -> Result<Slice, DataError> {
    let name = file.display().to_string();
    let set = DataSet::parse(&file_bytes(file)?, false).map_err(|why| bad(&name, "file", why))?;
    slice_of(&set, file)
}

/// The stored numbers of `slice`'s pixels, from its file read whole.
fn read_pixels(file: &Path, slice: &Slice) -> Result<Vec<i64>, DataError> {
    let name = file.display().to_string();
    let bytes = file_bytes(file)?;
    let set = DataSet::parse(&bytes, true).map_err(|why| bad(&name, "file", why))?;
    decode(&set, slice, bytes.len())
}

/// The whole of `file`, where it is a DICOM file (`DICM` after its
/// preamble): slices are small, and a large file beside them is not read
/// to find it is not one.
fn file_bytes(file: &Path) -> Result<Vec<u8>, DataError> {
    let name = file.display().to_string();
    let io = |source| DataError::Io {
        file: name.clone(),
        source,
    };
    let (mut handle, len) = files::open_regular(file).map_err(io)?;
    let mut head = [0u8; 132];
    let dicom = len >= 132 && handle.read_exact(&mut head).is_ok() && &head[128..] == b"DICM";
    if !dicom {
        return Err(bad(
            &name,
            "file",
            "not a DICOM file (no DICM after a 128-byte preamble)".into(),
        ));
    }
    let (handle, len) = files::open_regular(file).map_err(io)?;
    files::read_len(handle, len).map_err(io)
}

/// The slice header of `set`, every field checked.
fn slice_of(set: &DataSet, file: &Path) -> Result<Slice, DataError> {
    let name = file.display().to_string();
    let field = |tag: &str, why: String| bad(&name, tag, why);
    let int = |tag, label: &str| -> Result<i64, DataError> {
        set.us(tag)
            .map(i64::from)
            .ok_or_else(|| field(label, "missing".into()))
    };
    let floats = |tag, label: &str, n: usize| -> Result<Vec<f64>, DataError> {
        let v = set.numbers(tag).ok_or_else(|| match set.text(tag) {
            None => field(label, "missing".into()),
            Some(t) => field(label, format!("'{t}' is not numbers")),
        })?;
        if v.len() != n {
            return Err(field(
                label,
                format!("{} values where {n} are needed", v.len()),
            ));
        }
        Ok(v)
    };
    let optional_float = |tag| set.numbers(tag).and_then(|v| v.first().copied());
    let text = |tag| set.text(tag).unwrap_or_default();
    let frames = set
        .numbers(tags::NUMBER_OF_FRAMES)
        .and_then(|v| v.first().copied())
        .unwrap_or(1.0);
    if frames != 1.0 {
        return Err(field(
            "NumberOfFrames",
            format!("{frames} frames: caveray reads series of single-frame slices"),
        ));
    }
    let samples = int(tags::SAMPLES_PER_PIXEL, "SamplesPerPixel").unwrap_or(1);
    if samples != 1 {
        return Err(field(
            "SamplesPerPixel",
            format!("{samples} samples a pixel: caveray reads scalar (grey) images"),
        ));
    }
    let size = |tag, label: &str| -> Result<u32, DataError> {
        let n = int(tag, label)?;
        u32::try_from(n)
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| field(label, format!("{n} is not a size")))
    };
    let rows = size(tags::ROWS, "Rows")?;
    let columns = size(tags::COLUMNS, "Columns")?;
    let bits_allocated = int(tags::BITS_ALLOCATED, "BitsAllocated")?;
    if ![8, 16, 32].contains(&bits_allocated) {
        return Err(field(
            "BitsAllocated",
            format!("{bits_allocated}: caveray reads 8, 16 and 32-bit pixels"),
        ));
    }
    let bits_stored = int(tags::BITS_STORED, "BitsStored").unwrap_or(bits_allocated);
    if !(1..=bits_allocated).contains(&bits_stored) {
        return Err(field(
            "BitsStored",
            format!("{bits_stored} of {bits_allocated} allocated bits"),
        ));
    }
    let signed = match int(tags::PIXEL_REPRESENTATION, "PixelRepresentation").unwrap_or(0) {
        0 => false,
        1 => true,
        other => {
            return Err(field(
                "PixelRepresentation",
                format!("{other} is neither 0 (unsigned) nor 1 (signed)"),
            ))
        }
    };
    let orientation = floats(
        tags::IMAGE_ORIENTATION_PATIENT,
        "ImageOrientationPatient",
        6,
    )?;
    let row_axis = DVec3::new(orientation[0], orientation[1], orientation[2]);
    let column_axis = DVec3::new(orientation[3], orientation[4], orientation[5]);
    let unit = |v: DVec3| (v.length() - 1.0).abs() < 1e-3;
    if !unit(row_axis) || !unit(column_axis) || row_axis.dot(column_axis).abs() > 1e-3 {
        return Err(field(
            "ImageOrientationPatient",
            "its row and column directions are not orthogonal unit vectors".into(),
        ));
    }
    let position = floats(tags::IMAGE_POSITION_PATIENT, "ImagePositionPatient", 3)?;
    let pixel_spacing = floats(tags::PIXEL_SPACING, "PixelSpacing", 2)?;
    if pixel_spacing.iter().any(|&s| s <= 0.0) {
        return Err(field(
            "PixelSpacing",
            format!("{pixel_spacing:?} is not positive"),
        ));
    }
    let slope = optional_float(tags::RESCALE_SLOPE).unwrap_or(1.0);
    let intercept = optional_float(tags::RESCALE_INTERCEPT).unwrap_or(0.0);
    if slope == 0.0 {
        return Err(field("RescaleSlope", "zero".into()));
    }
    Ok(Slice {
        file: file.to_path_buf(),
        series: text(tags::SERIES_INSTANCE_UID),
        rows,
        columns,
        row_axis: row_axis.normalize(),
        column_axis: column_axis.normalize(),
        pixel_spacing: [pixel_spacing[0], pixel_spacing[1]],
        position: DVec3::from_slice(&position),
        bits_allocated: bits_allocated as u16,
        bits_stored: bits_stored as u16,
        signed,
        slope,
        intercept,
        thickness: optional_float(tags::SPACING_BETWEEN_SLICES)
            .or(optional_float(tags::SLICE_THICKNESS))
            .filter(|t| *t > 0.0),
        modality: text(tags::MODALITY),
        transfer_syntax: set.syntax.clone(),
    })
}

/// The stored numbers of `set`'s pixels (masked to the bits stored,
/// sign-extended), which `slice` describes.
fn decode(set: &DataSet, slice: &Slice, file_len: usize) -> Result<Vec<i64>, DataError> {
    let name = slice.file.display().to_string();
    let pixels = slice.rows as usize * slice.columns as usize;
    let width = usize::from(slice.bits_allocated / 8);
    // No codec here compresses beyond what deflate can: a slice that
    // claims more is refused before a decoder allocates for it.
    if (pixels * width) / ZLIB_MAX_RATIO > file_len {
        return Err(bad(
            &name,
            "Rows",
            format!(
                "{}x{} pixels of {} bits cannot come from a file of {file_len} bytes",
                slice.columns, slice.rows, slice.bits_allocated
            ),
        ));
    }
    let data = set
        .frame(slice.columns, slice.rows, width)
        .map_err(|why| bad(&name, "PixelData", why))?;
    if data.len() < pixels * width {
        return Err(bad(
            &name,
            "PixelData",
            format!(
                "{} bytes where {}x{} pixels of {} bits need {}",
                data.len(),
                slice.columns,
                slice.rows,
                slice.bits_allocated,
                pixels * width
            ),
        ));
    }
    let stored = u32::from(slice.bits_stored);
    let mask: u64 = if stored >= 32 {
        u64::from(u32::MAX)
    } else {
        (1u64 << stored) - 1
    };
    let sign_bit = 1u64 << (stored - 1);
    let mut values = Vec::new();
    values
        .try_reserve_exact(pixels)
        .map_err(|_| DataError::Io {
            file: name.clone(),
            source: out_of_memory(pixels as u64 * 8),
        })?;
    // Decoders hand back samples in the machine's byte order.
    values.extend(data[..pixels * width].chunks_exact(width).map(|c| {
        let mut b = [0u8; 4];
        b[..width].copy_from_slice(c);
        let raw = u64::from(u32::from_ne_bytes(b)) & mask;
        if slice.signed && raw & sign_bit != 0 {
            raw as i64 - (mask + 1) as i64
        } else {
            raw as i64
        }
    }));
    Ok(values)
}

/// A series' voxels as they are gathered slice by slice: in the type
/// the slices store where one rescale holds for all of them, else as
/// 32-bit floats, each slice's rescale applied.
enum Gathered {
    U8(Vec<u8>),
    U16(Vec<u16>),
    I16(Vec<i16>),
    F32(Vec<f32>),
}

impl Gathered {
    fn new(first: &Slice, uniform: bool, voxels: usize) -> Option<Self> {
        fn reserved<T>(n: usize) -> Option<Vec<T>> {
            let mut v = Vec::new();
            v.try_reserve_exact(n).ok()?;
            Some(v)
        }
        Some(match (uniform, first.bits_allocated, first.signed) {
            (true, 8, false) => Gathered::U8(reserved(voxels)?),
            (true, 16, false) => Gathered::U16(reserved(voxels)?),
            (true, 16, true) => Gathered::I16(reserved(voxels)?),
            _ => Gathered::F32(reserved(voxels)?),
        })
    }

    /// Appends a slice's stored numbers (masked to the bits the type
    /// holds, so each fits it), rescaled where kept as floats.
    fn push(&mut self, stored: &[i64], slice: &Slice) {
        match self {
            Gathered::U8(v) => v.extend(stored.iter().map(|&x| x as u8)),
            Gathered::U16(v) => v.extend(stored.iter().map(|&x| x as u16)),
            Gathered::I16(v) => v.extend(stored.iter().map(|&x| x as i16)),
            Gathered::F32(v) => v.extend(
                stored
                    .iter()
                    .map(|&x| (x as f64 * slice.slope + slice.intercept) as f32),
            ),
        }
    }

    fn voxels(self) -> Voxels {
        match self {
            Gathered::U8(v) => Voxels::U8(v.into()),
            Gathered::U16(v) => Voxels::U16(v.into()),
            Gathered::I16(v) => Voxels::I16(v.into()),
            Gathered::F32(v) => Voxels::F32(v.into()),
        }
    }
}

/// The volume of `slices` (one series), ordered along their normal and
/// checked to form a grid, each slice's values from `pixels`.
fn assemble(
    mut slices: Vec<Slice>,
    name: &str,
    mut pixels: impl FnMut(&Slice) -> Result<Vec<i64>, DataError>,
) -> Result<VolumeFile, DataError> {
    let Some(first) = slices.first().cloned() else {
        return Err(bad(name, "files", "no slices".into()));
    };
    for s in &slices {
        let same_plane = s.row_axis.distance(first.row_axis) < 1e-4
            && s.column_axis.distance(first.column_axis) < 1e-4;
        let differs = |what: &str, how: String| {
            bad(
                &s.file.display().to_string(),
                what,
                format!("{how}, where {} has another", first.file.display()),
            )
        };
        if !same_plane {
            return Err(differs(
                "ImageOrientationPatient",
                "the slices of the series are not parallel".into(),
            ));
        }
        if (s.rows, s.columns) != (first.rows, first.columns) {
            return Err(differs("Rows", format!("{}x{} pixels", s.columns, s.rows)));
        }
        if (s.pixel_spacing[0] - first.pixel_spacing[0]).abs() > 1e-4
            || (s.pixel_spacing[1] - first.pixel_spacing[1]).abs() > 1e-4
        {
            return Err(differs("PixelSpacing", format!("{:?}", s.pixel_spacing)));
        }
        if (s.bits_allocated, s.bits_stored, s.signed)
            != (first.bits_allocated, first.bits_stored, first.signed)
        {
            return Err(differs("BitsStored", "another pixel type".into()));
        }
    }
    let normal = first.row_axis.cross(first.column_axis);
    slices.sort_by(|a, b| normal.dot(a.position).total_cmp(&normal.dot(b.position)));
    let depth = slices.len();
    let dims = UVec3::new(first.columns, first.rows, depth as u32);
    let voxels = voxel_count(dims)?;
    let along: Vec<f64> = slices.iter().map(|s| normal.dot(s.position)).collect();
    let step = if depth > 1 {
        let mut gaps: Vec<f64> = along.windows(2).map(|p| p[1] - p[0]).collect();
        // The series' own step is its most common one: the median, which
        // a missing slice or a stray one does not move.
        gaps.sort_by(f64::total_cmp);
        let typical = gaps[gaps.len() / 2];
        for (k, pair) in along.windows(2).enumerate() {
            let gap = pair[1] - pair[0];
            let (a, b) = (slices[k].file.display(), slices[k + 1].file.display());
            if gap.abs() < 1e-6 * typical.abs().max(1.0) {
                return Err(bad(
                    name,
                    "ImagePositionPatient",
                    format!("{a} and {b} lie at the same position"),
                ));
            }
            if (gap - typical).abs() > STEP_TOLERANCE * typical {
                return Err(bad(
                    name,
                    "ImagePositionPatient",
                    format!(
                        "the slices are not evenly spaced: {gap:.3} mm between {a} and {b}, \
                         where the series steps {typical:.3} mm (a slice missing?)"
                    ),
                ));
            }
        }
        // The mean step between first and last positions, which keeps a
        // gantry tilt's in-plane shift (a sheared grid).
        (slices[depth - 1].position - slices[0].position) / (depth - 1) as f64
    } else {
        normal * first.thickness.unwrap_or(1.0)
    };
    let uniform = slices
        .iter()
        .all(|s| (s.slope, s.intercept) == (first.slope, first.intercept));
    let mut gathered =
        Gathered::new(&first, uniform, voxels as usize).ok_or_else(|| DataError::Io {
            file: name.to_string(),
            source: out_of_memory(voxels * 4),
        })?;
    for slice in &slices {
        gathered.push(&pixels(slice)?, slice);
    }
    let scaling = match gathered {
        Gathered::F32(_) => Scaling::IDENTITY,
        _ => Scaling {
            slope: first.slope as f32,
            intercept: first.intercept as f32,
        },
    };
    // DICOM's patient space is LPS: to RAS+.
    let turn = DVec3::new(-1.0, -1.0, 1.0);
    let affine = DMat4::from_cols(
        (first.row_axis * first.pixel_spacing[1] * turn).extend(0.0),
        (first.column_axis * first.pixel_spacing[0] * turn).extend(0.0),
        (step * turn).extend(0.0),
        (slices[0].position * turn).extend(1.0),
    );
    let det = glam::DMat3::from_mat4(affine).determinant();
    if !det.is_finite() || det.abs() < 1e-12 {
        return Err(bad(
            name,
            "ImagePositionPatient",
            "the slices span no volume".into(),
        ));
    }
    let dtype = match (first.bits_allocated, first.signed) {
        (8, false) => "uint8",
        (8, true) => "int8",
        (16, false) => "uint16",
        (16, true) => "int16",
        (_, false) => "uint32",
        (_, true) => "int32",
    };
    let volume = StructuredVolume::new(dims, gathered.voxels(), glam::Vec3::ZERO, glam::Vec3::ONE)?
        .with_scaling(scaling)?;
    let spacing = [
        first.pixel_spacing[1],
        first.pixel_spacing[0],
        step.length(),
    ];
    let mut details = vec![
        ("modality", Value::from(first.modality.clone())),
        (
            "transfer_syntax",
            Value::from(first.transfer_syntax.clone()),
        ),
        ("slices", Value::from(depth)),
        ("spacing", Value::from(spacing.to_vec())),
        ("bits_stored", Value::from(first.bits_stored)),
    ];
    details.push((
        "scaling",
        if uniform {
            Value::from(vec![first.slope, first.intercept])
        } else {
            Value::from("per slice")
        },
    ));
    Ok(VolumeFile {
        format: VolumeFormat::DicomSeries,
        volume,
        affine,
        anatomical: true,
        units: "mm",
        dtype,
        details,
    })
}
