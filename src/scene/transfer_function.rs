use glam::Vec4;
use thiserror::Error;

use crate::geometry::Rounded;

/// Entries of the resampled RGBA table that both renderers look up with
/// linear interpolation.
pub const TABLE_SIZE: usize = 256;

#[derive(Debug, Error, PartialEq)]
pub enum TransferFunctionError {
    #[error("transfer function needs at least one color and one opacity")]
    Empty,
    #[error("{what}[{index}] is not a finite number in [0, 1]")]
    OutOfRange { what: &'static str, index: usize },
    #[error(
        "value range [{}, {}] is empty or not finite",
        Rounded::from(*.lo),
        Rounded::from(*.hi)
    )]
    EmptyRange { lo: f32, hi: f32 },
    #[error(
        "unit distance must be finite and positive, got {}",
        Rounded::from(*.0)
    )]
    UnitDistance(f32),
}

/// ANARI's `transferFunction1D`: colors and opacities spread evenly over
/// `value_range`; a color's alpha multiplies the opacity.
#[derive(Clone, Debug, PartialEq)]
pub struct TransferFunction {
    colors: Vec<Vec4>,
    opacities: Vec<f32>,
    value_range: (f32, f32),
    unit_distance: f32,
}

impl TransferFunction {
    pub fn new(
        colors: Vec<Vec4>,
        opacities: Vec<f32>,
        value_range: (f32, f32),
        unit_distance: f32,
    ) -> Result<Self, TransferFunctionError> {
        if colors.is_empty() || opacities.is_empty() {
            return Err(TransferFunctionError::Empty);
        }
        let unit = |x: f32| x.is_finite() && (0.0..=1.0).contains(&x);
        if let Some(index) = colors
            .iter()
            .position(|c| !c.to_array().into_iter().all(unit))
        {
            return Err(TransferFunctionError::OutOfRange {
                what: "color",
                index,
            });
        }
        if let Some(index) = opacities.iter().position(|&o| !unit(o)) {
            return Err(TransferFunctionError::OutOfRange {
                what: "opacity",
                index,
            });
        }
        let (lo, hi) = value_range;
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(TransferFunctionError::EmptyRange { lo, hi });
        }
        if !(unit_distance.is_finite() && unit_distance > 0.0) {
            return Err(TransferFunctionError::UnitDistance(unit_distance));
        }
        Ok(Self {
            colors,
            opacities,
            value_range,
            unit_distance,
        })
    }

    pub fn value_range(&self) -> (f32, f32) {
        self.value_range
    }
    pub fn unit_distance(&self) -> f32 {
        self.unit_distance
    }

    /// The same function over another value range (e.g. the data's range).
    pub fn with_value_range(mut self, lo: f32, hi: f32) -> Result<Self, TransferFunctionError> {
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(TransferFunctionError::EmptyRange { lo, hi });
        }
        self.value_range = (lo, hi);
        Ok(self)
    }

    /// The same function with opacities meant per `unit_distance` world
    /// units (e.g. after the volume was scaled into a rig).
    pub fn with_unit_distance(mut self, unit_distance: f32) -> Result<Self, TransferFunctionError> {
        if !(unit_distance.is_finite() && unit_distance > 0.0) {
            return Err(TransferFunctionError::UnitDistance(unit_distance));
        }
        self.unit_distance = unit_distance;
        Ok(self)
    }

    /// Color (rgb) and opacity (a), not premultiplied, at position
    /// `t` in [0, 1] of the value range: each array is interpolated linearly
    /// on its own, then the color's alpha scales the opacity.
    pub fn evaluate(&self, t: f32) -> Vec4 {
        let c = lerp_table(&self.colors, t);
        let o = lerp_table(&self.opacities, t);
        c.truncate().extend(o * c.w)
    }

    /// The function resampled into `TABLE_SIZE` RGBA entries; the renderers
    /// read only this table.
    pub fn table(&self) -> Vec<Vec4> {
        (0..TABLE_SIZE)
            .map(|i| self.evaluate(i as f32 / (TABLE_SIZE - 1) as f32))
            .collect()
    }
}

fn lerp_table<T>(values: &[T], t: f32) -> T
where
    T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    if values.len() == 1 {
        return values[0];
    }
    let x = t.clamp(0.0, 1.0) * (values.len() - 1) as f32;
    let i = (x.floor() as usize).min(values.len() - 2);
    let f = x - i as f32;
    values[i] * (1.0 - f) + values[i + 1] * f
}
