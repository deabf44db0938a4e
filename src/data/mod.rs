//! Where volumes and transfer functions come from: raw, NIfTI and NRRD files,
//! NanoVDB and FLASH files, the
//! `volumes.toml` manifest, procedural test volumes, presets and ParaView
//! color maps; triangle meshes of volumes' isosurfaces; and the formats with headers that are recognised, to be
//! refused by name rather than read as raw.

mod cells;
mod dicom;
pub mod files;
mod flash;
mod format;
mod manifest;
mod mesh;
mod metaimage;
mod nifti;
mod nrrd;
mod nvdb;
mod open;
mod orientation;
mod paraview;
mod presets;
mod procedural;
mod raw;
mod refined;
mod stored;
pub mod toml_syntax;
mod volume_file;
mod vtk;
mod vtk_mesh;

pub use cells::{cell_corners, grid_cells, tetrahedra, Cut, KUHN};
pub use dicom::{load_dicom, parse_dicom};
pub use flash::is_hdf5;
#[cfg(feature = "hdf5")]
pub use flash::{load_flash, FlashFile};
pub use format::{sniff, VolumeFormat, SNIFF_BYTES};
pub use manifest::{Manifest, ManifestEntry};
pub use mesh::{isosurface_mesh, Mesh, MeshError};
pub use metaimage::{load_metaimage, parse_metaimage};
pub use nifti::{load_nifti, parse_nifti, parse_nifti_header, Nifti, NiftiHeader};
pub use nrrd::{load_nrrd, parse_nrrd, parse_nrrd_header, Nrrd, NrrdHeader};
pub use nvdb::{is_nvdb, load_nvdb, nvdb_entries, parse_nvdb, NvdbEntry, NvdbFile};
pub use open::load_volume_file;
pub use orientation::{known_orientation, Orientation};
pub use paraview::{load_paraview, parse_paraview};
pub use presets::{preset, PRESETS};
pub use procedural::{concentric_shells, marschner_lobb, shepp_logan, solid_box};
pub use raw::{load_raw, parse_raw, raw_size, VoxelType};
pub use refined::{finest_grid, refined, smooth_waves};
pub use volume_file::VolumeFile;
pub use vtk::{load_vtk, parse_vtk};
pub use vtk_mesh::{is_vtk_mesh, load_vtk_mesh, parse_vtk_mesh, MeshFile};

use thiserror::Error;

use crate::scene::{TransferFunctionError, VolumeError};

#[derive(Debug, Error)]
pub enum DataError {
    #[error("{file}: {source}")]
    Io {
        file: String,
        source: std::io::Error,
    },
    #[error("{file} has {actual} bytes, but {dims} {dtype} needs {expected} bytes")]
    FileSize {
        file: String,
        dims: String,
        dtype: &'static str,
        expected: u64,
        actual: u64,
    },
    #[error(
        "a volume of {dims} voxels is more than caveray loads ({} voxels at most)",
        crate::scene::MAX_VOXELS
    )]
    TooManyVoxels { dims: String },
    #[error("{file}: checksum mismatch: sha256 is {actual}, the manifest says {expected}")]
    Checksum {
        file: String,
        expected: String,
        actual: String,
    },
    #[error("{file}: {message}")]
    Manifest { file: String, message: String },
    #[error("no volume named '{name}' in {manifest} (known: {known})")]
    UnknownVolume {
        name: String,
        manifest: String,
        known: String,
    },
    #[error("no volume manifest found (tried {tried})")]
    NoManifest { tried: String },
    #[error("unknown voxel type '{0}' (expected uint8, uint16 or float32)")]
    VoxelType(String),
    #[error("{file}: not a ParaView color map: {message}")]
    ParaView { file: String, message: String },
    #[error("unknown transfer function preset '{name}' (presets: {known})")]
    UnknownPreset { name: String, known: String },
    #[error("{file}: {field}: {why}")]
    Header {
        file: String,
        field: String,
        why: String,
    },
    #[error(transparent)]
    Volume(#[from] VolumeError),
    #[error(transparent)]
    TransferFunction(#[from] TransferFunctionError),
}

/// A header refused: the file, the field at fault and why.
fn bad(file: &str, field: &str, why: String) -> DataError {
    DataError::Header {
        file: file.to_string(),
        field: field.to_string(),
        why,
    }
}
