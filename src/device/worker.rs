//! The render thread of a device: `anariRenderFrame` hands it a job and
//! returns; the host waits on the frame's slot.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::mpsc::{channel, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::camera::stereo::EyeView;
use super::frame::deadline::{Background, Shot};
use super::frame::slot::{FrameSlot, Kept};
use super::types::{DataType, Severity, Status, StatusCode};
use crate::geometry::MultiViewDisplay;
use crate::render::iso::{interleave, IsoSurface, MultiViewMethod, Panel};
use crate::render::stereo::{Bounds, LayerFormat, Reprojection, StereoFrames};
use crate::render::warp::{Source, WarpMode};
use crate::render::Render as _;
use crate::render::{
    AutoChoice, Backend, ColorFormat, Frame, FrameDesc, RenderError, RenderSettings, Renderer,
};
use crate::scene::Scene;

/// Where a device's status messages go; called from any thread.
pub type Reporter = Arc<dyn Fn(Status) + Send + Sync>;

/// What a render depends on, to tell an unchanged frame: the scene by
/// identity (a commit makes new derived values, so any change makes new
/// ones), everything else by value.
#[derive(Clone)]
pub struct RenderInputs {
    scene: Option<Scene>,
    surfaces: Vec<IsoSurface>,
    panel: Option<PanelJob>,
    views: Vec<EyeView>,
    settings: RenderSettings,
    desc: FrameDesc,
    backend: Backend,
}

impl PartialEq for RenderInputs {
    fn eq(&self, other: &Self) -> bool {
        let same_scene = match (&self.scene, &other.scene) {
            (None, None) => true,
            (Some(a), Some(b)) => a.same(b),
            _ => false,
        };
        same_scene
            && self.surfaces.len() == other.surfaces.len()
            && self
                .surfaces
                .iter()
                .zip(&other.surfaces)
                .all(|(a, b)| a.same(b))
            && self.panel == other.panel
            && self.views == other.views
            && self.settings == other.settings
            && self.desc == other.desc
            && self.backend == other.backend
    }
}

/// A multi-view camera's panel image: which view each subpixel shows,
/// and how the image is made.
pub type PanelJob = (Arc<MultiViewDisplay>, MultiViewMethod);

pub struct RenderJob {
    pub frame: u64,
    /// The world's volumes; `None` with no `surfaces` renders the
    /// background only (an empty world).
    pub scene: Option<Scene>,
    /// The world's isosurfaces (a world holds volumes or surfaces).
    pub surfaces: Vec<IsoSurface>,
    /// `Some`: `views` are a multi-view panel's, interleaved subpixel by
    /// subpixel into one image.
    pub panel: Option<PanelJob>,
    /// One view of the whole frame, or the two eyes of a stereo camera.
    pub views: Vec<EyeView>,
    pub settings: RenderSettings,
    pub desc: FrameDesc,
    pub backend: Backend,
    pub slot: Arc<FrameSlot>,
    pub on_done: Option<Box<dyn FnOnce() + Send>>,
    /// The frame's last image is still right: keep it, render nothing.
    pub unchanged: bool,
    /// Another frame's eye to render with this one in one pass.
    pub partner: Option<Partner>,
    /// A deadline frame's background render: its image goes there, not
    /// into `slot` (which only tracks the render).
    pub background: Option<BackgroundRender>,
}

/// Where a deadline frame's full render goes, and what it must keep.
pub struct BackgroundRender {
    pub target: Arc<Background>,
    pub warp: WarpMode,
    /// When the camera it renders was taken.
    pub taken: Instant,
}

/// Layers a background render keeps for the `layers` warp.
const DEVICE_LAYERS: usize = 4;

/// The other eye of a stereo pair, shown by another frame of the device:
/// rendered with the job in one re-projection pass and kept for that
/// frame's next render.
pub struct Partner {
    pub frame: u64,
    pub view: EyeView,
    pub slot: Arc<FrameSlot>,
    /// What that frame's render must ask for to be given the image.
    pub inputs: RenderInputs,
}

pub struct Worker {
    sender: Option<Sender<RenderJob>>,
    thread: Option<JoinHandle<()>>,
    report: Reporter,
    /// The slots of jobs sent and perhaps not finished: a device being
    /// released stops them rather than waiting for them.
    submitted: Vec<Arc<FrameSlot>>,
}

impl RenderJob {
    pub fn inputs(&self) -> RenderInputs {
        RenderInputs {
            scene: self.scene.clone(),
            surfaces: self.surfaces.clone(),
            panel: self.panel.clone(),
            views: self.views.clone(),
            settings: self.settings.clone(),
            desc: self.desc,
            backend: self.backend,
        }
    }
}

impl Worker {
    pub fn new(report: Reporter) -> Self {
        Self {
            sender: None,
            thread: None,
            report,
            submitted: Vec::new(),
        }
    }

    /// Where the render thread's messages go.
    pub fn reporter(&self) -> Reporter {
        Arc::clone(&self.report)
    }

    pub fn submit(&mut self, job: RenderJob) {
        if self.sender.is_none() {
            let (tx, rx) = channel::<RenderJob>();
            let report = self.report.clone();
            let spawned = std::thread::Builder::new()
                .name("caveray-render".into())
                .spawn(move || {
                    let mut renderer = None;
                    let mut kept = KeptPanel::default();
                    for job in rx {
                        match job.background {
                            Some(_) => run_background(job, &mut renderer, &report),
                            None => run(job, &mut renderer, &mut kept, &report),
                        }
                    }
                });
            match spawned {
                Ok(thread) => {
                    self.sender = Some(tx);
                    self.thread = Some(thread);
                }
                Err(e) => {
                    job.slot.finish(
                        Err(format!("cannot start the render thread: {e}")),
                        Default::default(),
                    );
                    return;
                }
            }
        }
        self.submitted.retain(|s| s.is_busy());
        self.submitted.push(Arc::clone(&job.slot));
        if let Some(tx) = &self.sender {
            if let Err(e) = tx.send(job) {
                e.0.slot.finish(
                    Err("the render thread has stopped".into()),
                    Default::default(),
                );
            }
        }
    }
}

impl Drop for Worker {
    /// Stops what is running and queued, then waits for the thread: a
    /// release returns promptly whatever the render was.
    fn drop(&mut self) {
        for slot in &self.submitted {
            slot.cancel();
        }
        self.sender = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The renderer for `backend`, made (and said so) when it changes.
fn renderer_for<'a>(
    renderer: &'a mut Option<(Backend, Renderer)>,
    backend: Backend,
    say: &dyn Fn(Severity, String),
) -> Result<&'a mut Renderer, String> {
    if renderer.as_ref().map(|r| r.0) != Some(backend) {
        *renderer = None;
        let (made, why) = Renderer::choose(backend).map_err(|e| e.to_string())?;
        match why {
            // A missing GPU is worth a warning; a software adapter passed
            // over is the right choice, said for the record.
            Some(why @ AutoChoice::NoGpu(_)) => say(Severity::Warning, why.to_string()),
            Some(why) => say(Severity::Info, why.to_string()),
            None => {}
        }
        say(
            Severity::Info,
            format!("rendering with {}", made.describe()),
        );
        *renderer = Some((backend, made));
    }
    match renderer.as_mut() {
        Some((_, r)) => Ok(r),
        None => Err("no renderer could be made".into()),
    }
}

/// A deadline frame's full render: what warps need of its one view, kept
/// as the frame's newest image.
fn run_background(job: RenderJob, renderer: &mut Option<(Backend, Renderer)>, report: &Reporter) {
    let started = Instant::now();
    let Some(back) = &job.background else { return };
    let say = |severity, message: String| {
        report(Status {
            severity,
            code: StatusCode::NoError,
            source: job.frame,
            source_kind: DataType::FRAME,
            message,
        })
    };
    let result = catch_unwind(AssertUnwindSafe(|| -> Result<Source, String> {
        let (Some(scene), [view]) = (&job.scene, job.views.as_slice()) else {
            return Err("internal: a background render needs a scene and one view".into());
        };
        let r = renderer_for(renderer, job.backend, &say)?;
        let layers = if back.warp == WarpMode::Layers {
            DEVICE_LAYERS
        } else {
            0
        };
        r.capture(
            scene,
            &view.rays,
            &job.settings,
            view.size,
            layers,
            &job.slot.stop,
        )
        .map(|(source, _)| source)
        .map_err(|e| e.to_string())
    }))
    .unwrap_or_else(|panic| {
        *renderer = None;
        Err(format!("render panicked: {}", panic_message(&panic)))
    });
    let stopped = job.slot.stop.load(std::sync::atomic::Ordering::Relaxed);
    match result {
        Ok(source) => back.target.finish(Some(Shot {
            source,
            inputs: job.inputs(),
            taken: back.taken,
        })),
        Err(e) => {
            if !stopped {
                report(Status {
                    severity: Severity::Error,
                    code: StatusCode::UnknownError,
                    source: job.frame,
                    source_kind: DataType::FRAME,
                    message: format!(
                        "the background render of frame {:#x} failed: {e}",
                        job.frame
                    ),
                });
            }
            back.target.finish(None);
        }
    }
    job.slot
        .finish(Err("background render".into()), started.elapsed());
}

/// The last panel's views of each subpixel: a display's pattern stays
/// from frame to frame, and looking every subpixel up costs a frame of a
/// full-size panel tens of milliseconds.
#[derive(Default)]
struct KeptPanel(Option<(Arc<MultiViewDisplay>, ViewTable)>);

/// Each subpixel's view, row by row from the lower left.
type ViewTable = Arc<[[u32; 3]]>;

impl KeptPanel {
    fn panel(
        &mut self,
        job: &RenderJob,
        display: &Arc<MultiViewDisplay>,
    ) -> Result<Panel, RenderError> {
        let views = job.views.iter().map(|v| v.rays).collect();
        let (size, color) = (job.desc.size, job.desc.color);
        if let Some((kept, table)) = &self.0 {
            if kept == display && display.resolution == size {
                return Panel::with_table(size, color, views, table.clone());
            }
        }
        self.0 = None;
        let panel = Panel::new(size, color, views, |x, y, c| display.view_of(x, y, c))?;
        self.0 = Some((display.clone(), panel.table().clone()));
        Ok(panel)
    }
}

fn run(
    job: RenderJob,
    renderer: &mut Option<(Backend, Renderer)>,
    kept: &mut KeptPanel,
    report: &Reporter,
) {
    let started = Instant::now();
    let status = |severity, code, message: String| Status {
        severity,
        code,
        source: job.frame,
        source_kind: DataType::FRAME,
        message,
    };
    if job.unchanged {
        job.slot.finish_unchanged(started.elapsed());
        if let Some(done) = job.on_done {
            done();
        }
        return;
    }
    if let Some(kept) = job.slot.take_kept(&job.inputs()) {
        report(status(
            Severity::Info,
            StatusCode::NoError,
            format!(
                "stereo pair: frame {:#x} shows the eye frame {:#x}'s pass re-projected for it",
                job.frame, kept.by
            ),
        ));
        job.slot.finish(Ok(kept.frame), kept.duration);
        if let Some(done) = job.on_done {
            done();
        }
        return;
    }
    let mut handed = Duration::ZERO;
    // A panic must neither kill the thread nor leave the host waiting.
    let result = catch_unwind(AssertUnwindSafe(|| -> Result<Frame, String> {
        if job.scene.is_none() && job.surfaces.is_empty() {
            return Ok(Frame::cleared(&job.desc, job.settings.background));
        }
        let r = renderer_for(renderer, job.backend, &|severity, message| {
            report(status(severity, StatusCode::NoError, message))
        })?;
        if let Some(why) = job
            .scene
            .as_ref()
            .and_then(|scene| crate::render::march_warning(scene, &job.settings))
        {
            report(status(Severity::Warning, StatusCode::NoError, why));
        }
        match (&job.panel, &job.scene) {
            (Some(panel), _) => render_panel(r, &job, panel, kept),
            (None, Some(scene)) => render_views(r, scene, &job, report, &mut handed),
            (None, None) => render_surface_views(r, &job),
        }
        .map_err(|e| e.to_string())
    }))
    .unwrap_or_else(|panic| {
        *renderer = None;
        Err(format!("render panicked: {}", panic_message(&panic)))
    });
    let discarded = job.slot.stop.load(std::sync::atomic::Ordering::Relaxed);
    let result = match result {
        Err(_) if discarded => Err("the render was discarded (anariDiscardFrame)".to_owned()),
        other => other,
    };
    if let Err(e) = &result {
        // A discard is the host's wish, not a failure.
        let severity = if discarded {
            Severity::Info
        } else {
            Severity::Error
        };
        report(status(
            severity,
            StatusCode::UnknownError,
            format!("rendering frame {:#x} failed: {e}", job.frame),
        ));
    }
    // The partner's share of a paired pass is its frame's duration.
    job.slot
        .finish(result, started.elapsed().saturating_sub(handed));
    if let Some(done) = job.on_done {
        done();
    }
}

/// The job's views, each into its rectangle of the frame: one render for
/// a single view, one per eye (stitched) for a stereo camera, and one
/// pass for both eyes where re-projection applies: the two eyes of a
/// stereo camera, or the frame's view and its partner frame's, whose share
/// of the pass goes to `handed`.
fn render_views(
    r: &mut Renderer,
    scene: &Scene,
    job: &RenderJob,
    report: &Reporter,
    handed: &mut Duration,
) -> Result<Frame, RenderError> {
    let info = |message: String| {
        report(Status {
            severity: Severity::Info,
            code: StatusCode::NoError,
            source: job.frame,
            source_kind: DataType::FRAME,
            message,
        })
    };
    match (job.views.as_slice(), &job.partner) {
        ([left, right], _) => match reprojected(r, scene, job, left, right) {
            Ok((pair, layers)) => {
                info(format!(
                    "stereo frame: both eyes in one re-projection pass ({layers} layers)"
                ));
                return Frame::stitched(
                    &job.desc,
                    &[(left.offset, pair.left), (right.offset, pair.right)],
                );
            }
            Err(why) => info(format!("stereo frame: two passes ({why})")),
        },
        ([one], Some(partner)) => match reprojected(r, scene, job, one, &partner.view) {
            Ok((pair, layers)) => {
                let share = Duration::from_secs_f64(pair.times.composite_ms.max(0.0) / 1e3);
                partner.slot.keep(Kept {
                    inputs: partner.inputs.clone(),
                    frame: pair.right,
                    duration: share,
                    by: job.frame,
                });
                *handed = share;
                info(format!(
                    "stereo pair: frame {:#x} and frame {:#x} in one re-projection pass ({layers} layers)",
                    job.frame, partner.frame
                ));
                return Ok(pair.left);
            }
            Err(why) => info(format!(
                "stereo pair: frame {:#x} renders alone, not with frame {:#x} ({why})",
                job.frame, partner.frame
            )),
        },
        _ => {}
    }
    let render = |r: &mut Renderer, view: &EyeView| {
        let desc = FrameDesc {
            size: view.size,
            ..job.desc
        };
        r.render_until(scene, &view.rays, &job.settings, &desc, &job.slot.stop)
    };
    match job.views.as_slice() {
        [one] if one.size == job.desc.size => render(r, one),
        views => {
            let mut parts = Vec::with_capacity(views.len());
            for view in views.iter().filter(|v| v.size.min_element() > 0) {
                parts.push((view.offset, render(r, view)?));
            }
            Frame::stitched(&job.desc, &parts)
        }
    }
}

/// A multi-view panel's image: of an isosurface by the camera's method;
/// of volumes the naive way (every view rendered, then interleaved), as
/// the per-pixel-eye passes are the isosurface caster's.
fn render_panel(
    r: &mut Renderer,
    job: &RenderJob,
    (display, method): &PanelJob,
    kept: &mut KeptPanel,
) -> Result<Frame, RenderError> {
    let panel = kept.panel(job, display)?;
    match (&job.scene, job.surfaces.as_slice()) {
        (Some(scene), _) => {
            // Views in floats: an 8-bit panel is quantised once.
            let desc = FrameDesc::new(panel.size).with_color(ColorFormat::Rgba32F);
            let mut views = Vec::with_capacity(job.views.len());
            for v in &job.views {
                views.push(r.render_until(scene, &v.rays, &job.settings, &desc, &job.slot.stop)?);
            }
            interleave(&views, &panel)
        }
        (None, [surface]) => r.cast_display(surface, &panel, *method),
        (None, surfaces) => Err(RenderError::Settings(format!(
            "a multi-view panel image shows one isosurface, not {}",
            surfaces.len()
        ))),
    }
}

/// The job's views of its isosurfaces, each into its rectangle of the
/// frame.
fn render_surface_views(r: &mut Renderer, job: &RenderJob) -> Result<Frame, RenderError> {
    let mut parts = Vec::with_capacity(job.views.len());
    for view in job.views.iter().filter(|v| v.size.min_element() > 0) {
        let desc = FrameDesc {
            size: view.size,
            ..job.desc
        };
        parts.push((
            view.offset,
            r.cast_surfaces(&job.surfaces, &view.rays, &desc)?,
        ));
    }
    match parts.as_slice() {
        [(_, one)] if one.size == job.desc.size => Ok(parts.remove(0).1),
        _ => Frame::stitched(&job.desc, &parts),
    }
}

/// Both eyes from one re-projection pass, the right eye re-projected from
/// the left one's samples, each of its eye's size; or why not. The left
/// eye is cast with its own rays, so it is the image it renders alone.
fn reprojected(
    r: &mut Renderer,
    scene: &Scene,
    job: &RenderJob,
    left: &EyeView,
    right: &EyeView,
) -> Result<(StereoFrames, u32), String> {
    let Renderer::Gpu(gpu) = r else {
        return Err("re-projection runs on the GPU renderer only".into());
    };
    let (Some(l), Some(rm)) = (left.matrix, right.matrix) else {
        return Err("an eye is not a perspective camera".into());
    };
    if left.size != right.size {
        return Err(format!(
            "the eyes differ in size ({}x{} and {}x{}); give the frame an even split",
            left.size.x, left.size.y, right.size.x, right.size.y
        ));
    }
    if job.settings.background_image.is_some() {
        return Err("re-projection takes a background color, not an image".into());
    }
    let plan = Reprojection::new(
        &l,
        &rm,
        left.size,
        Bounds::of(scene),
        None,
        LayerFormat::Rgba16F,
    )
    .map_err(|e| e.to_string())?;
    let desc = FrameDesc {
        size: left.size,
        ..job.desc
    };
    let pair = gpu
        .render_reprojected(scene, &left.rays, &plan, &job.settings, &desc)
        .map_err(|e| e.to_string())?;
    Ok((pair, plan.layers))
}

pub fn panic_message(panic: &Box<dyn std::any::Any + Send>) -> String {
    panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}
