//! `caveray render` for a multi-view display (a file with `views = N`):
//! the panel's interleaved image, every subpixel from its own eye, and
//! each view's image on a contact sheet. Displays show isosurfaces
//! (docs/autostereo.md); the volume sits behind the panel.

use std::path::Path;
use std::time::Instant;

use anari_library_caveray::cave::MultiViewDisplay;
use anari_library_caveray::output::{frame_to_rgba, write_png, write_rgba_png};
use anari_library_caveray::render::iso::{
    cast_by, crossing_box, render_display_by, values, Caster, IsoFilter, IsoSettings,
    MultiViewMethod, Panel,
};
use anari_library_caveray::render::{Frame, FrameDesc, Watch};
use glam::Vec3;

use crate::progress::Progress;
use crate::scene::{at, panel_frame, VolumeArgs};
use crate::Failure;

/// Views a row of the contact sheet.
const SHEET_COLUMNS: u32 = 4;

/// Whether the TOML file at `path` is a multi-view display.
pub fn is_display(path: &Path) -> bool {
    std::fs::read_to_string(path)
        .ok()
        .and_then(|t| t.parse::<toml::Table>().ok())
        .is_some_and(|t| t.contains_key("views"))
}

/// A display and its volume, ready to render: the field and its crossing
/// box found once, for the panel and every view.
pub struct Prepared {
    pub display: MultiViewDisplay,
    pub resolution: glam::UVec2,
    scene: anari_library_caveray::scene::Scene,
    settings: IsoSettings,
    field: Vec<f32>,
    bounds: (Vec3, Vec3),
    pub rays: Vec<anari_library_caveray::geometry::RayGen>,
    panel: Panel,
}

impl Prepared {
    pub fn new(
        config: &Path,
        volume: &VolumeArgs,
        scale: f64,
        iso: f32,
        filter: IsoFilter,
    ) -> Result<Self, Failure> {
        let runtime = |e: &dyn std::fmt::Display| Failure::Runtime(e.to_string());
        if !(iso.is_finite() && (0.0..=1.0).contains(&iso)) {
            return Err(Failure::Usage(format!(
                "--iso must be a fraction from 0 to 1, got {iso}"
            )));
        }
        let display = MultiViewDisplay::load(config).map_err(|e| Failure::Usage(e.to_string()))?;
        let resolution = (display.resolution.as_dvec2() * scale)
            .round()
            .max(glam::DVec2::ONE)
            .as_uvec2();
        let display = MultiViewDisplay {
            resolution,
            ..display
        };
        FrameDesc::new(resolution)
            .validate()
            .map_err(|e| Failure::Usage(e.to_string()))?;
        let loaded = volume.load()?;
        // Behind the panel, a third of its width across.
        let panel = &display.screen;
        let centre = panel.centre() - panel.normal() * panel.width() / 3.0;
        let scene = loaded.placed(
            at(centre.as_vec3(), (panel.width() / 3.0) as f32),
            &panel_frame(panel),
            display.units,
        )?;
        let placed = &scene.volumes()[0];
        let (lo, hi) = placed.volume.value_range();
        let settings = IsoSettings {
            filter,
            light: Some(Vec3::new(0.3, 0.5, 1.0)),
            ..IsoSettings::new(lo + iso * (hi - lo))
        };
        let rays = display.view_rays().map_err(|e| runtime(&e))?;
        let panel = Panel::new(resolution, Default::default(), rays.clone(), |x, y, c| {
            display.view_of(x, y, c)
        })
        .map_err(|e| runtime(&e))?;
        settings.validate().map_err(|e| runtime(&e))?;
        let field = values(placed).map_err(|e| runtime(&e))?;
        let bounds = crossing_box(
            placed.volume.dims(),
            |i| field[i],
            settings.isovalue,
            settings.filter,
        );
        Ok(Self {
            display,
            resolution,
            scene,
            settings,
            field,
            bounds,
            rays,
            panel,
        })
    }

    fn caster<'a>(&'a self, watch: Watch<'a>) -> Caster<'a> {
        Caster::with_bounds(
            &self.scene.volumes()[0],
            &self.field,
            &self.settings,
            self.bounds,
        )
        .watched(watch)
    }

    /// The panel's image, every subpixel from its own eye.
    pub fn interleaved(&self, watch: Watch<'_>) -> Result<Frame, Failure> {
        render_display_by(
            &self.caster(watch),
            &self.panel,
            MultiViewMethod::PerSubpixel,
        )
        .map(|(frame, _)| frame)
        .map_err(|e| Failure::Runtime(e.to_string()))
    }

    /// View `v`'s image.
    pub fn view(&self, v: usize, watch: Watch<'_>) -> Result<Frame, Failure> {
        cast_by(
            &self.caster(watch),
            &self.rays[v],
            &FrameDesc::new(self.resolution),
        )
        .map(|(frame, _)| frame)
        .map_err(|e| Failure::Runtime(e.to_string()))
    }
}

pub fn run(
    config: &Path,
    volume: &VolumeArgs,
    scale: f64,
    iso: f32,
    filter: IsoFilter,
    out: &Path,
) -> Result<(), Failure> {
    let runtime = |e: &dyn std::fmt::Display| Failure::Runtime(e.to_string());
    let prepared = Prepared::new(config, volume, scale, iso, filter)?;
    let (display, resolution, rays) = (&prepared.display, prepared.resolution, &prepared.rays);
    std::fs::create_dir_all(out)
        .map_err(|e| Failure::Runtime(format!("cannot create {}: {e}", out.display())))?;
    let mut progress = Progress::new(1 + rays.len());
    let start = Instant::now();
    let interleaved = progress.within(1, "interleaved", |counter| {
        prepared.interleaved(Watch::from(counter))
    })?;
    let interleaved_ms = start.elapsed().as_secs_f64() * 1e3;
    progress.step(&format!(
        "interleaved {}x{} {interleaved_ms:.1} ms",
        resolution.x, resolution.y
    ));
    write_png(&interleaved, &out.join("display_interleaved.png")).map_err(|e| runtime(&e))?;
    let (w, h) = (resolution.x, resolution.y);
    let cols = SHEET_COLUMNS.min(display.views);
    let rows = display.views.div_ceil(cols);
    let gap = 4;
    let mut sheet = image::RgbaImage::from_pixel(
        cols * (w + gap) + gap,
        rows * (h + gap) + gap,
        image::Rgba([255, 255, 255, 255]),
    );
    for v in 0..rays.len() {
        let label = format!("view {v}");
        let t = Instant::now();
        let frame = progress.within(1, &label, |counter| prepared.view(v, Watch::from(counter)))?;
        progress.step(&format!(
            "{label} {}x{} {:.1} ms",
            resolution.x,
            resolution.y,
            t.elapsed().as_secs_f64() * 1e3
        ));
        let (col, row) = (v as u32 % cols, v as u32 / cols);
        // Row 0 of the sheet at the top, view 0 first.
        image::imageops::overlay(
            &mut sheet,
            &frame_to_rgba(&frame),
            i64::from(gap + col * (w + gap)),
            i64::from(gap + row * (h + gap)),
        );
    }
    write_rgba_png(&sheet, &out.join("display_views.png")).map_err(|e| runtime(&e))?;
    println!(
        "{}: {} views, {}x{} pixels, each subpixel from its own eye in {interleaved_ms:.1} ms (CPU); wrote {} and {}",
        display.name,
        display.views,
        w,
        h,
        out.join("display_interleaved.png").display(),
        out.join("display_views.png").display()
    );
    Ok(())
}
