//! A series' slices, from however many files, checked to form one grid
//! and gathered into a volume.

use std::path::PathBuf;

use glam::{DMat3, DMat4, DVec2, DVec3, UVec3, Vec3};
use rayon::prelude::*;
use serde_json::Value;

use super::super::stored::{out_of_memory, voxel_count, Stored};
use super::super::volume_file::VolumeFile;
use super::super::{bad, DataError};
use super::VolumeFormat;
use crate::scene::{Scaling, StructuredVolume, Voxels};

/// How far apart two slices' steps may be, as a fraction of the series'
/// typical step, before the series counts as unevenly spaced (a slice
/// missing, or two series mixed): DICOM writes positions as decimal
/// strings of 16 characters at most, which round well inside this.
const STEP_TOLERANCE: f64 = 0.05;

/// What one slice (a file, or a frame of one) says, read before its
/// pixels.
#[derive(Clone, Debug)]
pub(super) struct Slice {
    pub file: PathBuf,
    pub frame: u32,
    pub series: String,
    pub rows: u32,
    pub columns: u32,
    /// Unit vectors along a row (increasing column) and along a column
    /// (increasing row), in LPS.
    pub row_axis: DVec3,
    pub column_axis: DVec3,
    /// Between rows, between columns (PixelSpacing's order).
    pub pixel_spacing: DVec2,
    pub position: DVec3,
    /// The type of BitsAllocated and PixelRepresentation.
    pub stored: Stored,
    pub bits_stored: u16,
    pub slope: f64,
    pub intercept: f64,
    pub thickness: Option<f64>,
    pub modality: String,
    pub transfer_syntax: String,
}

impl Slice {
    /// The file, and the frame where it is not the file's first.
    fn label(&self) -> String {
        match self.frame {
            0 => self.file.display().to_string(),
            k => format!("{} (frame {})", self.file.display(), k + 1),
        }
    }

    /// The bytes of one frame as decoded.
    pub fn frame_len(&self) -> usize {
        self.rows as usize * self.columns as usize * self.stored.bytes() as usize
    }

    /// This slice's frame of its file's decoded frames (checked to hold
    /// them all).
    fn frame_in<'a>(&self, frames: &'a [u8]) -> &'a [u8] {
        let at = self.frame as usize * self.frame_len();
        frames.get(at..at + self.frame_len()).unwrap_or_default()
    }

    /// Appends `frame` (decoded samples in the machine's byte order) to
    /// `out` as numbers of the same width, masked to the bits stored and
    /// sign-extended.
    fn normalize(&self, frame: &[u8], out: &mut Vec<u8>) {
        let width = self.stored.bytes() as usize;
        let bits = u32::from(self.bits_stored);
        let mask = u32::MAX >> (32 - bits);
        let signed = matches!(self.stored, Stored::I8 | Stored::I16 | Stored::I32);
        for sample in frame.chunks_exact(width) {
            let mut b = [0u8; 4];
            b[..width].copy_from_slice(sample);
            let raw = u32::from_ne_bytes(b) & mask;
            let value = match signed && (raw >> (bits - 1)) & 1 == 1 {
                true => raw | !mask,
                false => raw,
            };
            out.extend_from_slice(&value.to_ne_bytes()[..width]);
        }
    }
}

/// The volume of `slices` (one series), ordered along their normal and
/// checked to form a grid; `decode` gives the decoded frames of a slice's
/// file, each file's once.
pub(super) fn assemble(
    mut slices: Vec<Slice>,
    name: &str,
    decode: impl Fn(&Slice) -> Result<Vec<u8>, DataError> + Sync,
) -> Result<VolumeFile, DataError> {
    let Some(first) = slices.first().cloned() else {
        return Err(bad(name, "files", "no slices".into()));
    };
    for s in &slices {
        let differs = |field: &str, how: &str| {
            let why = format!("{how}, where {} has another", first.label());
            Err(bad(&s.label(), field, why))
        };
        let turned =
            s.row_axis.distance(first.row_axis) + s.column_axis.distance(first.column_axis);
        if turned > 1e-4 {
            return differs(
                "ImageOrientationPatient",
                "the slices of the series are not parallel",
            );
        }
        if (s.rows, s.columns) != (first.rows, first.columns) {
            return differs("Rows", "another size");
        }
        if s.pixel_spacing.distance(first.pixel_spacing) > 1e-4 {
            return differs("PixelSpacing", "another spacing");
        }
        if (s.stored, s.bits_stored) != (first.stored, first.bits_stored) {
            return differs("BitsStored", "another pixel type");
        }
    }
    let normal = first.row_axis.cross(first.column_axis);
    slices.sort_by(|a, b| normal.dot(a.position).total_cmp(&normal.dot(b.position)));
    let depth = slices.len();
    let dims = UVec3::new(first.columns, first.rows, depth as u32);
    let along: Vec<f64> = slices.iter().map(|s| normal.dot(s.position)).collect();
    let mut gaps: Vec<f64> = along.windows(2).map(|p| p[1] - p[0]).collect();
    // The series' own step is its most common one: the median, which a
    // missing slice or a stray one does not move.
    gaps.sort_by(f64::total_cmp);
    let typical = gaps.get(gaps.len() / 2).copied().unwrap_or(1.0);
    for (k, pair) in along.windows(2).enumerate() {
        let gap = pair[1] - pair[0];
        let (a, b) = (slices[k].label(), slices[k + 1].label());
        let why = if gap.abs() < 1e-6 * typical.abs().max(1.0) {
            format!("{a} and {b} lie at the same position")
        } else if (gap - typical).abs() > STEP_TOLERANCE * typical {
            format!(
                "the slices are not evenly spaced: {gap:.3} mm between {a} and {b}, \
                 where the series steps {typical:.3} mm (a slice missing?)"
            )
        } else {
            continue;
        };
        return Err(bad(name, "ImagePositionPatient", why));
    }
    // The mean step between first and last positions, which keeps a gantry
    // tilt's in-plane shift (a sheared grid).
    let step = match depth {
        1 => normal * first.thickness.unwrap_or(1.0),
        _ => (slices[depth - 1].position - slices[0].position) / (depth - 1) as f64,
    };
    // DICOM's patient space is LPS: to RAS+.
    let turn = DVec3::new(-1.0, -1.0, 1.0);
    let affine = DMat4::from_cols(
        (first.row_axis * first.pixel_spacing.y * turn).extend(0.0),
        (first.column_axis * first.pixel_spacing.x * turn).extend(0.0),
        (step * turn).extend(0.0),
        (slices[0].position * turn).extend(1.0),
    );
    let det = DMat3::from_mat4(affine).determinant();
    if !det.is_finite() || det.abs() < 1e-12 {
        return Err(bad(
            name,
            "ImagePositionPatient",
            "the slices span no volume".into(),
        ));
    }
    let n = voxel_count(dims)? as usize;
    let rescale = |s: &Slice| (s.slope, s.intercept);
    let uniform = slices.iter().all(|s| rescale(s) == rescale(&first));
    fn native<T: bytemuck::Pod>(_: &Slice, raw: &[u8]) -> Vec<T> {
        bytemuck::pod_collect_to_vec(raw)
    }
    let voxels = match (uniform, first.stored) {
        (true, Stored::U8) => Voxels::U8(gather(&slices, n, name, &decode, native)?.into()),
        (true, Stored::U16) => Voxels::U16(gather(&slices, n, name, &decode, native)?.into()),
        (true, Stored::I16) => Voxels::I16(gather(&slices, n, name, &decode, native)?.into()),
        // Each slice's own rescale, to 32-bit floats.
        _ => Voxels::F32(
            gather(&slices, n, name, &decode, |s, raw| {
                let big = cfg!(target_endian = "big");
                s.stored.decode(raw, big, rescale(s)).unwrap_or_default()
            })?
            .into(),
        ),
    };
    let scaling = match voxels {
        Voxels::F32(_) => Scaling::IDENTITY,
        _ => Scaling {
            slope: first.slope as f32,
            intercept: first.intercept as f32,
        },
    };
    let volume =
        StructuredVolume::new(dims, voxels, Vec3::ZERO, Vec3::ONE)?.with_scaling(scaling)?;
    let spacing = vec![first.pixel_spacing.y, first.pixel_spacing.x, step.length()];
    let scaling = match uniform {
        true => Value::from(vec![first.slope, first.intercept]),
        false => Value::from("per slice"),
    };
    let (modality, syntax) = (first.modality.as_str(), first.transfer_syntax.as_str());
    let details = vec![
        ("modality", modality.into()),
        ("transfer_syntax", syntax.into()),
        ("slices", depth.into()),
        ("spacing", spacing.into()),
        ("bits_stored", first.bits_stored.into()),
        ("scaling", scaling),
    ];
    Ok(VolumeFile {
        format: VolumeFormat::DicomSeries,
        volume,
        affine,
        anatomical: true,
        units: "mm",
        dtype: first.stored.name(),
        details,
    })
}

/// The series' voxels in type `T`, each slice's frame normalized and
/// turned by `turn`, into one buffer reserved first: held once. Files are
/// decoded in parallel, a run of slices from one file (a multi-frame
/// file's frames, which follow one another once sorted) once.
fn gather<T: bytemuck::Pod + Send>(
    slices: &[Slice],
    n: usize,
    name: &str,
    decode: &(impl Fn(&Slice) -> Result<Vec<u8>, DataError> + Sync),
    turn: impl Fn(&Slice, &[u8]) -> Vec<T> + Sync,
) -> Result<Vec<T>, DataError> {
    let mut voxels = Vec::new();
    let source = out_of_memory((n * std::mem::size_of::<T>()) as u64);
    let io = DataError::Io {
        file: name.into(),
        source,
    };
    voxels.try_reserve_exact(n).map_err(|_| io)?;
    voxels.resize(n, T::zeroed());
    let per_slice = n / slices.len();
    let mut runs = Vec::new();
    let mut rest = voxels.as_mut_slice();
    for run in slices.chunk_by(|a, b| a.file == b.file) {
        let (mine, others) = rest.split_at_mut(run.len() * per_slice);
        runs.push((run, mine));
        rest = others;
    }
    runs.into_par_iter().try_for_each(|(run, out)| {
        let frames = decode(&run[0])?;
        let mut raw = Vec::new();
        for (slice, out) in run.iter().zip(out.chunks_exact_mut(per_slice)) {
            raw.clear();
            slice.normalize(slice.frame_in(&frames), &mut raw);
            let values = turn(slice, &raw);
            if values.len() != out.len() {
                let why = format!("{} of {} pixels decoded", values.len(), out.len());
                return Err(bad(&slice.label(), "PixelData", why));
            }
            out.copy_from_slice(&values);
        }
        Ok(())
    })?;
    Ok(voxels)
}
