//! Opening a volume file with a header, whatever its format: callers that
//! take "a scan" go through [`load_volume_file`], so that a new reader is
//! one arm of it.

use std::path::Path;

use serde_json::Value;

use super::format::VolumeFormat;
use super::volume_file::VolumeFile;
use super::{dicom, load_nifti, load_nrrd, metaimage, vtk, DataError};

impl VolumeFormat {
    /// Whether caveray reads this format (the others are recognised only
    /// to be refused by name).
    pub fn readable(self) -> bool {
        !matches!(self, VolumeFormat::Gzip)
    }
}

/// Reads the volume at `path`, a file (or a DICOM series' folder) in one
/// of the [`VolumeFormat::readable`] formats.
pub fn load_volume_file(path: &Path) -> Result<VolumeFile, DataError> {
    let format = VolumeFormat::of(path).filter(|f| f.readable());
    match format {
        Some(VolumeFormat::Nifti) => {
            let nifti = load_nifti(path)?;
            let h = nifti.header;
            Ok(VolumeFile {
                format: VolumeFormat::Nifti,
                volume: nifti.volume,
                affine: h.affine,
                // Scanner and template spaces are RAS+.
                anatomical: true,
                units: h.units,
                dtype: h.dtype,
                details: vec![
                    ("version", Value::from(h.version)),
                    ("spacing", Value::from(h.spacing.to_array().to_vec())),
                    ("placed_by", Value::from(h.placed_by)),
                    ("scaling", Value::from(vec![h.slope, h.intercept])),
                ],
            })
        }
        Some(VolumeFormat::Nrrd) => {
            let nrrd = load_nrrd(path)?;
            let h = nrrd.header;
            Ok(VolumeFile {
                format: VolumeFormat::Nrrd,
                volume: nrrd.volume,
                affine: h.affine,
                anatomical: h.anatomical,
                units: h.units,
                dtype: h.dtype,
                details: vec![
                    ("encoding", Value::from(h.encoding)),
                    ("space", Value::from(h.space)),
                ],
            })
        }
        Some(VolumeFormat::MetaImage) => metaimage::load_metaimage(path),
        Some(VolumeFormat::VtkLegacy | VolumeFormat::VtkXml) => vtk::load_vtk(path),
        Some(VolumeFormat::Dicom | VolumeFormat::DicomSeries) => dicom::load_dicom(path),
        Some(VolumeFormat::Gzip) | None => Err(DataError::Header {
            file: path.display().to_string(),
            field: "format".into(),
            why:
                "not a volume format caveray reads (NIfTI, NRRD, MetaImage, VTK image data, DICOM)"
                    .into(),
        }),
    }
}
