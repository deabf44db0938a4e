//! The render thread of a device: `anariRenderFrame` hands it a job and
//! returns; the host waits on the frame's slot.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::mpsc::{channel, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use super::data_parallel;
use super::deadline::{Shot, WARP_LAYERS};
use super::inputs::{Inputs, Views};
use super::job::RenderJob;
use super::passes::{render_panel, render_surface_views, render_views, KeptPanel};
use super::slot::{FrameSlot, DISCARDED};
use super::status::{panic_message, About, Note, Notify, Severity, StatusCode};
use super::threads::join_unless_current;
use crate::render::stereo::PairCosts;
use crate::render::warp::{Source, WarpMode};
use crate::render::{AutoChoice, Backend, Frame, Renderer};

pub struct Worker {
    sender: Option<Sender<RenderJob>>,
    thread: Option<JoinHandle<()>>,
    report: Notify,
    /// The slots of jobs sent and perhaps not finished: a device being
    /// released stops them rather than waiting for them.
    submitted: Vec<Arc<FrameSlot>>,
}

impl Worker {
    pub fn new(report: Notify) -> Self {
        Self {
            sender: None,
            thread: None,
            report,
            submitted: Vec::new(),
        }
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
                    let mut costs = PairCosts::new();
                    for job in rx {
                        match job.background {
                            Some(_) => run_background(job, &mut renderer, &report),
                            None => run(job, &mut renderer, (&mut kept, &mut costs), &report),
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
        if let Some(thread) = &self.thread {
            job.slot.hand_to(thread.thread().id());
        }
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
    /// release returns promptly whatever the render was. A release from
    /// the render thread itself (a completion callback releasing the
    /// device) does not wait for itself: the thread ends once the
    /// callback returns, as nothing can send it jobs any more.
    fn drop(&mut self) {
        for slot in &self.submitted {
            slot.cancel();
        }
        self.sender = None;
        if let Some(t) = self.thread.take() {
            join_unless_current(t);
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

/// The renderer `inputs` ask for, with their volumes uploaded.
fn ready<'a>(
    renderer: &'a mut Option<(Backend, Renderer)>,
    inputs: &Inputs,
    say: &dyn Fn(Severity, String),
) -> Result<&'a mut Renderer, String> {
    let r = renderer_for(renderer, inputs.backend, say)?;
    r.set_gpu_budget(inputs.gpu_budget);
    r.set_stream_wait(inputs.stream_wait);
    if let Some(scene) = &inputs.scene {
        if let Some(why) = r
            .upload_for(inputs.backend, scene)
            .map_err(|e| e.to_string())?
        {
            say(Severity::Warning, why.to_string());
        }
    }
    Ok(r)
}

/// A deadline frame's full render: what warps need of its one view, kept
/// as the frame's newest image.
fn run_background(job: RenderJob, renderer: &mut Option<(Backend, Renderer)>, report: &Notify) {
    let started = Instant::now();
    let Some(back) = &job.background else { return };
    let say = |severity, message: String| report(Note::frame(severity, job.frame, message));
    let inputs = &job.inputs;
    let result = catch_unwind(AssertUnwindSafe(|| -> Result<Source, String> {
        let (Some(scene), Views::Mono(view)) = (&inputs.scene, &inputs.views) else {
            return Err("internal: a background render needs a scene and one view".into());
        };
        let r = renderer_for(renderer, inputs.backend, &say)?;
        r.set_gpu_budget(inputs.gpu_budget);
        r.set_stream_wait(inputs.stream_wait);
        if let Some(why) = r
            .upload_for(inputs.backend, scene)
            .map_err(|e| e.to_string())?
        {
            say(Severity::Warning, why.to_string());
        }
        let layers = if back.warp == WarpMode::Layers {
            WARP_LAYERS
        } else {
            0
        };
        r.capture(
            scene,
            &view.rays,
            &inputs.settings,
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
    let stopped = job.stopped();
    match result {
        Ok(source) => back.target.finish(Some(Shot {
            source,
            inputs: Arc::clone(inputs),
            taken: back.taken,
            took: started.elapsed(),
        })),
        Err(e) => {
            if !stopped {
                report(Note {
                    severity: Severity::Error,
                    code: StatusCode::UnknownError,
                    about: About::Frame(job.frame),
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

fn run(
    job: RenderJob,
    renderer: &mut Option<(Backend, Renderer)>,
    (kept, costs): (&mut KeptPanel, &mut PairCosts),
    report: &Notify,
) {
    let started = Instant::now();
    let note = |severity, code, message: String| Note {
        severity,
        code,
        about: About::Frame(job.frame),
        message,
    };
    if job.unchanged {
        job.slot.finish_unchanged(started.elapsed());
        if let Some(done) = job.on_done {
            done();
        }
        return;
    }
    if let Some(kept) = job.slot.take_kept(&job.inputs) {
        report(note(
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
    let inputs = &job.inputs;
    // The render reads hosts' shared arrays in place: a host taking one
    // back (anariRelease) waits for it to end before its memory is freed.
    let reading: Vec<_> = inputs
        .scene
        .iter()
        .flat_map(|s| s.lenders())
        .map(|l| l.reading())
        .collect();
    // A panic must neither kill the thread nor leave the host waiting.
    let result = catch_unwind(AssertUnwindSafe(|| -> Result<Frame, String> {
        let say = |severity, message| report(note(severity, StatusCode::NoError, message));
        if let Some(share) = &inputs.share {
            // Even an empty world or a missing renderer takes its part in
            // the frame's collectives.
            return data_parallel::render(ready(renderer, inputs, &say), &job, share);
        }
        if inputs.scene.is_none() && inputs.surfaces.is_empty() {
            return Ok(Frame::background(
                &inputs.desc,
                inputs.settings.background,
                inputs.settings.background_image.as_deref(),
            ));
        }
        let r = ready(renderer, inputs, &say)?;
        if let Some(why) = r.fit_surfaces(inputs.backend, &inputs.surfaces) {
            say(Severity::Warning, why.to_string());
        }
        if let Some(why) = inputs
            .scene
            .as_ref()
            .and_then(|scene| crate::render::march_warning(scene, &inputs.settings))
        {
            report(note(Severity::Warning, StatusCode::NoError, why));
        }
        let frame = match (&inputs.views, &inputs.scene) {
            (Views::Panel(panel), _) => render_panel(r, &job, panel, kept),
            (_, Some(scene)) => render_views(r, scene, &job, report, &mut handed, costs),
            (_, None) => render_surface_views(r, &job),
        }
        .map_err(|e| e.to_string())?;
        if let Some(scene) = &inputs.scene {
            let mut s = job.slot.lock();
            s.resident = Some(r.resident_bytes(scene));
            s.progress = Some(r.stream_progress());
        }
        Ok(frame)
    }))
    .unwrap_or_else(|panic| {
        *renderer = None;
        Err(format!("render panicked: {}", panic_message(&panic)))
    });
    // Before the host hears of the frame: its callback may release an
    // array, which waits for the readers.
    drop(reading);
    let discarded = job.stopped();
    let result = match result {
        Err(_) if discarded => Err(DISCARDED.to_owned()),
        other => other,
    };
    if let Some(k) = job.sample {
        let outcome = job.slot.finish_sample(result, started.elapsed());
        if let (Err(e), false) = (outcome, discarded) {
            report(note(
                Severity::Warning,
                StatusCode::UnknownError,
                format!(
                    "frame {:#x}: sample {} of its accumulation failed ({e}); its image stays as it was",
                    job.frame,
                    k + 1
                ),
            ));
        }
        if let Some(done) = job.on_done {
            done();
        }
        return;
    }
    if let Err(e) = &result {
        // A discard is the host's wish, not a failure.
        let severity = if discarded {
            Severity::Info
        } else {
            Severity::Error
        };
        report(note(
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
