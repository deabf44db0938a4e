//! A spatial field as renderers march it: a structured grid, or an
//! unstructured mesh, an AMR field or a NanoVDB grid with the lattice
//! its rays march in.

use std::sync::Arc;

use glam::{UVec3, Vec3};

use super::amr::AmrVolume;
use super::nanovdb::NanoVdbGrid;
use super::storage::Lent;
use super::unstructured::UnstructuredVolume;
use super::volume::{Filter, StructuredVolume};

/// What a volume samples. Both kinds have a lattice: a structured grid's
/// own vertices, or for a mesh a lattice over its box spaced by its
/// typical cell edge (unstructured.rs). Marches, steps and empty-space
/// bricks are laid on it; only the sample differs.
#[derive(Clone, Debug, PartialEq)]
pub enum SpatialField {
    Structured(StructuredVolume),
    Unstructured(UnstructuredVolume),
    Amr(AmrVolume),
    NanoVdb(NanoVdbGrid),
}

impl From<NanoVdbGrid> for SpatialField {
    fn from(v: NanoVdbGrid) -> Self {
        SpatialField::NanoVdb(v)
    }
}

impl From<AmrVolume> for SpatialField {
    fn from(v: AmrVolume) -> Self {
        SpatialField::Amr(v)
    }
}

impl From<StructuredVolume> for SpatialField {
    fn from(v: StructuredVolume) -> Self {
        SpatialField::Structured(v)
    }
}

impl From<UnstructuredVolume> for SpatialField {
    fn from(v: UnstructuredVolume) -> Self {
        SpatialField::Unstructured(v)
    }
}

impl SpatialField {
    pub fn structured(&self) -> Option<&StructuredVolume> {
        match self {
            SpatialField::Structured(v) => Some(v),
            _ => None,
        }
    }

    pub fn unstructured(&self) -> Option<&UnstructuredVolume> {
        match self {
            SpatialField::Unstructured(m) => Some(m),
            _ => None,
        }
    }

    pub fn amr(&self) -> Option<&AmrVolume> {
        match self {
            SpatialField::Amr(a) => Some(a),
            _ => None,
        }
    }

    pub fn nanovdb(&self) -> Option<&NanoVdbGrid> {
        match self {
            SpatialField::NanoVdb(g) => Some(g),
            _ => None,
        }
    }

    /// What a brick of the lattice (vertices `lo..=hi`) holds: a grid's
    /// voxels there, or a mesh's cells whose boxes reach that box.
    pub fn cropped(&self, lo: UVec3, hi: UVec3) -> Result<SpatialField, String> {
        match self {
            SpatialField::Structured(v) => {
                v.cropped(lo, hi).map(Into::into).map_err(|e| e.to_string())
            }
            SpatialField::Unstructured(m) => {
                let (dims, spacing) = m.lattice();
                if lo.cmpgt(hi).any() || hi.cmpge(dims).any() {
                    return Err(format!(
                        "vertices {lo} to {hi} are not a box of the mesh's {dims} lattice"
                    ));
                }
                let origin = m.bounds().0;
                m.cells_within(
                    origin + lo.as_vec3() * spacing,
                    origin + hi.as_vec3() * spacing,
                )
                .map(Into::into)
                .map_err(|e| match e {
                    super::UnstructuredError::NoCells => {
                        "no cell of the mesh reaches it".to_string()
                    }
                    e => e.to_string(),
                })
            }
            SpatialField::Amr(a) => {
                let dims = a.lattice().0;
                if lo.cmpgt(hi).any() || hi.cmpge(dims).any() {
                    return Err(format!(
                        "vertices {lo} to {hi} are not a box of the AMR field's {dims} lattice"
                    ));
                }
                let (origin, step) = (a.amr_bounds().0, a.lattice_step());
                a.cells_within(origin + lo.as_vec3() * step, origin + hi.as_vec3() * step)
                    .map(Into::into)
                    .map_err(|e| e.to_string())
            }
            SpatialField::NanoVdb(g) => g.window_of(lo, hi).map(Into::into),
        }
    }

    /// Lattice vertices per axis.
    pub fn dims(&self) -> UVec3 {
        match self {
            SpatialField::Structured(v) => v.dims(),
            SpatialField::Unstructured(m) => m.lattice().0,
            SpatialField::Amr(a) => a.lattice().0,
            SpatialField::NanoVdb(g) => g.lattice().0,
        }
    }

    /// Where lattice vertex (0, 0, 0) lies.
    pub fn origin(&self) -> Vec3 {
        match self {
            SpatialField::Structured(v) => v.origin(),
            SpatialField::Unstructured(m) => m.bounds().0,
            SpatialField::Amr(a) => a.bounds().0,
            SpatialField::NanoVdb(g) => g.bounds().0,
        }
    }

    /// Distance between lattice vertices, per axis.
    pub fn spacing(&self) -> Vec3 {
        match self {
            SpatialField::Structured(v) => v.spacing(),
            SpatialField::Unstructured(m) => m.lattice().1,
            SpatialField::Amr(a) => a.lattice().1,
            SpatialField::NanoVdb(g) => g.lattice().1,
        }
    }

    /// The cell edges that set the step: a grid's spacing, a mesh's
    /// typical edge on every axis.
    pub fn cell_edges(&self) -> Vec3 {
        match self {
            SpatialField::Structured(v) => v.spacing(),
            SpatialField::Unstructured(m) => Vec3::splat(m.edge()),
            SpatialField::Amr(a) => a.finest_cell(),
            SpatialField::NanoVdb(g) => g.voxel_size(),
        }
    }

    /// A grid's or a NanoVDB grid's filter; a mesh interpolates inside
    /// each cell, an AMR field between cell centres (Linear).
    pub fn filter(&self) -> Filter {
        match self {
            SpatialField::Structured(v) => v.filter(),
            SpatialField::Unstructured(_) | SpatialField::Amr(_) => Filter::Linear,
            SpatialField::NanoVdb(g) => g.filter(),
        }
    }

    pub fn value_range(&self) -> (f32, f32) {
        match self {
            SpatialField::Structured(v) => v.value_range(),
            SpatialField::Unstructured(m) => m.value_range(),
            SpatialField::Amr(a) => a.value_range(),
            SpatialField::NanoVdb(g) => g.value_range(),
        }
    }

    /// The box the lattice covers (a mesh's or an AMR field's own box).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            SpatialField::Structured(v) => v.bounds(),
            SpatialField::Unstructured(m) => m.bounds(),
            SpatialField::Amr(a) => a.bounds(),
            SpatialField::NanoVdb(g) => g.bounds(),
        }
    }

    /// The host's memory a structured grid reads in place, if it does.
    pub fn lender(&self) -> Option<&Arc<Lent>> {
        match self {
            SpatialField::Structured(v) => v.voxels().lender(),
            _ => None,
        }
    }

    /// Bytes of the numbers held by the device: a grid read in place
    /// from the host's memory holds none until the host takes its memory
    /// back (then its copy).
    pub fn held_bytes(&self) -> u64 {
        match self {
            SpatialField::Structured(v) if v.voxels().in_place() => 0,
            other => other.bytes(),
        }
    }

    /// Bytes of the numbers.
    pub fn bytes(&self) -> u64 {
        match self {
            SpatialField::Structured(v) => v.voxels().bytes(),
            SpatialField::Unstructured(m) => m.bytes(),
            SpatialField::Amr(a) => a.bytes(),
            SpatialField::NanoVdb(g) => g.bytes(),
        }
    }
}
