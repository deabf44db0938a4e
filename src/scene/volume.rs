use std::sync::{Arc, OnceLock};

use glam::{UVec3, Vec3};
use thiserror::Error;

use super::storage::{Buf, Lent};

/// Voxel values as stored, in their own type: the volume's [`Scaling`]
/// makes them values.
#[derive(Clone, Debug, PartialEq)]
pub enum Voxels {
    U8(Buf<u8>),
    U16(Buf<u16>),
    I16(Buf<i16>),
    F32(Buf<f32>),
}

impl Voxels {
    pub fn len(&self) -> usize {
        match self {
            Voxels::U8(v) => v.len(),
            Voxels::U16(v) => v.len(),
            Voxels::I16(v) => v.len(),
            Voxels::F32(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the numbers are a mapped file's bytes, not a copy.
    pub fn is_mapped(&self) -> bool {
        match self {
            Voxels::U8(v) => v.is_mapped(),
            Voxels::U16(v) => v.is_mapped(),
            Voxels::I16(v) => v.is_mapped(),
            Voxels::F32(v) => v.is_mapped(),
        }
    }

    /// The host's memory these are read from, if they are.
    pub fn lender(&self) -> Option<&Arc<Lent>> {
        match self {
            Voxels::U8(v) => v.lender(),
            Voxels::U16(v) => v.lender(),
            Voxels::I16(v) => v.lender(),
            Voxels::F32(v) => v.lender(),
        }
    }

    /// Whether these are the host's memory itself, not a copy.
    pub fn in_place(&self) -> bool {
        self.lender().is_some_and(|l| !l.is_copied())
    }

    /// Bytes the stored numbers take.
    pub fn bytes(&self) -> u64 {
        let each = match self {
            Voxels::U8(_) => 1,
            Voxels::U16(_) | Voxels::I16(_) => 2,
            Voxels::F32(_) => 4,
        };
        self.len() as u64 * each
    }

    /// The number stored for voxel `i`, unscaled.
    pub fn stored(&self, i: usize) -> f32 {
        match self {
            Voxels::U8(v) => f32::from(v[i]),
            Voxels::U16(v) => f32::from(v[i]),
            Voxels::I16(v) => f32::from(v[i]),
            Voxels::F32(v) => v[i],
        }
    }

    /// The map ANARI's element types imply: fixed-point numbers to [0, 1]
    /// (UFIXED8, UFIXED16) or [-1, 1] (FIXED16), floats as they are.
    pub fn fixed_point(&self) -> Scaling {
        let slope = match self {
            Voxels::U8(_) => 1.0 / 255.0,
            Voxels::U16(_) => 1.0 / 65535.0,
            Voxels::I16(_) => 1.0 / 32767.0,
            Voxels::F32(_) => 1.0,
        };
        Scaling {
            slope,
            intercept: 0.0,
        }
    }
}

/// A linear map from stored numbers to values, `stored * slope +
/// intercept`: a fixed-point type's normalisation, or a file's rescale
/// (NIfTI's scl_slope, DICOM's RescaleSlope). Being linear, it commutes
/// with trilinear interpolation, so renderers interpolate stored numbers
/// and map the result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scaling {
    pub slope: f32,
    pub intercept: f32,
}

impl Scaling {
    pub const IDENTITY: Self = Self {
        slope: 1.0,
        intercept: 0.0,
    };

    pub fn apply(self, stored: f32) -> f32 {
        stored * self.slope + self.intercept
    }
}

/// The most voxels a volume may have: 2^32 (4 GiB as uint8, 8 GiB as
/// uint16, 16 GiB as float32). Every index into a grid is a usize or u64;
/// the AVX2 packet gathers, which index in i32, take grids of fewer than
/// 2^31 voxels and leave larger ones to the scalar path.
pub const MAX_VOXELS: u64 = 1 << 32;

#[derive(Debug, Error, PartialEq)]
pub enum VolumeError {
    #[error("a volume of {}x{}x{} voxels is more than caveray takes ({MAX_VOXELS} voxels at most)", .dims.x, .dims.y, .dims.z)]
    TooManyVoxels { dims: UVec3 },
    #[error("volume dimensions must all be at least 1, got {}x{}x{}", .dims.x, .dims.y, .dims.z)]
    ZeroDims { dims: UVec3 },
    #[error("volume of {}x{}x{} needs {expected} voxels, got {got}", .dims.x, .dims.y, .dims.z)]
    WrongLength {
        dims: UVec3,
        expected: u64,
        got: usize,
    },
    #[error("voxel spacing must be finite and positive, got {spacing}")]
    BadSpacing { spacing: Vec3 },
    #[error("volume origin must be finite, got {origin}")]
    BadOrigin { origin: Vec3 },
    #[error("voxel {index} is not a finite number")]
    NonFiniteVoxel { index: usize },
    #[error("a scaling of stored values must be finite with a slope other than 0, got {slope} * v + {intercept}")]
    BadScaling { slope: f32, intercept: f32 },
    #[error("vertices {}..={} are not a box within a grid of {}x{}x{}", .lo, .hi, .dims.x, .dims.y, .dims.z)]
    BadBox { lo: UVec3, hi: UVec3, dims: UVec3 },
}

/// How a volume is sampled between its grid vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Filter {
    /// Trilinear interpolation of the eight surrounding vertices.
    #[default]
    Linear,
    /// The value of the nearest vertex.
    Nearest,
}

impl Filter {
    /// The shaders' FILTER_ code.
    pub fn code(self) -> u32 {
        match self {
            Filter::Linear => 0,
            Filter::Nearest => 1,
        }
    }
}

/// A structured regular grid: vertex-centred samples, x fastest, covering
/// [origin, origin + (dims - 1) * spacing].
#[derive(Clone, Debug)]
pub struct StructuredVolume {
    dims: UVec3,
    /// Shared, so the same grid placed elsewhere costs no copy.
    voxels: Arc<Voxels>,
    origin: Vec3,
    spacing: Vec3,
    scaling: Scaling,
    /// Smallest and largest stored number, found when first asked (with
    /// the voxels, shared by the grid's copies): a mapped file's pages are
    /// read only when something needs them, so a cluster rank cropping its
    /// brick out of a grid reads the brick alone.
    stored_range: Arc<OnceLock<(f32, f32)>>,
    filter: Filter,
}

/// Grids are equal by what they hold; the range is derived from it.
impl PartialEq for StructuredVolume {
    fn eq(&self, other: &Self) -> bool {
        self.dims == other.dims
            && self.voxels == other.voxels
            && self.origin == other.origin
            && self.spacing == other.spacing
            && self.scaling == other.scaling
            && self.filter == other.filter
    }
}

impl StructuredVolume {
    pub fn new(
        dims: UVec3,
        voxels: Voxels,
        origin: Vec3,
        spacing: Vec3,
    ) -> Result<Self, VolumeError> {
        if dims.min_element() == 0 {
            return Err(VolumeError::ZeroDims { dims });
        }
        let expected = u64::from(dims.x)
            .saturating_mul(u64::from(dims.y))
            .saturating_mul(u64::from(dims.z));
        if expected > MAX_VOXELS {
            return Err(VolumeError::TooManyVoxels { dims });
        }
        if voxels.len() as u64 != expected {
            return Err(VolumeError::WrongLength {
                dims,
                expected,
                got: voxels.len(),
            });
        }
        if let Voxels::F32(v) = &voxels {
            if let Some(index) = v.iter().position(|x| !x.is_finite()) {
                return Err(VolumeError::NonFiniteVoxel { index });
            }
        }
        Self {
            dims,
            scaling: voxels.fixed_point(),
            voxels: Arc::new(voxels),
            origin: Vec3::ZERO,
            spacing: Vec3::ONE,
            stored_range: Arc::default(),
            filter: Filter::Linear,
        }
        .with_geometry(origin, spacing)
    }

    /// The same grid with its first voxel at `origin` and voxels
    /// `spacing` apart.
    pub fn with_geometry(mut self, origin: Vec3, spacing: Vec3) -> Result<Self, VolumeError> {
        if !spacing.is_finite() || spacing.min_element() <= 0.0 {
            return Err(VolumeError::BadSpacing { spacing });
        }
        if !origin.is_finite() {
            return Err(VolumeError::BadOrigin { origin });
        }
        self.origin = origin;
        self.spacing = spacing;
        Ok(self)
    }

    /// The same grid with its stored numbers read through `scaling`
    /// instead of their type's fixed-point map.
    pub fn with_scaling(mut self, scaling: Scaling) -> Result<Self, VolumeError> {
        let Scaling { slope, intercept } = scaling;
        if !slope.is_finite() || !intercept.is_finite() || slope == 0.0 {
            return Err(VolumeError::BadScaling { slope, intercept });
        }
        self.scaling = scaling;
        Ok(self)
    }
    pub fn scaling(&self) -> Scaling {
        self.scaling
    }

    /// The value of voxel `i`: its stored number scaled.
    pub fn value(&self, i: usize) -> f32 {
        self.scaling.apply(self.voxels.stored(i))
    }

    /// The same grid sampled with `filter`.
    pub fn with_filter(mut self, filter: Filter) -> Self {
        self.filter = filter;
        self
    }
    pub fn filter(&self) -> Filter {
        self.filter
    }

    pub fn dims(&self) -> UVec3 {
        self.dims
    }
    pub fn voxels(&self) -> &Voxels {
        &self.voxels
    }
    pub fn origin(&self) -> Vec3 {
        self.origin
    }
    pub fn spacing(&self) -> Vec3 {
        self.spacing
    }
    /// Smallest and largest voxel value.
    pub fn value_range(&self) -> (f32, f32) {
        let (lo, hi) = *self.stored_range.get_or_init(|| {
            let v = &self.voxels;
            (0..v.len()).fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), i| {
                let x = v.stored(i);
                (lo.min(x), hi.max(x))
            })
        });
        let (a, b) = (self.scaling.apply(lo), self.scaling.apply(hi));
        (a.min(b), a.max(b))
    }
    /// World-space box of the grid's vertices.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let extent = (self.dims - UVec3::ONE).as_vec3() * self.spacing;
        (self.origin, self.origin + extent)
    }

    /// Vertices `lo..=hi` of this grid as a grid of their own, in the same
    /// place: a copy of just those numbers (of a mapped file, only the
    /// pages that hold them are read), with the same scaling and filter.
    pub fn cropped(&self, lo: UVec3, hi: UVec3) -> Result<Self, VolumeError> {
        if lo.cmpgt(hi).any() || hi.cmpge(self.dims).any() {
            return Err(VolumeError::BadBox {
                lo,
                hi,
                dims: self.dims,
            });
        }
        let dims = hi - lo + UVec3::ONE;
        let (w, h) = (self.dims.x as usize, self.dims.y as usize);
        fn rows<T: bytemuck::Pod>(v: &[T], lo: UVec3, dims: UVec3, w: usize, h: usize) -> Vec<T> {
            let mut out = Vec::with_capacity(dims.x as usize * dims.y as usize * dims.z as usize);
            for z in lo.z..lo.z + dims.z {
                for y in lo.y..lo.y + dims.y {
                    let at = (z as usize * h + y as usize) * w + lo.x as usize;
                    out.extend_from_slice(&v[at..at + dims.x as usize]);
                }
            }
            out
        }
        let voxels = match &*self.voxels {
            Voxels::U8(v) => Voxels::U8(rows(v, lo, dims, w, h).into()),
            Voxels::U16(v) => Voxels::U16(rows(v, lo, dims, w, h).into()),
            Voxels::I16(v) => Voxels::I16(rows(v, lo, dims, w, h).into()),
            Voxels::F32(v) => Voxels::F32(rows(v, lo, dims, w, h).into()),
        };
        let origin = self.origin + lo.as_vec3() * self.spacing;
        Ok(Self::new(dims, voxels, origin, self.spacing)?
            .with_scaling(self.scaling)?
            .with_filter(self.filter))
    }

    /// The same grid moved and scaled so that its bounding box is centred
    /// at `centre` and its longest side is `size` long.
    pub fn placed(mut self, centre: Vec3, size: f32) -> Self {
        let (lo, hi) = self.bounds();
        let longest = (hi - lo).max_element().max(f32::MIN_POSITIVE);
        let scale = size / longest;
        self.spacing *= scale;
        self.origin = centre - 0.5 * (hi - lo) * scale;
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cropped_grid_holds_its_box_in_place() {
        let make = || {
            StructuredVolume::new(
                UVec3::new(5, 4, 3),
                Voxels::U16((0..60).collect::<Vec<u16>>().into()),
                Vec3::new(1.0, 2.0, 3.0),
                Vec3::new(0.5, 1.0, 2.0),
            )
            .and_then(|g| {
                g.with_scaling(Scaling {
                    slope: 2.0,
                    intercept: 1.0,
                })
            })
            .unwrap_or_else(|e| panic!("{e}"))
        };
        let grid = make();
        let part = grid
            .cropped(UVec3::new(1, 1, 1), UVec3::new(3, 2, 2))
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(part.dims(), UVec3::new(3, 2, 2));
        assert_eq!(part.origin(), Vec3::new(1.5, 3.0, 5.0));
        assert_eq!(part.scaling(), grid.scaling());
        // Voxel (1, 1, 1) of the grid is 1 + 5 + 20 = 26; (3, 2, 2) is 53.
        assert_eq!(part.value(0), grid.value(26));
        assert_eq!(part.value(11), grid.value(53));
        assert_eq!(part.value_range(), (53.0, 107.0));
        assert_eq!(grid.value_range(), (1.0, 119.0));
        // The range, found when asked, does not make grids unequal.
        assert_eq!(make(), grid);
        assert!(matches!(
            grid.cropped(UVec3::new(2, 0, 0), UVec3::new(1, 3, 2)),
            Err(VolumeError::BadBox { .. })
        ));
        assert!(grid.cropped(UVec3::ZERO, UVec3::new(5, 3, 2)).is_err());
    }
}
