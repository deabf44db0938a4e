//! How each kind of job is rendered: one view, a stereo camera's two
//! eyes (one re-projection pass where the stereo decision allows it), a
//! frame with its stereo partner's eye, a multi-view panel, and
//! isosurfaces. Each kind looks at the job's stop flag between its passes
//! and views; the ray casters look at it between rows.

use std::sync::Arc;
use std::time::Duration;

use super::inputs::{EyeView, PanelViews, Views};
use super::job::{Partner, RenderJob};
use super::slot::Kept;
use super::status::{Note, Notify, Severity};
use crate::geometry::MultiViewDisplay;
use crate::render::iso::{interleave, Panel};
use crate::render::stereo::{
    decide, Bounds, Eyes, LayerFormat, LayerRequest, PairChoice, PairCosts, PairPath, RenderFacts,
    Reprojection, StereoFrames, TwoPasses,
};
use crate::render::Render as _;
use crate::render::{ColorFormat, Frame, FrameDesc, RenderError, Renderer};
use crate::scene::Scene;

/// The layers the device re-projects with: as many as the plan needs.
pub const REPROJECTION_LAYERS: LayerRequest = LayerRequest {
    count: None,
    format: LayerFormat::Rgba16F,
};

fn stop_check(job: &RenderJob) -> Result<(), RenderError> {
    if job.stopped() {
        return Err(RenderError::Stopped);
    }
    Ok(())
}

/// The job's views, each into its rectangle of the frame: one render for
/// a single view, one per eye (stitched) for a stereo camera, and one
/// pass for both eyes where re-projection applies: the two eyes of a
/// stereo camera, or the frame's view and its partner frame's, whose share
/// of the pass goes to `handed`. Where the pair could re-project, `costs`
/// says whether it pays on this view and learns what the path taken cost.
pub fn render_views(
    r: &mut Renderer,
    scene: &Scene,
    job: &RenderJob,
    report: &Notify,
    handed: &mut Duration,
    costs: &mut PairCosts,
) -> Result<Frame, RenderError> {
    let info = |message: String| report(Note::frame(Severity::Info, job.frame, message));
    let inputs = &job.inputs;
    // The pose class and the eyes' share of a pair rendered in two passes
    // on cost: the passes' times go to `costs` once they are rendered.
    let mut two_passes: Option<(u32, f64)> = None;
    let mut refused = |costs: &mut PairCosts, class: u32, choice: &PairChoice, eyes: f64| {
        if choice.refuses_reprojection() && costs.first_refusal(job.frame) {
            info(refusal(choice));
        }
        two_passes = Some((class, eyes));
    };
    match (&inputs.views, &job.partner) {
        (Views::StereoPair([left, right]), _) => {
            stop_check(job)?;
            match stereo_camera(r, scene, job, left, right, costs) {
                Ok(Paired::Reprojected(pair, layers)) => {
                    info(format!(
                        "stereo frame: both eyes in one re-projection pass ({layers} layers)"
                    ));
                    return Frame::stitched(
                        &inputs.desc,
                        &[(left.offset, pair.left), (right.offset, pair.right)],
                    );
                }
                Ok(Paired::OnCost(class, choice)) => refused(costs, class, &choice, 1.0),
                Err(why) => {
                    stop_check(job)?;
                    info(format!("stereo frame: two passes ({why})"))
                }
            }
        }
        (Views::Mono(one), Some(partner)) => {
            stop_check(job)?;
            match with_partner(r, scene, job, one, partner, costs) {
                // The partner renders its own eye, as costly as this one.
                Ok(Paired::OnCost(class, choice)) => refused(costs, class, &choice, 2.0),
                Ok(Paired::Reprojected(pair, _)) => {
                    let share = Duration::from_secs_f64(pair.times.composite_ms.max(0.0) / 1e3);
                    partner.slot.keep(Kept {
                        inputs: Arc::clone(&partner.inputs),
                        frame: pair.right,
                        duration: share,
                        by: job.frame,
                    });
                    *handed = share;
                    info(format!(
                        "stereo pair: frame {:#x} and frame {:#x} in one re-projection pass ({} layers)",
                        job.frame, partner.frame, partner.plan.layers
                    ));
                    return Ok(pair.left);
                }
                Err(why) => {
                    stop_check(job)?;
                    info(format!(
                        "stereo pair: frame {:#x} renders alone, not with frame {:#x} ({why})",
                        job.frame, partner.frame
                    ))
                }
            }
        }
        _ => {}
    }
    let render = |r: &mut Renderer, view: &EyeView| {
        let desc = FrameDesc {
            size: view.size,
            ..inputs.desc
        };
        r.render_until(scene, &view.rays, &inputs.settings, &desc, &job.slot.stop)
    };
    let mut pass_ms = 0.0;
    let mut timed = |r: &mut Renderer, view: &EyeView| {
        let frame = render(r, view);
        if let Renderer::Gpu(gpu) = r {
            pass_ms += gpu.last_pass_ms();
        }
        frame
    };
    let frame = match inputs.views.all() {
        [one] if one.size == inputs.desc.size => timed(r, one),
        views => {
            let mut parts = Vec::with_capacity(views.len());
            for view in views.iter().filter(|v| v.size.min_element() > 0) {
                parts.push((view.offset, timed(r, view)?));
            }
            Frame::stitched(&inputs.desc, &parts)
        }
    };
    if let (Ok(_), Some((class, eyes))) = (&frame, two_passes) {
        costs.record_two_passes(job.frame, class, eyes * pass_ms);
    }
    frame
}

/// What a host hears, once per view, when its pairs take two passes
/// because re-projection measured dearer there.
fn refusal(choice: &PairChoice) -> String {
    let ms = |v: Option<f64>| v.map_or("?".into(), |v| format!("{v:.1}"));
    format!(
        "stereo: two passes on this view, where re-projection measured {} ms a pair against {} ms for two passes; re-projection is measured again every {} frames",
        ms(choice.reprojected_ms),
        ms(choice.two_passes_ms),
        PairCosts::PROBE_AFTER
    )
}

/// A pair that could re-project: re-projected (with its layer count), or
/// left to two passes on cost (its pose class, and the choice).
enum Paired {
    Reprojected(StereoFrames, u32),
    OnCost(u32, PairChoice),
}

/// Runs `plan` unless `costs` says two passes are cheaper on this view;
/// a re-projected pair's time goes to `costs`.
fn paid(
    r: &mut Renderer,
    scene: &Scene,
    job: &RenderJob,
    left: &EyeView,
    plan: &Reprojection,
    costs: &mut PairCosts,
) -> Result<Paired, String> {
    let class = plan.plan.family_count();
    let choice = costs.choose(job.frame, class);
    if choice.path == PairPath::TwoPasses {
        return Ok(Paired::OnCost(class, choice));
    }
    let pair = reproject(r, scene, job, left, plan)?;
    let times = pair.times;
    costs.record_reprojected(
        job.frame,
        class,
        times.left_ms + times.composite_ms,
        times.left_ms,
    );
    Ok(Paired::Reprojected(pair, plan.layers))
}

/// What the job's renderer brings to the stereo decision.
fn facts(r: &Renderer, job: &RenderJob) -> RenderFacts {
    RenderFacts {
        reprojects: matches!(r, Renderer::Gpu(_)),
        background_image: job.inputs.settings.background_image.is_some(),
        hits: job.inputs.desc.hits,
    }
}

/// A stereo camera's two eyes from one re-projection pass, the right eye
/// re-projected from the left one's samples, each of its eye's size; or
/// why not. The left eye is cast with its own rays, so it is the image it
/// renders alone.
fn stereo_camera(
    r: &mut Renderer,
    scene: &Scene,
    job: &RenderJob,
    left: &EyeView,
    right: &EyeView,
    costs: &mut PairCosts,
) -> Result<Paired, String> {
    let not_perspective = || "an eye is not a perspective camera".to_owned();
    let eyes = Eyes {
        left: left.matrix.ok_or_else(not_perspective),
        right: right.matrix.ok_or_else(not_perspective),
        sizes: [left.size, right.size],
    };
    let plan = decide(
        eyes,
        Bounds::of(scene),
        REPROJECTION_LAYERS,
        Some(facts(r, job)),
    )
    .map_err(|e| e.to_string())?;
    paid(r, scene, job, left, &plan, costs)
}

/// The frame's view and its partner's from the pass planned when the
/// partner was chosen, if this renderer may run it.
fn with_partner(
    r: &mut Renderer,
    scene: &Scene,
    job: &RenderJob,
    one: &EyeView,
    partner: &Partner,
    costs: &mut PairCosts,
) -> Result<Paired, String> {
    facts(r, job).admit().map_err(|e| e.to_string())?;
    paid(r, scene, job, one, &partner.plan, costs)
}

fn reproject(
    r: &mut Renderer,
    scene: &Scene,
    job: &RenderJob,
    left: &EyeView,
    plan: &Reprojection,
) -> Result<StereoFrames, String> {
    let Renderer::Gpu(gpu) = r else {
        return Err(TwoPasses::NotOnThisRenderer.to_string());
    };
    let desc = FrameDesc {
        size: left.size,
        ..job.inputs.desc
    };
    let stop = &job.slot.stop;
    gpu.render_reprojected_until(scene, &left.rays, plan, &job.inputs.settings, &desc, stop)
        .map_err(|e| e.to_string())
}

/// The last panel's views of each subpixel: a display's pattern stays
/// from frame to frame, and looking every subpixel up costs a frame of a
/// full-size panel tens of milliseconds.
#[derive(Default)]
pub struct KeptPanel(Option<(Arc<MultiViewDisplay>, ViewTable)>);

/// Each subpixel's view, row by row from the lower left.
type ViewTable = Arc<[[u32; 3]]>;

impl KeptPanel {
    fn panel(&mut self, job: &RenderJob, views: &PanelViews) -> Result<Panel, RenderError> {
        let display = &views.display;
        let rays = views.views.iter().map(|v| v.rays).collect();
        let (size, color) = (job.inputs.desc.size, job.inputs.desc.color);
        if let Some((kept, table)) = &self.0 {
            if kept == display && display.resolution == size {
                return Panel::with_table(size, color, rays, table.clone());
            }
        }
        self.0 = None;
        // A stopped job's table is left unfinished, and never kept.
        let stop = &job.slot.stop;
        let panel = Panel::new(size, color, rays, |x, y, c| {
            match stop.load(std::sync::atomic::Ordering::Relaxed) {
                true => 0,
                false => display.view_of(x, y, c),
            }
        })?;
        stop_check(job)?;
        self.0 = Some((display.clone(), panel.table().clone()));
        Ok(panel)
    }
}

/// A multi-view panel's image: of an isosurface by the camera's method;
/// of volumes the naive way (every view rendered, then interleaved), as
/// the per-pixel-eye passes are the isosurface caster's.
pub fn render_panel(
    r: &mut Renderer,
    job: &RenderJob,
    views: &PanelViews,
    kept: &mut KeptPanel,
) -> Result<Frame, RenderError> {
    let panel = kept.panel(job, views)?;
    let inputs = &job.inputs;
    match (&inputs.scene, inputs.surfaces.as_slice()) {
        (Some(scene), _) => {
            // Views in floats: an 8-bit panel is quantised once.
            let desc = FrameDesc::new(panel.size).with_color(ColorFormat::Rgba32F);
            let mut frames = Vec::with_capacity(views.views.len());
            for v in &views.views {
                // Before each view: a large view's buffers take long to
                // make, and a stopped job needs none.
                stop_check(job)?;
                frames.push(r.render_until(
                    scene,
                    &v.rays,
                    &inputs.settings,
                    &desc,
                    &job.slot.stop,
                )?);
            }
            interleave(&frames, &panel)
        }
        (None, [surface]) => {
            stop_check(job)?;
            r.cast_display(surface, &panel, views.method, &job.slot.stop)
        }
        (None, surfaces) => Err(RenderError::Settings(format!(
            "a multi-view panel image shows one isosurface, not {}",
            surfaces.len()
        ))),
    }
}

/// The job's views of its isosurfaces, each into its rectangle of the
/// frame.
pub fn render_surface_views(r: &mut Renderer, job: &RenderJob) -> Result<Frame, RenderError> {
    let inputs = &job.inputs;
    let mut parts = Vec::with_capacity(inputs.views.all().len());
    for view in inputs
        .views
        .all()
        .iter()
        .filter(|v| v.size.min_element() > 0)
    {
        stop_check(job)?;
        let image = inputs.settings.background_image.as_deref();
        // Where the rays miss, the image shows: depth tells where.
        let desc = FrameDesc {
            size: view.size,
            depth: inputs.desc.depth || image.is_some(),
            ..inputs.desc
        };
        let mut frame = r.cast_surfaces(&inputs.surfaces, &view.rays, &desc, &job.slot.stop)?;
        if let Some(image) = image {
            frame.show_background_where_missed(image);
            if !inputs.desc.depth {
                frame.depth = None;
            }
        }
        parts.push((view.offset, frame));
    }
    match parts.as_slice() {
        [(_, one)] if one.size == inputs.desc.size => Ok(parts.remove(0).1),
        _ => Frame::stitched(&inputs.desc, &parts),
    }
}
