//! The TOML format of multi-view displays (`views = N` at the top level):
//! parsing and validation, with errors that name the file, the line and
//! the field, as rig files' do.

use std::path::Path;

use glam::UVec2;
use serde::Deserialize;
use toml::Spanned;

use super::config::{read, ConfigError, Ctx, Vec3};
use crate::geometry::{
    MultiViewDisplay, PanelNumber, Rounded, Screen, Units, ViewPattern, MAX_VIEWS,
};

/// The largest panel side, in pixels.
const MAX_SIDE: u32 = 16384;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDisplay {
    name: Option<String>,
    units: Spanned<Units>,
    views: Spanned<i64>,
    resolution: Spanned<Vec<i64>>,
    ll: Vec3,
    lr: Vec3,
    ur: Vec3,
    viewing_distance: Spanned<f64>,
    view_spacing: Spanned<f64>,
    lens: Option<Spanned<RawLens>>,
    table: Option<Spanned<RawTable>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLens {
    pitch: Spanned<f64>,
    slant: Spanned<f64>,
    offset: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTable {
    period: Spanned<Vec<i64>>,
    views: Spanned<Vec<Vec<i64>>>,
}

/// Displays are read from files here alone, so the display model knows
/// nothing of TOML.
impl MultiViewDisplay {
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let (text, file) = read(path, "display file")?;
        Self::from_toml(&text, &file)
    }

    /// Parses display TOML; `file` names the source in error messages.
    pub fn from_toml(text: &str, file: &str) -> Result<Self, ConfigError> {
        let ctx = Ctx { text, file };
        let raw: RawDisplay = ctx.parse()?;
        let views = *raw.views.get_ref();
        if !(1..=i64::from(MAX_VIEWS)).contains(&views) {
            return Err(ctx.at(
                &raw.views,
                "views".into(),
                format!("must be a whole number from 1 to {MAX_VIEWS}, got {views}"),
            ));
        }
        let views = views as u32;
        let resolution = pair(&ctx, &raw.resolution, "resolution", MAX_SIDE)?;
        let corner = |v: &Vec3, name: &'static str| ctx.vec3(v, || name.to_string());
        let (ll, lr, ur) = (
            corner(&raw.ll, "ll")?,
            corner(&raw.lr, "lr")?,
            corner(&raw.ur, "ur")?,
        );
        let screen = Screen::new(ll, lr, ur)
            .map_err(|e| ctx.at(&raw.ll, "ll".into(), format!("the panel's corners: {e}")))?;
        let viewing_distance = ctx.positive(&raw.viewing_distance, "viewing_distance", false)?;
        let view_spacing = ctx.positive(&raw.view_spacing, "view_spacing", false)?;
        let pattern = match (&raw.lens, &raw.table) {
            (Some(lens), None) => {
                let l = lens.get_ref();
                let finite = |v: &Spanned<f64>, field: &str| {
                    let x = *v.get_ref();
                    if x.is_finite() {
                        Ok(x)
                    } else {
                        Err(ctx.at(
                            v,
                            field.into(),
                            format!("must be a finite number, got {}", Rounded(x)),
                        ))
                    }
                };
                ViewPattern::lens(
                    ctx.positive(&l.pitch, "lens.pitch", false)?,
                    finite(&l.slant, "lens.slant")?,
                    match &l.offset {
                        Some(o) => finite(o, "lens.offset")?,
                        None => 0.0,
                    },
                )
            }
            (None, Some(table)) => {
                let t = table.get_ref();
                let period = pair(&ctx, &t.period, "table.period", 1024)?;
                let want = (period.x * period.y) as usize;
                let rows = t.views.get_ref();
                if rows.len() != want {
                    return Err(ctx.at(
                        &t.views,
                        "table.views".into(),
                        format!(
                            "a period of {}x{} pixels needs {want} entries of [red, green, blue] views, got {}",
                            period.x,
                            period.y,
                            rows.len()
                        ),
                    ));
                }
                let mut entries = Vec::with_capacity(want);
                for (i, row) in rows.iter().enumerate() {
                    match row[..] {
                        [r, g, b]
                            if [r, g, b].iter().all(|v| (0..i64::from(views)).contains(v)) =>
                        {
                            entries.push([r as u32, g as u32, b as u32]);
                        }
                        _ => {
                            return Err(ctx.at(
                                &t.views,
                                format!("table.views[{i}]"),
                                format!(
                                "expected three views from 0 to {} (red, green, blue), got {row:?}",
                                views - 1
                            ),
                            ))
                        }
                    }
                }
                ViewPattern::Table {
                    period,
                    views: entries,
                }
            }
            (Some(lens), Some(_)) => {
                return Err(ctx.at(
                    lens,
                    "lens".into(),
                    "give either [lens] or [table], not both".into(),
                ))
            }
            (None, None) => {
                return Err(ctx.error(
                    0..0,
                    Some("lens".into()),
                    "a display needs [lens] (pitch, slant, offset) or [table] (period, views)"
                        .into(),
                ))
            }
        };
        let display = MultiViewDisplay {
            name: raw.name.unwrap_or_else(|| file.to_string()),
            units: *raw.units.get_ref(),
            screen,
            resolution,
            views,
            pattern,
            viewing_distance,
            view_spacing,
        };
        if let Some((number, must)) = display.out_of_range() {
            let lens = raw.lens.as_ref().map(|l| l.get_ref());
            // Only a lens has a pitch and a slant: without one, the line
            // named is the panel's distance, which sets the pattern too.
            let (value, field) = match (number, lens) {
                (PanelNumber::Pitch, Some(l)) => (&l.pitch, "lens.pitch"),
                (PanelNumber::Slant, Some(l)) => (&l.slant, "lens.slant"),
                (PanelNumber::ViewSpacing, _) => (&raw.view_spacing, "view_spacing"),
                _ => (&raw.viewing_distance, "viewing_distance"),
            };
            return Err(ctx.at(
                value,
                field.into(),
                format!("{must}, got {}", Rounded(*value.get_ref())),
            ));
        }
        Ok(display)
    }
}

/// Two whole numbers from 1 to `max`.
fn pair(ctx: &Ctx<'_>, v: &Spanned<Vec<i64>>, field: &str, max: u32) -> Result<UVec2, ConfigError> {
    match v.get_ref()[..] {
        [x, y] if [x, y].iter().all(|n| (1..=i64::from(max)).contains(n)) => {
            Ok(UVec2::new(x as u32, y as u32))
        }
        _ => Err(ctx.at(
            v,
            field.into(),
            format!(
                "expected two whole numbers from 1 to {max}, got {:?}",
                v.get_ref()
            ),
        )),
    }
}
