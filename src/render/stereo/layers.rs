//! The re-projection layers themselves: their texel format, how many a
//! span of pixels needs, what they cost in memory, and the one error for a
//! layer count that does not fit.

use std::fmt;
use std::str::FromStr;

use glam::UVec2;
use thiserror::Error;

/// Texel format of the re-projection layers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LayerFormat {
    /// Buchacher & Erdt's choice: half the memory, color to about 3 digits.
    #[default]
    Rgba16F,
    /// Exact: with e = 0 the right image equals the left bit for bit.
    Rgba32F,
}

impl LayerFormat {
    pub const NAMES: [&'static str; 2] = ["rgba16f", "rgba32f"];

    pub fn bytes_per_texel(self) -> u64 {
        match self {
            LayerFormat::Rgba16F => 8,
            LayerFormat::Rgba32F => 16,
        }
    }
}

impl fmt::Display for LayerFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LayerFormat::Rgba16F => "rgba16f",
            LayerFormat::Rgba32F => "rgba32f",
        })
    }
}

impl FromStr for LayerFormat {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "rgba16f" => Ok(LayerFormat::Rgba16F),
            "rgba32f" => Ok(LayerFormat::Rgba32F),
            _ => Err(format!(
                "unknown layer format \"{s}\": expected rgba16f or rgba32f"
            )),
        }
    }
}

/// Layers for a span of `d` pixels: samples land in the pixel they fall
/// in, and a segment of length d can reach into ceil(d) + 1 pixels.
pub fn layers_for(span_px: f64) -> u32 {
    // Rounding noise must not cost a layer (and 144 MiB at 768^2).
    (span_px - 1e-9).ceil().max(0.0) as u32 + 1
}

/// Bytes of `layers` layers of `size` texels: `M = w h L b`, with `b` the
/// bytes of one texel (Buchacher & Erdt's `w^2 L bytes channels` when square).
pub fn layer_memory(size: UVec2, layers: u32, format: LayerFormat) -> u64 {
    u64::from(size.x) * u64::from(size.y) * u64::from(layers) * format.bytes_per_texel()
}

/// A layer count that cannot serve a plan.
#[derive(Debug, Error, PartialEq)]
pub enum LayerCountError {
    #[error("at least one re-projection layer is needed, got 0")]
    NoLayers,
    #[error("{layers} layers are too few: the re-projected segments reach {needed} pixels ({reach}); give at least {needed} or let the planner choose")]
    TooFewLayers {
        layers: u32,
        needed: u32,
        /// What the segments span, in words ("offsets -3..=12").
        reach: String,
    },
}

/// The layers to allocate: `asked`, or the plan's `needed` when `None`.
pub fn layer_count(
    asked: Option<u32>,
    needed: u32,
    reach: impl FnOnce() -> String,
) -> Result<u32, LayerCountError> {
    match asked {
        None => Ok(needed),
        Some(0) => Err(LayerCountError::NoLayers),
        Some(n) if n < needed => Err(LayerCountError::TooFewLayers {
            layers: n,
            needed,
            reach: reach(),
        }),
        Some(n) => Ok(n),
    }
}
