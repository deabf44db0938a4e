//! The `amr` field: block-structured adaptive mesh refinement in the two
//! forms hosts send (no KHR definition exists yet). OpenCOVER's (and
//! anari-ospray's): `cellWidth` per level, `block.bounds`, `block.level`
//! and one ARRAY3D per block in `block.data`. anari-visionaray's:
//! `refinementRatio`, the same bounds and levels, one contiguous `data`,
//! `gridOrigin` and `gridSpacing`. Where both are given, `cellWidth` wins
//! over `refinementRatio` and `block.data` over `data`; the grid's origin
//! and spacing place either (scene/amr.rs samples them).

use std::sync::Arc;

use glam::IVec3;

use super::{reserve, values};
use crate::device::array::Array;
use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, VEC3};
use crate::device::types::words;
use crate::device::types::DataType as T;
use crate::scene::{AmrBlock, AmrError, AmrInput, AmrVolume, SpatialField, MAX_AMR_LEVELS};

const VALUE_TYPES: &[T] = &[T::FLOAT32, T::FLOAT64, T::UFIXED8, T::UFIXED16, T::FIXED16];

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::SPATIAL_FIELD,
    subtype: "amr",
    description: "block-structured adaptive mesh refinement: cell-centred blocks on levels of cell widths, the finest data winning where levels overlap, continuous across level boundaries",
    extensions: &[],
    params: &[
        p(
            "cellWidth",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "FLOAT32 per level: its cells' width (level 0 the finest, 1, 2, 4, ...); wins over refinementRatio",
        )
        .elements(&[T::FLOAT32]),
        p(
            "refinementRatio",
            &[T::UINT32, T::ARRAY1D],
            false,
            DefaultValue::None,
            "UINT32, or ARRAY1D of UINT32 per level: level L's cells are the ratio^L wide (entry k between levels k and k + 1); 2 where neither this nor cellWidth is set",
        )
        .elements(&[T::UINT32]),
        p(
            "block.bounds",
            &[T::ARRAY1D],
            true,
            DefaultValue::None,
            "INT32_BOX3 per block: its cells' inclusive bounds in its level's index space",
        )
        .elements(&[T::INT32_BOX3]),
        p(
            "block.level",
            &[T::ARRAY1D],
            true,
            DefaultValue::None,
            "INT32 (or UINT32) per block: its level",
        )
        .elements(&[T::INT32, T::UINT32]),
        p(
            "block.data",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "an ARRAY3D per block (any array type declared), its cells x fastest: FLOAT32, FLOAT64, UFIXED8, UFIXED16 or FIXED16; wins over data",
        )
        .elements(&[T::ARRAY3D, T::ARRAY1D, T::ARRAY, T::OBJECT]),
        p(
            "data",
            &[T::ARRAY1D],
            false,
            DefaultValue::None,
            "every block's cells, x fastest, block after block (FLOAT32, FLOAT64, UFIXED8, UFIXED16 or FIXED16)",
        )
        .elements(VALUE_TYPES),
        p(
            "gridOrigin",
            VEC3,
            false,
            DefaultValue::Floats(&[0.0, 0.0, 0.0]),
            "where cell coordinate 0 lies",
        ),
        p(
            "gridSpacing",
            VEC3,
            false,
            DefaultValue::Floats(&[1.0, 1.0, 1.0]),
            "world units per unit of cell width, per axis",
        ),
    ],
    commit: Some(commit),
};

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let bounds = r
        .array("block.bounds", block_bounds)?
        .ok_or("parameter 'block.bounds' (ARRAY1D of INT32_BOX3) is required")?;
    let levels = r
        .array("block.level", block_levels)?
        .ok_or("parameter 'block.level' (ARRAY1D of INT32) is required")?;
    if bounds.len() != levels.len() {
        return Err(format!(
            "'block.bounds' has {} blocks and 'block.level' {}; they must match",
            bounds.len(),
            levels.len()
        ));
    }
    let mut blocks = Vec::with_capacity(bounds.len());
    for (i, ((lo, hi), level)) in bounds.into_iter().zip(levels).enumerate() {
        let level = u32::try_from(level)
            .ok()
            .filter(|&l| (l as usize) < MAX_AMR_LEVELS)
            .ok_or_else(|| {
                format!(
                    "block {i}'s level is {level}; levels run from 0 to {}",
                    MAX_AMR_LEVELS - 1
                )
            })?;
        if hi.cmplt(lo).any() {
            return Err(AmrError::EmptyBlock { block: i, lo, hi }.to_string());
        }
        blocks.push(AmrBlock { lo, hi, level });
    }
    let top = blocks.iter().map(|b| b.level).max().unwrap_or(0) as usize + 1;
    let widths = match r.array("cellWidth", cell_widths)? {
        Some(w) => {
            if r.set("refinementRatio").is_some() {
                warn("both cellWidth and refinementRatio are set; cellWidth is used".into());
            }
            w
        }
        None => ratio_widths(r, top)?,
    };
    let cells = |b: &AmrBlock| b.cells();
    let origin = r.vec3("gridOrigin")?;
    let spacing = r.vec3("gridSpacing")?;
    let make = |values: Vec<f32>, blocks: Vec<AmrBlock>, widths: Vec<f32>| {
        AmrVolume::new(AmrInput {
            widths,
            blocks,
            values,
            origin,
            spacing,
        })
        .map_err(|e: AmrError| e.to_string())
    };
    // Sizes are checked (AmrVolume::new checks them again) before the
    // values are gathered.
    let needed = blocks.iter().map(cells).fold(0u64, u64::saturating_add);
    let values = if r.object("block.data").is_some() {
        if r.set("data").is_some() {
            warn("both block.data and data are set; block.data is used".into());
        }
        block_data(r, &blocks, needed)?
    } else {
        r.array("data", |a| {
            if a.len() != needed {
                return Err(AmrError::WrongLength {
                    needed,
                    got: a.len(),
                }
                .to_string());
            }
            values(a, "'data'", needed)
        })?
        .ok_or("an amr field needs 'block.data' (an array per block) or 'data'")?
    };
    let volume = make(values, blocks, widths)?;
    if volume.dropped() > 0 {
        warn(format!(
            "{} cells hold NaN or an infinity; they are read as no value",
            volume.dropped()
        ));
    }
    Ok(Some(State::ready(Arc::new(SpatialField::from(volume)))))
}

fn block_bounds(a: &Array) -> Result<Vec<(IVec3, IVec3)>, String> {
    if a.element() != T::INT32_BOX3 {
        return Err(format!(
            "'block.bounds' holds {}; it needs INT32_BOX3",
            a.element()
        ));
    }
    let n = a.len();
    let mut out = reserve(n, "block bounds")?;
    out.extend(words::<24>(a.bytes()).take(n as usize).map(|w| {
        let i = |k: usize| i32::from_ne_bytes([w[4 * k], w[4 * k + 1], w[4 * k + 2], w[4 * k + 3]]);
        (IVec3::new(i(0), i(1), i(2)), IVec3::new(i(3), i(4), i(5)))
    }));
    Ok(out)
}

fn block_levels(a: &Array) -> Result<Vec<i64>, String> {
    let n = a.len();
    let mut out = reserve(n, "block levels")?;
    match a.element() {
        T::INT32 => out.extend(
            words::<4>(a.bytes())
                .take(n as usize)
                .map(|w| i64::from(i32::from_ne_bytes(w))),
        ),
        T::UINT32 => out.extend(
            words::<4>(a.bytes())
                .take(n as usize)
                .map(|w| i64::from(u32::from_ne_bytes(w))),
        ),
        other => {
            return Err(format!(
                "'block.level' holds {other}; it needs INT32 or UINT32"
            ))
        }
    }
    Ok(out)
}

fn cell_widths(a: &Array) -> Result<Vec<f32>, String> {
    if a.element() != T::FLOAT32 {
        return Err(format!(
            "'cellWidth' holds {}; it needs FLOAT32",
            a.element()
        ));
    }
    if a.len() as usize > MAX_AMR_LEVELS {
        return Err(AmrError::TooManyLevels {
            levels: a.len() as usize,
        }
        .to_string());
    }
    Ok(words::<4>(a.bytes()).map(f32::from_ne_bytes).collect())
}

/// Widths from `refinementRatio` (one for all levels, or one per level),
/// 2 where it is unset, for `levels` levels at least.
fn ratio_widths(r: &Read<'_>, levels: usize) -> Result<Vec<f32>, String> {
    let ratios: Vec<u32> = match r.set("refinementRatio") {
        None => vec![2],
        Some(v) => match v.u64() {
            Some(n) => vec![u32::try_from(n).unwrap_or(u32::MAX)],
            None => r
                .array("refinementRatio", |a| {
                    if a.element() != T::UINT32 {
                        return Err(format!(
                            "'refinementRatio' holds {}; it needs UINT32",
                            a.element()
                        ));
                    }
                    Ok(words::<4>(a.bytes())
                        .take(MAX_AMR_LEVELS)
                        .map(u32::from_ne_bytes)
                        .collect::<Vec<u32>>())
                })?
                .unwrap_or_default(),
        },
    };
    if let Some(bad) = ratios.iter().find(|&&k| k == 0) {
        return Err(format!(
            "'refinementRatio' holds {bad}; a ratio is at least 1"
        ));
    }
    let Some(&last) = ratios.last() else {
        return Err("'refinementRatio' is empty".into());
    };
    let levels = levels.max(ratios.len());
    let mut widths = Vec::with_capacity(levels);
    let mut w = 1.0f32;
    for k in 0..levels {
        widths.push(w);
        w *= ratios.get(k).copied().unwrap_or(last) as f32;
    }
    Ok(widths)
}

/// Each block's array, checked against its bounds, gathered block after
/// block.
fn block_data(r: &Read<'_>, blocks: &[AmrBlock], needed: u64) -> Result<Vec<f32>, String> {
    let arrays = r
        .array("block.data", |a| Ok(a.objects.clone()))?
        .unwrap_or_default();
    if arrays.len() != blocks.len() {
        return Err(format!(
            "'block.data' has {} arrays and 'block.bounds' {} blocks; they must match",
            arrays.len(),
            blocks.len()
        ));
    }
    let mut out = reserve(needed, "cells")?;
    for (i, (array, block)) in arrays.iter().zip(blocks).enumerate() {
        let Some(array) = array else {
            return Err(format!("'block.data' element {i} is not an array"));
        };
        let read = array.with_array(|a| {
            let [x, y, z] = block.size();
            let dims = a.dims();
            if a.len() != block.cells() {
                return Err(format!(
                    "'block.data' element {i} is {}x{}x{}; block {i}'s bounds {} to {} hold {x}x{y}x{z} cells",
                    dims[0], dims[1], dims[2], block.lo, block.hi
                ));
            }
            out.extend(values(a, &format!("'block.data' element {i}"), block.cells())?);
            Ok(())
        });
        match read {
            Some(r) => r?,
            None => {
                return Err(format!(
                    "'block.data' element {i} is {}, not an array",
                    array.describe()
                ))
            }
        }
    }
    Ok(out)
}
