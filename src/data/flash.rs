//! FLASH checkpoint and plot files (HDF5): block-structured AMR as the
//! FLASH code writes it, read into an [`AmrVolume`] with every block,
//! parents included, as OpenCOVER's plug-in sends them.
//!
//! What is read (FLASH 3 and 4's layout): `refine level` (1 the
//! coarsest, per block), `bounding box` (per block, per axis, its lower
//! and upper face) and each variable as a dataset of shape (blocks, nzb,
//! nyb, nxb), x fastest. Level L counts from the finest (L = max refine
//! level - refine level) and its cells are 2^L finest cells wide; a
//! block's bounds are its lower face's distance from the domain's, in
//! its own cells. The finest cell's size per axis becomes the grid's
//! spacing and the domain's lower corner its origin.
//!
//! HDF5 is a C library many CAVE hosts link themselves (OpenCOVER's
//! FLASH reader does): two copies in one process may clash, so the
//! reader is built only with the `hdf5` feature, which the `caveray`
//! tool's builds turn on and the ANARI library that hosts load leaves
//! off.

#[cfg(feature = "hdf5")]
use std::path::Path;

#[cfg(feature = "hdf5")]
use glam::{DVec3, IVec3};

#[cfg(feature = "hdf5")]
use super::{bad, DataError};
#[cfg(feature = "hdf5")]
use crate::scene::{AmrBlock, AmrInput, AmrVolume};

/// What a FLASH file held and what was read of it.
#[cfg(feature = "hdf5")]
pub struct FlashFile {
    pub amr: AmrVolume,
    /// The variable read, and every variable the file has.
    pub variable: String,
    pub variables: Vec<String>,
    /// Cells per block along x, y, z.
    pub block_cells: [usize; 3],
    /// Blocks FLASH marks as leaves (node type 1), if it says.
    pub leaves: Option<usize>,
}

/// HDF5's signature, at the start of a file without a user block.
const SIGNATURE: &[u8] = b"\x89HDF\r\n\x1a\n";

/// Whether `head` (a file's first bytes) is an HDF5 file's.
pub fn is_hdf5(head: &[u8]) -> bool {
    head.starts_with(SIGNATURE)
}

#[cfg(feature = "hdf5")]
fn h5<'a>(file: &'a str, what: &'a str) -> impl Fn(hdf5_metno::Error) -> DataError + 'a {
    move |e| bad(file, what, e.to_string())
}

#[cfg(feature = "hdf5")]
/// Reads FLASH file `path`, sampling `variable` (the first variable,
/// `dens` where there is one, when `None`).
pub fn load_flash(path: &Path, variable: Option<&str>) -> Result<FlashFile, DataError> {
    let name = path.display().to_string();
    let file = hdf5_metno::File::open(path).map_err(h5(&name, "HDF5"))?;
    let levels: Vec<i32> = file
        .dataset("refine level")
        .and_then(|d| d.read_raw::<i32>())
        .map_err(h5(&name, "refine level"))?;
    let n = levels.len();
    if n == 0 {
        return Err(bad(&name, "refine level", "the file holds no block".into()));
    }
    let boxes = file
        .dataset("bounding box")
        .map_err(h5(&name, "bounding box"))?;
    let shape = boxes.shape();
    if shape != [n, 3, 2] {
        return Err(bad(
            &name,
            "bounding box",
            format!(
                "shape {shape:?}; caveray reads three-dimensional FLASH files, whose boxes are [{n}, 3, 2]"
            ),
        ));
    }
    let boxes: Vec<f64> = boxes.read_raw().map_err(h5(&name, "bounding box"))?;
    // Variables: every dataset shaped (blocks, nz, ny, nx).
    let mut variables = Vec::new();
    for member in file.member_names().map_err(h5(&name, "HDF5"))? {
        if let Ok(d) = file.dataset(&member) {
            let s = d.shape();
            if s.len() == 4 && s[0] == n {
                variables.push(member);
            }
        }
    }
    variables.sort();
    let chosen = match variable {
        Some(v) if variables.iter().any(|x| x == v) => v.to_string(),
        Some(v) => {
            return Err(bad(
                &name,
                v,
                format!("no such variable; the file has {}", variables.join(", ")),
            ))
        }
        None => variables
            .iter()
            .find(|v| v.as_str() == "dens")
            .or(variables.first())
            .cloned()
            .ok_or_else(|| {
                bad(
                    &name,
                    "variables",
                    "the file has no per-block variable".into(),
                )
            })?,
    };
    let data = file.dataset(&chosen).map_err(h5(&name, &chosen))?;
    let s = data.shape();
    let block_cells = [s[3], s[2], s[1]];
    if block_cells.iter().any(|&c| c == 0 || c > 4096) {
        return Err(bad(
            &name,
            &chosen,
            format!("blocks of {block_cells:?} cells"),
        ));
    }
    let values: Vec<f32> = data.read_raw().map_err(h5(&name, &chosen))?;
    let leaves = file
        .dataset("node type")
        .and_then(|d| d.read_raw::<i32>())
        .ok()
        .map(|t| t.iter().filter(|&&t| t == 1).count());

    let top = *levels.iter().max().expect("n > 0");
    let bottom = *levels.iter().min().expect("n > 0");
    if bottom < 1 || top - bottom >= 31 {
        return Err(bad(
            &name,
            "refine level",
            format!("levels {bottom} to {top}; caveray reads 1 and up, at most 31 apart"),
        ));
    }
    let cells = DVec3::new(
        block_cells[0] as f64,
        block_cells[1] as f64,
        block_cells[2] as f64,
    );
    let lo_of = |b: usize| DVec3::new(boxes[6 * b], boxes[6 * b + 2], boxes[6 * b + 4]);
    let hi_of = |b: usize| DVec3::new(boxes[6 * b + 1], boxes[6 * b + 3], boxes[6 * b + 5]);
    // The finest cell, from a finest block; the domain's lower corner.
    let finest = (0..n)
        .find(|&b| levels[b] == top)
        .expect("the top level has a block");
    let h = (hi_of(finest) - lo_of(finest)) / cells;
    if !(h.is_finite() && h.cmpgt(DVec3::ZERO).all()) {
        return Err(bad(
            &name,
            "bounding box",
            format!("block {finest}'s box gives cells {h} wide"),
        ));
    }
    let origin = (0..n).map(lo_of).fold(DVec3::INFINITY, DVec3::min);
    let mut blocks = Vec::with_capacity(n);
    for (b, &refine) in levels.iter().enumerate() {
        let level = (top - refine) as u32;
        let w = h * f64::from(1u32 << level);
        let lo = ((lo_of(b) - origin) / w).round();
        if !lo.is_finite() || lo.abs().max_element() > f64::from(1 << 24) {
            return Err(bad(
                &name,
                "bounding box",
                format!("block {b} lies {lo} cells from the domain's corner"),
            ));
        }
        let lo = lo.as_ivec3();
        let hi = lo + IVec3::new(s[3] as i32, s[2] as i32, s[1] as i32) - IVec3::ONE;
        blocks.push(AmrBlock { lo, hi, level });
    }
    let amr = AmrVolume::new(AmrInput {
        widths: (0..=(top - bottom) as u32)
            .map(|l| (1u32 << l) as f32)
            .collect(),
        blocks,
        values,
        origin: origin.as_vec3(),
        spacing: h.as_vec3(),
    })
    .map_err(|e| bad(&name, &chosen, e.to_string()))?;
    Ok(FlashFile {
        amr,
        variable: chosen,
        variables,
        block_cells,
        leaves,
    })
}
