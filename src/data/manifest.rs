use std::path::{Path, PathBuf};

use glam::{UVec3, Vec3};
use serde::Deserialize;
use sha2::{Digest, Sha256};

use super::files;
use super::orientation::{known_orientation, Orientation};
use super::raw::{decode_raw, read_raw};
use super::toml_syntax::{line_column, syntax_error};
use super::{DataError, VoxelType};
use crate::geometry::VolumeAxis;
use crate::scene::StructuredVolume;

/// A `volumes.toml` manifest: named raw volumes beside it.
#[derive(Debug)]
pub struct Manifest {
    path: PathBuf,
    volumes: Vec<ManifestEntry>,
}

#[derive(Clone, Debug, Deserialize)]
pub struct ManifestEntry {
    pub name: String,
    pub file: String,
    pub dims: [u32; 3],
    pub dtype: String,
    pub spacing: [f32; 3],
    #[serde(default)]
    pub quality: String,
    #[serde(default)]
    pub category: String,
    #[serde(default)]
    pub small: bool,
    pub sha256: Option<String>,
    #[serde(default)]
    pub source: String,
    /// The grid axis that points to the top of the object (a CT series
    /// stored crown first has -z), if the data set says.
    #[serde(default)]
    pub up: Option<VolumeAxis>,
    /// The grid axis the object's front faces, if the data set says.
    #[serde(default)]
    pub front: Option<VolumeAxis>,
}

impl ManifestEntry {
    /// The axes the entry states; if it states neither, those of the
    /// published data set its hash names.
    pub fn orientation(&self) -> Orientation {
        match (self.up, self.front, self.sha256.as_deref()) {
            (None, None, Some(sha)) => known_orientation(sha),
            (up, front, _) => Orientation { up, front },
        }
    }
}

#[derive(Deserialize)]
struct RawManifest {
    volume: Vec<ManifestEntry>,
}

impl Manifest {
    pub fn load(path: &Path) -> Result<Self, DataError> {
        let file = path.display().to_string();
        let text = files::read_text(path, files::TEXT_LIMIT)
            .map_err(|source| DataError::Io { file, source })?;
        Self::parse(&text, path)
    }

    /// A manifest from its text; `path` names it and anchors its files.
    pub fn parse(text: &str, path: &Path) -> Result<Self, DataError> {
        let raw: RawManifest = toml::from_str(text).map_err(|e| {
            // Text that is not TOML is placed at its cause; TOML that is
            // not a manifest, where toml found the wrong field.
            let (line, column, message) = match syntax_error(text) {
                Some(s) => (s.line, s.column, s.message),
                None => {
                    let (line, column) = line_column(text, e.span().map_or(0, |s| s.start));
                    (line, column, e.message().to_string())
                }
            };
            DataError::Manifest {
                file: format!("{}:{line}:{column}", path.display()),
                message,
            }
        })?;
        Ok(Self {
            path: path.to_path_buf(),
            volumes: raw.volume,
        })
    }

    /// The manifest to use: `explicit` if given, else
    /// `$CAVERAY_DATA/volumes.toml`, else the first of the caller's
    /// `fallbacks` that exists (where a tool keeps its data is the tool's
    /// business, not the library's).
    pub fn locate(explicit: Option<&Path>, fallbacks: &[PathBuf]) -> Result<Self, DataError> {
        if let Some(path) = explicit {
            return Self::load(path);
        }
        let mut tried = Vec::new();
        let env = std::env::var_os("CAVERAY_DATA").map(|d| PathBuf::from(d).join("volumes.toml"));
        for candidate in env.into_iter().chain(fallbacks.iter().cloned()) {
            if candidate.is_file() {
                return Self::load(&candidate);
            }
            tried.push(candidate.display().to_string());
        }
        Err(DataError::NoManifest {
            tried: tried.join(", "),
        })
    }

    pub fn entries(&self) -> &[ManifestEntry] {
        &self.volumes
    }

    pub fn find(&self, name: &str) -> Result<&ManifestEntry, DataError> {
        self.volumes
            .iter()
            .find(|v| v.name.eq_ignore_ascii_case(name))
            .ok_or_else(|| DataError::UnknownVolume {
                name: name.to_string(),
                manifest: self.path.display().to_string(),
                known: self
                    .volumes
                    .iter()
                    .map(|v| v.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// Path of an entry's raw file (relative to the manifest).
    pub fn file_of(&self, entry: &ManifestEntry) -> PathBuf {
        self.path
            .parent()
            .unwrap_or(Path::new("."))
            .join(&entry.file)
    }

    /// Loads a named volume, checking its size and (if the manifest gives
    /// one) its SHA-256 before use.
    pub fn load_volume(&self, name: &str) -> Result<StructuredVolume, DataError> {
        let entry = self.find(name)?;
        let path = self.file_of(entry);
        let dims = UVec3::from_array(entry.dims);
        let dtype = VoxelType::parse(&entry.dtype)?;
        let bytes = read_raw(&path, dims, dtype)?;
        if let Some(expected) = &entry.sha256 {
            let actual: String = Sha256::digest(&bytes)
                .iter()
                .map(|b| format!("{b:02x}"))
                .collect();
            if !actual.eq_ignore_ascii_case(expected) {
                return Err(DataError::Checksum {
                    file: path.display().to_string(),
                    expected: expected.clone(),
                    actual,
                });
            }
        }
        decode_raw(&bytes, dims, dtype, Vec3::from_array(entry.spacing))
    }
}
