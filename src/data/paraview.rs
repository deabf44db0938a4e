use std::path::Path;

use serde_json::Value;

use super::presets::tabulate;
use super::DataError;
use crate::scene::TransferFunction;

/// Loads a color map exported from ParaView as JSON: `RGBPoints` (x, r, g,
/// b quadruples) and, if present, `Points` (x, opacity, midpoint,
/// sharpness; midpoint and sharpness are ignored). The file may hold one
/// map or a list; the first with `RGBPoints` is used. The value range is
/// that of the color points; without `Points` opacity ramps from 0 to 1.
pub fn load_paraview(path: &Path) -> Result<TransferFunction, DataError> {
    let file = path.display().to_string();
    let text = super::files::read_text(path, super::files::TEXT_LIMIT).map_err(|source| {
        DataError::Io {
            file: file.clone(),
            source,
        }
    })?;
    parse_paraview(&text, &file)
}

/// `load_paraview` on text already read; `file` names it in errors.
pub fn parse_paraview(text: &str, file: &str) -> Result<TransferFunction, DataError> {
    let bad = |message: String| DataError::ParaView {
        file: file.to_string(),
        message,
    };
    let json: Value = serde_json::from_str(text).map_err(|e| bad(e.to_string()))?;
    let maps = match &json {
        Value::Array(list) => list.iter().collect(),
        other => vec![other],
    };
    let map = maps
        .into_iter()
        .find(|m| m.get("RGBPoints").is_some())
        .ok_or_else(|| bad("no entry has RGBPoints".into()))?;
    let numbers = |key: &str, stride: usize| -> Result<Option<Vec<Vec<f32>>>, DataError> {
        let Some(v) = map.get(key) else {
            return Ok(None);
        };
        let list = v
            .as_array()
            .ok_or_else(|| bad(format!("{key} is not a list")))?;
        let flat: Vec<f32> = list
            .iter()
            .map(|x| x.as_f64().map(|f| f as f32).filter(|f| f.is_finite()))
            .collect::<Option<_>>()
            .ok_or_else(|| bad(format!("{key} holds something other than finite numbers")))?;
        if flat.is_empty() || !flat.len().is_multiple_of(stride) {
            return Err(bad(format!(
                "{key} must hold groups of {stride} numbers, got {}",
                flat.len()
            )));
        }
        Ok(Some(flat.chunks(stride).map(<[f32]>::to_vec).collect()))
    };
    let rgb = numbers("RGBPoints", 4)?.unwrap_or_default();
    let opacity = numbers("Points", 4)?;
    let lo = rgb.iter().map(|p| p[0]).fold(f32::INFINITY, f32::min);
    let hi = rgb.iter().map(|p| p[0]).fold(f32::NEG_INFINITY, f32::max);
    if hi <= lo {
        return Err(bad(format!("RGBPoints span no value range ([{lo}, {hi}])")));
    }
    let norm = |x: f32| (x - lo) / (hi - lo);
    let mut colors: Vec<(f32, [f32; 3])> = rgb
        .iter()
        .map(|p| (norm(p[0]), [p[1], p[2], p[3]]))
        .collect();
    let mut opacities: Vec<(f32, f32)> = match opacity {
        Some(points) => points.iter().map(|p| (norm(p[0]), p[1])).collect(),
        None => vec![(0.0, 0.0), (1.0, 1.0)],
    };
    colors.sort_by(|a, b| a.0.total_cmp(&b.0));
    opacities.sort_by(|a, b| a.0.total_cmp(&b.0));
    let tf = tabulate(&colors, &opacities).map_err(|e| bad(e.to_string()))?;
    Ok(tf.with_value_range(lo, hi)?)
}
