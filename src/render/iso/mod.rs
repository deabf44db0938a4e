//! Isosurface ray casting (the CPU reference): the first
//! crossing of the iso-value along each ray, refined by secant steps, with
//! trilinear or tricubic B-spline filtering, the gradient for the normal
//! and the Hessian for the principal curvatures; Blinn-Phong shading, in a
//! flat color or colored by curvature. docs/autostereo.md describes it.

mod cast;
mod field;
mod multiview;
mod surfaces;

use glam::{Vec3, Vec4};

pub use cast::{cast, cast_by, values, Caster, IsoHit, UNSTRUCTURED_ISO};
pub use field::{crossing_box, curvatures, IsoField, IsoFilter, Sample};
pub use multiview::{
    render_display, render_display_by, subpixels_differing, MultiViewMethod, Panel,
};
pub(crate) use multiview::{same_view_offsets, SAME_VIEW_SAMPLES, SEARCH_MARGIN_STEPS};
pub use surfaces::{interleave, nearest, IsoSurface};

use super::RenderError;

/// How the surface is colored before shading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Coloring {
    /// One color (linear RGB).
    Flat(Vec3),
    /// By mean curvature: blue where the surface is concave, white where it
    /// is flat, orange where it is convex, saturating at a curvature of
    /// 1/`radius` (world units).
    Curvature { radius: f32 },
}

/// What the isosurface caster needs besides the volume and the rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IsoSettings {
    pub isovalue: f32,
    pub filter: IsoFilter,
    /// Steps per grid cell along the ray before the secant refinement.
    pub steps_per_cell: f32,
    /// Secant steps refining each crossing (0: the first sample past it).
    pub secant_steps: u32,
    pub coloring: Coloring,
    /// Towards the light; `None`: from the eye (a headlight).
    pub light: Option<Vec3>,
    pub ambient: f32,
    pub diffuse: f32,
    pub specular: f32,
    pub shininess: f32,
    /// Straight RGBA behind the surface.
    pub background: Vec4,
}

impl IsoSettings {
    pub fn new(isovalue: f32) -> Self {
        Self {
            isovalue,
            filter: IsoFilter::TricubicBSpline,
            steps_per_cell: 2.0,
            secant_steps: 6,
            coloring: Coloring::Flat(Vec3::new(0.9, 0.85, 0.75)),
            light: None,
            ambient: 0.15,
            diffuse: 0.75,
            specular: 0.3,
            shininess: 40.0,
            background: Vec4::new(0.0, 0.0, 0.0, 1.0),
        }
    }

    /// Why these settings cannot render, if they cannot.
    pub fn validate(&self) -> Result<(), RenderError> {
        let bad = |m: String| Err(RenderError::Settings(m));
        if !self.isovalue.is_finite() {
            return bad(format!(
                "the iso-value must be finite, got {}",
                self.isovalue
            ));
        }
        if !(self.steps_per_cell.is_finite() && (0.25..=64.0).contains(&self.steps_per_cell)) {
            return bad(format!(
                "steps per cell must be 0.25 to 64, got {}",
                self.steps_per_cell
            ));
        }
        if self.secant_steps > 64 {
            return bad(format!(
                "at most 64 secant steps, got {}",
                self.secant_steps
            ));
        }
        let shading = [self.ambient, self.diffuse, self.specular, self.shininess];
        if !shading.iter().all(|x| x.is_finite() && *x >= 0.0) {
            return bad(format!(
                "ambient, diffuse, specular and shininess must be finite and >= 0, got {shading:?}"
            ));
        }
        if let Some(l) = self.light {
            if !(l.is_finite() && l.length() > 0.0) {
                return bad(format!(
                    "the light direction must be finite and not zero, got {l}"
                ));
            }
        }
        match self.coloring {
            Coloring::Curvature { radius } if !(radius.is_finite() && radius > 0.0) => bad(
                format!("the curvature radius must be positive, got {radius}"),
            ),
            Coloring::Flat(c) if !c.is_finite() => {
                bad(format!("the color must be finite, got {c}"))
            }
            _ => Ok(()),
        }
    }
}

/// The color of mean curvature `mean` under `radius` (see [`Coloring`]).
pub fn curvature_color(mean: f32, radius: f32) -> Vec3 {
    let s = (mean * radius).clamp(-1.0, 1.0);
    let white = Vec3::splat(0.95);
    if s >= 0.0 {
        white.lerp(Vec3::new(1.0, 0.45, 0.1), s)
    } else {
        white.lerp(Vec3::new(0.15, 0.35, 1.0), -s)
    }
}
