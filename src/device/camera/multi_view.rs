//! caveray's `multiView` camera: a lenticular or parallax-barrier panel
//! whose every subpixel is seen from its own eye, the ANARI face of the
//! display model in `crate::geometry::display` (the TOML's fields, renamed to
//! ANARI's camelCase). The frame is the panel: its size is the panel's
//! pixels. docs/autostereo.md has the formulas.

use std::sync::Arc;

use glam::UVec2;

use super::CameraModel;
use crate::device::array::Array;
use crate::device::object::State;
use crate::device::table::Read;
use crate::device::table::{p, DefaultValue, SubtypeInfo, EXT_MULTI_VIEW, F32, VEC3};
use crate::device::types::DataType as T;
use crate::geometry::Screen;
use crate::geometry::{
    MultiViewDisplay, PanelNumber, Units, ViewPattern, MAX_SLANT, MAX_VIEWS, PITCH_RANGE,
};
use crate::render::iso::MultiViewMethod;

/// The largest view table period, in pixels each way.
const MAX_PERIOD: u64 = 1024;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::CAMERA,
    subtype: "multiView",
    description: "an autostereoscopic panel: each subpixel seen from the eye of its view, views spread along a line in front of the panel",
    extensions: &[EXT_MULTI_VIEW],
    params: &[
        p("lowerLeft", VEC3, true, DefaultValue::None, "panel's lower-left corner"),
        p("lowerRight", VEC3, true, DefaultValue::None, "panel's lower-right corner"),
        p("upperRight", VEC3, true, DefaultValue::None, "panel's upper-right corner"),
        p("views", &[T::INT32, T::UINT32], true, DefaultValue::None, "number of views, 1 to 64")
            .range(1.0, 64.0),
        p("viewingDistance", F32, true, DefaultValue::None,
          "from the panel to the line of eyes, along its normal (world units): 0.01 to 100 panel widths"),
        p("viewSpacing", F32, true, DefaultValue::None,
          "between neighbouring views' eyes on that line, view 0 at the right end: positive, the line (views - 1 spacings) at most 100 panel widths"),
        p("lens.pitch", F32, false, DefaultValue::None,
          "lens width across the panel, in subpixels, 1/64 to 10000 (a lens sheet; or give viewTable)")
            .range(PITCH_RANGE.0 as f32, PITCH_RANGE.1 as f32),
        p("lens.slant", F32, false, DefaultValue::Floats(&[0.0]),
          "subpixels the lens moves right per subpixel height upward (tan of its slant), -10 to 10")
            .range(-MAX_SLANT as f32, MAX_SLANT as f32),
        p("lens.offset", F32, false, DefaultValue::Floats(&[0.0]),
          "where the first lens starts, in subpixels"),
        p("viewTable", &[T::ARRAY2D], false, DefaultValue::None,
          "one period of the pattern, period.x by period.y pixels from the lower left, each pixel's red, green and blue view (instead of lens.*)")
            .elements(&[T::UINT8_VEC3, T::UINT32_VEC3]),
        p("view", &[T::INT32], false, DefaultValue::None,
          "one view's image alone (0 to views - 1); unset or -1: the interleaved panel image"),
        p("method", &[T::STRING], false, DefaultValue::Text("passes"),
          "passes (geometric + spectral: each subpixel's own hit, about one view's cost and a half), greenGeometry (red and blue shade green's hit: one view's cost, colours off where the eyes see different points), perSubpixel (one ray a subpixel) or naive (every view, then interleaved)")
            .names(&["passes", "greenGeometry", "perSubpixel", "naive"]),
    ],
    commit: Some(commit),
};

/// A multi-view camera after commit.
#[derive(Clone, Debug, PartialEq)]
pub struct MultiViewCamera {
    /// The panel; its resolution is each frame's size.
    pub display: MultiViewDisplay,
    /// `Some`: that view's image alone.
    pub view: Option<u32>,
    pub method: MultiViewMethod,
}

impl MultiViewCamera {
    /// The panel of a frame of `size`.
    pub fn panel(&self, size: UVec2) -> Arc<MultiViewDisplay> {
        Arc::new(MultiViewDisplay {
            resolution: size,
            ..self.display.clone()
        })
    }
}

fn commit(r: &Read<'_>, warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let point = |name| r.vec3(name).map(|v| v.as_dvec3());
    let screen = Screen::new(
        point("lowerLeft")?,
        point("lowerRight")?,
        point("upperRight")?,
    )
    .map_err(|e| format!("the panel's corners: {e}"))?;
    let views = whole(r, "views")?.unwrap_or(0);
    if !(1..=i64::from(MAX_VIEWS)).contains(&views) {
        return Err(format!("views must be 1 to {MAX_VIEWS}, got {views}"));
    }
    let views = views as u32;
    let positive = |name| {
        let x = r.f32(name)?;
        if x.is_finite() && x > 0.0 {
            Ok(f64::from(x))
        } else {
            Err(format!("{name} must be positive and finite, got {x}"))
        }
    };
    let viewing_distance = positive("viewingDistance")?;
    let view_spacing = positive("viewSpacing")?;
    let pattern = match (r.set("lens.pitch"), r.object("viewTable")) {
        (Some(_), Some(_)) => {
            return Err(
                "give either lens.pitch (with lens.slant, lens.offset) or viewTable, not both"
                    .into(),
            )
        }
        (None, None) => {
            return Err(
                "a multi-view camera needs lens.pitch (a lens sheet) or viewTable (a pattern)"
                    .into(),
            )
        }
        (None, Some(_)) => r
            .array("viewTable", |a| table(a, views))?
            .ok_or("viewTable is not set")?,
        (Some(_), None) => {
            let finite = |name| {
                let x = r.f32(name)?;
                if x.is_finite() {
                    Ok(f64::from(x))
                } else {
                    Err(format!("{name} must be finite, got {x}"))
                }
            };
            ViewPattern::lens(
                positive("lens.pitch")?,
                finite("lens.slant")?,
                finite("lens.offset")?,
            )
        }
    };
    let view = match whole(r, "view")? {
        None | Some(-1) => None,
        Some(v) if (0..i64::from(views)).contains(&v) => Some(v as u32),
        Some(v) => {
            return Err(format!(
                "view {v} is not one of the {views} views (0 to {}) or -1 (the panel image)",
                views - 1
            ))
        }
    };
    let method = match r.string("method") {
        Some("perSubpixel") => MultiViewMethod::PerSubpixel,
        Some("naive") => MultiViewMethod::Naive,
        Some("greenGeometry") => MultiViewMethod::GreenGeometry,
        Some("passes") | None => MultiViewMethod::GeometricSpectral,
        Some(other) => {
            warn(format!(
                "method '{other}' is not one of passes, greenGeometry, perSubpixel, naive; rendering by passes"
            ));
            MultiViewMethod::GeometricSpectral
        }
    };
    let display = MultiViewDisplay {
        name: "multiView camera".into(),
        units: Units::Metres,
        screen,
        resolution: UVec2::ONE,
        views,
        pattern,
        viewing_distance,
        view_spacing,
    };
    if let Some((number, must)) = display.out_of_range() {
        let name = match number {
            PanelNumber::ViewingDistance => "viewingDistance",
            PanelNumber::ViewSpacing => "viewSpacing",
            PanelNumber::Pitch => "lens.pitch",
            PanelNumber::Slant => "lens.slant",
        };
        return Err(format!("{name} {must}, got {:?}", r.f32(name)?));
    }
    // Every view's eye must see the panel's front.
    for v in [0, views - 1] {
        display
            .view_camera(v)
            .map_err(|e| format!("view {v}'s eye: {e}"))?;
    }
    CameraModel::MultiView(Box::new(MultiViewCamera {
        display,
        view,
        method,
    }))
    .committed()
}

/// An INT32 or UINT32 parameter, if set.
fn whole(r: &Read<'_>, name: &str) -> Result<Option<i64>, String> {
    let Some(v) = r.set(name) else {
        return Ok(None);
    };
    match (v.i32(), v.u32s().as_deref()) {
        (Some(i), _) => Ok(Some(i64::from(i))),
        (None, Some([u])) => Ok(Some(i64::from(*u))),
        _ => Err(format!("'{name}' must be an INT32 or UINT32")),
    }
}

/// A view table array: its dimensions are the period.
fn table(a: &Array, views: u32) -> Result<ViewPattern, String> {
    let [px, py, _] = a.dims();
    if px > MAX_PERIOD || py > MAX_PERIOD || a.is_empty() {
        return Err(format!(
            "viewTable is {px}x{py}; a period is 1 to {MAX_PERIOD} pixels each way"
        ));
    }
    let bytes = a.bytes();
    let entries: Vec<[u32; 3]> = match a.element() {
        T::UINT8_VEC3 => bytes
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]].map(u32::from))
            .collect(),
        T::UINT32_VEC3 => bytes
            .chunks_exact(12)
            .map(|c| {
                let word = |i: usize| u32::from_ne_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
                [word(0), word(4), word(8)]
            })
            .collect(),
        other => {
            return Err(format!(
                "viewTable holds {other}; expected UINT8_VEC3 or UINT32_VEC3"
            ))
        }
    };
    if let Some((i, e)) = entries
        .iter()
        .enumerate()
        .find(|(_, e)| e.iter().any(|&v| v >= views))
    {
        return Err(format!(
            "viewTable[{i}] is {e:?}; views are 0 to {}",
            views - 1
        ));
    }
    Ok(ViewPattern::Table {
        period: UVec2::new(px as u32, py as u32),
        views: entries,
    })
}
