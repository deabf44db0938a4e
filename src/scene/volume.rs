use std::sync::Arc;

use glam::{UVec3, Vec3};
use thiserror::Error;

/// Voxel values as stored. Fixed-point types read as [0, 1] (ANARI's
/// UFIXED8 / UFIXED16); floats are taken as they are.
#[derive(Clone, Debug, PartialEq)]
pub enum Voxels {
    U8(Vec<u8>),
    U16(Vec<u16>),
    F32(Vec<f32>),
}

impl Voxels {
    pub fn len(&self) -> usize {
        match self {
            Voxels::U8(v) => v.len(),
            Voxels::U16(v) => v.len(),
            Voxels::F32(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The value of voxel `i`, fixed-point types normalised to [0, 1].
    pub fn value(&self, i: usize) -> f32 {
        match self {
            Voxels::U8(v) => f32::from(v[i]) / 255.0,
            Voxels::U16(v) => f32::from(v[i]) / 65535.0,
            Voxels::F32(v) => v[i],
        }
    }
}

/// The most voxels a volume may have: 2^31 (8 GiB as the renderers' f32),
/// beyond any GPU's 3D texture limit and what a workstation should hold
/// twice.
pub const MAX_VOXELS: u64 = 1 << 31;

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
#[derive(Clone, Debug, PartialEq)]
pub struct StructuredVolume {
    dims: UVec3,
    /// Shared, so the same grid placed elsewhere costs no copy.
    voxels: Arc<Voxels>,
    origin: Vec3,
    spacing: Vec3,
    value_range: (f32, f32),
    filter: Filter,
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
        if !spacing.is_finite() || spacing.min_element() <= 0.0 {
            return Err(VolumeError::BadSpacing { spacing });
        }
        if !origin.is_finite() {
            return Err(VolumeError::BadOrigin { origin });
        }
        if let Voxels::F32(v) = &voxels {
            if let Some(index) = v.iter().position(|x| !x.is_finite()) {
                return Err(VolumeError::NonFiniteVoxel { index });
            }
        }
        let value_range =
            (0..voxels.len()).fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), i| {
                let v = voxels.value(i);
                (lo.min(v), hi.max(v))
            });
        Ok(Self {
            dims,
            voxels: Arc::new(voxels),
            origin,
            spacing,
            value_range,
            filter: Filter::Linear,
        })
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
    /// Smallest and largest (normalised) voxel value.
    pub fn value_range(&self) -> (f32, f32) {
        self.value_range
    }
    /// World-space box of the grid's vertices.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let extent = (self.dims - UVec3::ONE).as_vec3() * self.spacing;
        (self.origin, self.origin + extent)
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
