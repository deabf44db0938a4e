//! Frame operations: gather the committed scene, hand it to the render
//! thread, wait, map and unmap.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{Mat4, UVec2, Vec3};

use super::Device;
use crate::device::frame::deadline::{present as present_frame, Present, Shot};
use crate::device::frame::slot::Channel;
use crate::device::frame::{self, color_format};
use crate::device::object::{Derived, ObjectRef, State};
use crate::device::types::{kind_name, DataType, StatusCode};
use crate::device::worker::{BackgroundRender, Partner, RenderJob};
use crate::geometry::PrimaryRays;
use crate::render::stereo::{Bounds, LayerFormat, Reprojection};
use crate::render::warp::{Source, WarpMode};
use crate::render::{Backend, ColorData, FrameDesc};
use crate::scene::{PlacedVolume, Scene};

/// What a render call does: a whole render on the render thread, or a
/// deadline frame's presentation.
enum Next {
    Render(Box<RenderJob>),
    Present(Box<Present>),
}

/// Why a frame is not a job's partner.
enum Unpaired {
    /// It cannot be: the host should hear why if it named it.
    Unsuited(String),
    /// Pairing would gain nothing: it already has its image.
    Pointless,
}

/// A mapped channel: pointer to the first (lower-left) pixel, size, type.
pub struct Mapped {
    pub ptr: *const u8,
    pub size: UVec2,
    pub ty: DataType,
}

impl Device {
    fn frame(&mut self, handle: u64, call: &str) -> Option<ObjectRef> {
        let cell = self.lookup(handle, call)?;
        if cell.kind != DataType::FRAME {
            self.error(
                StatusCode::InvalidArgument,
                Some(&cell),
                format!("{call}: {} is not a frame", cell.describe()),
            );
            return None;
        }
        Some(cell)
    }

    /// `anariRenderFrame`: returns at once; the render thread fills the frame.
    /// `on_done` runs on that thread when the frame is ready.
    pub fn render_frame(&mut self, handle: u64, on_done: Option<Box<dyn FnOnce() + Send>>) {
        let Some(frame) = self.frame(handle, "anariRenderFrame") else {
            return;
        };
        let slot = {
            let g = frame.lock();
            let State::Frame(f) = &g.state else { return };
            if f.mapped.iter().any(|&m| m) {
                drop(g);
                self.error(
                    StatusCode::InvalidOperation,
                    Some(&frame),
                    format!(
                        "anariRenderFrame: {} is mapped; unmap its channels before rendering into it",
                        frame.describe()
                    ),
                );
                return;
            }
            f.slot.clone()
        };
        // One render per frame at a time: the previous one finishes first.
        drop(slot.wait());
        let next = self
            .prepare(&frame)
            .and_then(|(job, color_type, deadline)| {
                let next = match deadline {
                    Some((deadline, warp)) => {
                        Next::Present(Box::new(self.present_by(&frame, job, deadline, warp)?))
                    }
                    None => Next::Render(Box::new(job)),
                };
                Ok((next, color_type))
            });
        match next {
            Ok((Next::Present(present), color_type)) => {
                if let State::Frame(f) = &mut frame.lock().state {
                    f.color_type = color_type;
                    f.last = None;
                }
                slot.start();
                self.spawn_presenter(*present, on_done);
            }
            Ok((Next::Render(mut job), color_type)) => {
                // Hosts render unchanged frames again (OpenCOVER up to 64
                // times, to accumulate): the last image stands.
                let inputs = job.inputs();
                if let State::Frame(f) = &mut frame.lock().state {
                    f.color_type = color_type;
                    job.unchanged = f.last.as_ref() == Some(&inputs) && slot.holds_image();
                    f.last = Some(inputs.clone());
                }
                if !job.unchanged && !slot.keeps(&inputs) {
                    job.partner = self.partner(&frame, &job);
                }
                slot.start();
                job.on_done = on_done;
                self.worker.submit(*job);
            }
            Err(e) => {
                self.error(
                    StatusCode::InvalidOperation,
                    Some(&frame),
                    format!("anariRenderFrame: {}: {e}", frame.describe()),
                );
                slot.finish(Err(e), Default::default());
                if let Some(done) = on_done {
                    done();
                }
            }
        }
    }

    /// A deadline frame's render: starts the full render in the background
    /// unless one is running or the newest image is of these inputs, and
    /// says what the presenter needs.
    fn present_by(
        &mut self,
        frame: &ObjectRef,
        job: RenderJob,
        deadline: Duration,
        warp: WarpMode,
    ) -> Result<Present, String> {
        let called = Instant::now();
        if job.panel.is_some() {
            return Err("a frame with caveray.deadline shows one view: set the multi-view camera's 'view', or render the panel image without a deadline".into());
        }
        if !job.surfaces.is_empty() {
            return Err("a frame with caveray.deadline warps volume images; this world holds isosurfaces (render it without a deadline)".into());
        }
        let [view] = job.views.as_slice() else {
            return Err("a frame with caveray.deadline shows one view: set the camera's stereoMode to none (each eye its own frame)".into());
        };
        if job.settings.background_image.is_some() {
            self.warn(
                Some(frame),
                format!(
                    "anariRenderFrame: {} has a deadline: it shows the renderer's background color, not its background image",
                    frame.describe()
                ),
            );
        }
        let background = match &frame.lock().state {
            State::Frame(f) => Arc::clone(&f.background),
            _ => return Err("not a frame".into()),
        };
        let inputs = job.inputs();
        let bounds = job
            .scene
            .as_ref()
            .map_or((Vec3::ZERO, Vec3::ZERO), |s| s.bounds());
        let present = Present {
            background: Arc::clone(&background),
            slot: Arc::clone(&job.slot),
            inputs: inputs.clone(),
            rays: view.rays,
            desc: job.desc,
            color: job.settings.background,
            bounds,
            warp,
            called,
            deadline,
            warper: Arc::clone(&self.warper),
            backend: self.backend(),
            report: self.worker.reporter(),
            frame: frame.handle,
        };
        if job.scene.is_some() {
            if let Some(slot) = background.claim(&inputs) {
                self.worker.submit(RenderJob {
                    slot,
                    background: Some(BackgroundRender {
                        target: background,
                        warp,
                        taken: called,
                    }),
                    ..job
                });
            }
        } else {
            // An empty world: its image is the background, at once.
            background.finish(Some(Shot {
                source: Source::empty(job.desc.size, view.rays, 0).map_err(|e| e.to_string())?,
                inputs,
                taken: called,
            }));
        }
        Ok(present)
    }

    /// Runs the frame's presenter on its own thread: the frame is ready by
    /// its deadline whatever the background render does.
    fn spawn_presenter(&mut self, present: Present, on_done: Option<Box<dyn FnOnce() + Send>>) {
        self.presenters.retain(|p| !p.is_finished());
        let slot = Arc::clone(&present.slot);
        let spawned = std::thread::Builder::new()
            .name("caveray-present".into())
            .spawn(move || {
                present_frame(present);
                if let Some(done) = on_done {
                    done();
                }
            });
        match spawned {
            Ok(thread) => self.presenters.push(thread),
            Err(e) => slot.finish(
                Err(format!("cannot start the frame's presenter: {e}")),
                Default::default(),
            ),
        }
    }

    /// Everything the render thread needs, copied out of the committed
    /// objects so the host may change them while the frame renders.
    #[allow(clippy::type_complexity)]
    fn prepare(
        &mut self,
        frame: &ObjectRef,
    ) -> Result<(RenderJob, Option<DataType>, Option<(Duration, WarpMode)>), String> {
        let params = frame
            .lock()
            .committed
            .clone()
            .ok_or("the frame has not been committed")?;
        let frame::Setup {
            size,
            color_type,
            depth,
            deadline,
        } = frame::setup(&params)?;
        let needed = |name: &str, kind: DataType| -> Result<ObjectRef, String> {
            let o = params.object(name).ok_or_else(|| {
                format!(
                    "no {0}: set parameter '{name}' to a {0} and commit the frame",
                    kind_name(kind)
                )
            })?;
            if !o.implemented {
                return Err(format!("{} is not implemented by caveray", o.describe()));
            }
            Ok(o.clone())
        };
        let camera = needed("camera", DataType::CAMERA)?;
        let renderer = needed("renderer", DataType::RENDERER)?;
        let world = needed("world", DataType::WORLD)?;
        let views = match &camera.lock().state {
            State::Camera(c) => c.ready(&camera.describe())?.views(size)?,
            _ => {
                return Err(format!(
                    "{} cannot be used as the frame's camera",
                    camera.describe()
                ))
            }
        };
        let mut settings = match &renderer.lock().state {
            State::Renderer(r) => r.ready(&renderer.describe())?.clone(),
            _ => {
                return Err(format!(
                    "{} cannot be used as the frame's renderer",
                    renderer.describe()
                ))
            }
        };
        let world_model = match &world.lock().state {
            State::World(w) => w.ready(&world.describe())?.clone(),
            _ => {
                return Err(format!(
                    "{} cannot be used as the frame's world",
                    world.describe()
                ))
            }
        };
        // The first usable directional light lights the shading.
        let light = world_model
            .lights
            .iter()
            .find_map(|l| match &l.lock().state {
                State::Light(Derived::Ready(light)) => Some(*light),
                _ => None,
            });
        if let Some(light) = light {
            settings.light = light.towards;
            settings.light_color = light.color;
        }
        let mut placed = Vec::with_capacity(world_model.volumes.len());
        for (v, transform) in &world_model.volumes {
            let model = match &v.lock().state {
                State::Volume(m) => m.ready(&v.describe())?.clone(),
                _ => return Err(format!("{} is not implemented by caveray", v.describe())),
            };
            let field = &model.field;
            let volume = match &field.lock().state {
                State::Field(f) => f.ready(&field.describe())?.clone(),
                _ => {
                    return Err(format!(
                        "{} is not implemented by caveray",
                        field.describe()
                    ))
                }
            };
            placed.push(PlacedVolume {
                volume,
                transfer_function: model.transfer_function,
                transform: transform.unwrap_or(Mat4::IDENTITY),
            });
        }
        let scene = if placed.is_empty() {
            None
        } else {
            Some(Scene::placed(placed).map_err(|e| format!("{}: {e}", world.describe()))?)
        };
        let surfaces = super::surfaces::iso_surfaces(&world_model.surfaces, &settings, light)?;
        if scene.is_some() && !surfaces.is_empty() {
            return Err(format!(
                "{} holds volumes and surfaces; caveray draws one or the other in a frame (a volume composited with isosurfaces is not implemented)",
                world.describe()
            ));
        }
        let panel = match &camera.lock().state {
            State::Camera(Derived::Ready(c)) => c.panel(size),
            _ => None,
        };
        if panel.is_some() {
            if depth {
                return Err("a multi-view panel image has no depth channel (each subpixel has its own eye): unset 'channel.depth', or set the camera's 'view'".into());
            }
            if surfaces.len() > 1 {
                return Err(format!(
                    "{} has {} isosurfaces (surfaces times iso-values); a multi-view panel image shows one",
                    world.describe(),
                    surfaces.len()
                ));
            }
        }
        let mut desc =
            FrameDesc::new(size).with_color(color_type.and_then(color_format).unwrap_or_default());
        desc.depth = depth;
        let slot = match &frame.lock().state {
            State::Frame(f) => f.slot.clone(),
            _ => return Err(format!("{} is not a frame", frame.describe())),
        };
        let job = RenderJob {
            frame: frame.handle,
            scene,
            surfaces,
            panel,
            views,
            settings,
            desc,
            backend: self.backend(),
            slot,
            on_done: None,
            unchanged: false,
            partner: None,
            background: None,
        };
        Ok((job, color_type, deadline))
    }

    /// The other eye of a stereo pair for `frame`'s job: the frame its
    /// `stereoPartner` names, or, with `pairStereoFrames` on, the device's
    /// frame with the same world, renderer, size and channels whose eye is
    /// nearest, a small baseline away on the same image plane, and whose
    /// inputs have changed since its last render.
    fn partner(&mut self, frame: &ObjectRef, job: &RenderJob) -> Option<Partner> {
        let named = frame
            .lock()
            .committed
            .as_ref()
            .and_then(|p| p.object("stereoPartner").cloned());
        if (named.is_none() && !self.pairing) || self.backend == Backend::Cpu {
            return None;
        }
        let candidates: Vec<ObjectRef> = match &named {
            Some(o) => vec![o.clone()],
            None => self
                .objects
                .values()
                .map(|(o, _)| o)
                .filter(|o| o.kind == DataType::FRAME && o.handle != frame.handle)
                .cloned()
                .collect(),
        };
        let mut best: Option<(f64, Partner)> = None;
        for c in &candidates {
            match self.pair_with(c, job) {
                Ok((baseline, p)) => {
                    if best.as_ref().is_none_or(|b| baseline < b.0) {
                        best = Some((baseline, p));
                    }
                }
                Err(Unpaired::Unsuited(why)) if named.is_some() => self.warn(
                    Some(frame),
                    format!(
                        "anariRenderFrame: {} renders alone: its stereoPartner {} {why}",
                        frame.describe(),
                        c.describe()
                    ),
                ),
                Err(_) => {}
            }
        }
        best.map(|(_, p)| p)
    }

    /// `candidate` as `job`'s partner, with the eyes' distance.
    fn pair_with(
        &mut self,
        candidate: &ObjectRef,
        job: &RenderJob,
    ) -> Result<(f64, Partner), Unpaired> {
        let unsuited = |why: &str| Unpaired::Unsuited(why.to_owned());
        if job.panel.is_some() {
            return Err(Unpaired::Pointless);
        }
        let ([view], Some(scene)) = (job.views.as_slice(), &job.scene) else {
            return Err(Unpaired::Pointless);
        };
        let own = view.matrix.ok_or_else(|| {
            unsuited("is paired with a frame whose camera is not a perspective one")
        })?;
        let (theirs, ..) = self
            .prepare(candidate)
            .map_err(|e| Unpaired::Unsuited(format!("cannot render: {e}")))?;
        if !theirs.scene.as_ref().is_some_and(|s| s.same(scene)) {
            return Err(unsuited("shows another world"));
        }
        if theirs.settings != job.settings || theirs.backend != job.backend {
            return Err(unsuited("has another renderer"));
        }
        if theirs.desc != job.desc {
            return Err(unsuited("differs in size or channels"));
        }
        if theirs.panel.is_some() {
            return Err(unsuited("renders a multi-view panel"));
        }
        let [other] = theirs.views.as_slice() else {
            return Err(unsuited("renders both eyes itself (stereoMode)"));
        };
        let matrix = other
            .matrix
            .ok_or_else(|| unsuited("has a camera that is not a perspective one"))?;
        let (Some(a), Some(b)) = (own.eye(), matrix.eye()) else {
            return Err(unsuited("has a camera that is not a perspective one"));
        };
        let (lo, hi) = scene.bounds();
        let distance = (0.5 * (lo + hi)).as_dvec3().distance(a);
        let baseline = a.distance(b);
        if baseline == 0.0 {
            return Err(unsuited("sees from the same eye"));
        }
        if baseline > 0.25 * distance {
            return Err(Unpaired::Unsuited(format!(
                "has its eye {baseline:.4} away, more than a quarter of the distance to the volume ({distance:.4})"
            )));
        }
        let inputs = theirs.inputs();
        let holds = match &candidate.lock().state {
            State::Frame(f) => f.last.as_ref() == Some(&inputs) && f.slot.holds_image(),
            _ => false,
        };
        if holds || theirs.slot.keeps(&inputs) {
            return Err(Unpaired::Pointless);
        }
        Reprojection::new(
            &own,
            &matrix,
            job.desc.size,
            Bounds::of(scene),
            None,
            LayerFormat::Rgba16F,
        )
        .map_err(|e| Unpaired::Unsuited(format!("cannot be re-projected: {e}")))?;
        Ok((
            baseline,
            Partner {
                frame: candidate.handle,
                view: *other,
                slot: theirs.slot,
                inputs,
            },
        ))
    }

    /// `anariFrameReady(NO_WAIT)`: whether no render is in flight. (The C
    /// layer waits for `WAIT` itself, without holding the device.)
    pub fn frame_ready(&mut self, handle: u64) -> bool {
        let Some(frame) = self.frame(handle, "anariFrameReady") else {
            return false;
        };
        let slot = match &frame.lock().state {
            State::Frame(f) => f.slot.clone(),
            _ => return false,
        };
        !slot.is_busy()
    }

    /// `anariMapFrame`: waits for the frame, then lends the channel's pixels
    /// (lower-left first) until `unmap_frame`.
    pub fn map_frame(&mut self, handle: u64, channel_name: &str) -> Option<Mapped> {
        let frame = self.frame(handle, "anariMapFrame")?;
        let Some(channel) = Channel::parse(channel_name) else {
            self.error(
                StatusCode::InvalidArgument,
                Some(&frame),
                format!("anariMapFrame: unknown channel '{channel_name}'; expected channel.color or channel.depth"),
            );
            return None;
        };
        let (slot, color_type, already) = match &frame.lock().state {
            State::Frame(f) => (f.slot.clone(), f.color_type, f.mapped[channel as usize]),
            _ => return None,
        };
        let fail = |d: &mut Self, code, m: String| {
            d.error(
                code,
                Some(&frame),
                format!("anariMapFrame: {}: {m}", frame.describe()),
            );
            None
        };
        if already {
            return fail(
                self,
                StatusCode::InvalidOperation,
                format!("'{channel_name}' is already mapped; unmap it first"),
            );
        }
        let state = slot.wait();
        let mapped = match &state.result {
            None => Err("the frame has not been rendered yet".to_owned()),
            Some(Err(e)) => Err(format!("the last render failed: {e}")),
            Some(Ok(f)) => match channel {
                Channel::Color => match (color_type, &f.color) {
                    (None, _) => {
                        Err("the frame has no color channel; set 'channel.color'".to_owned())
                    }
                    (Some(ty), ColorData::Rgba8(b) | ColorData::Srgba8(b)) => Ok((b.as_ptr(), ty)),
                    (Some(ty), ColorData::Rgba32F(v)) => Ok((v.as_ptr().cast(), ty)),
                },
                Channel::Depth => match &f.depth {
                    Some(d) => Ok((d.as_ptr().cast(), DataType::FLOAT32)),
                    None => Err(
                        "the frame has no depth channel; set 'channel.depth' to FLOAT32".to_owned(),
                    ),
                },
            }
            .map(|(ptr, ty)| Mapped {
                ptr,
                size: f.size,
                ty,
            }),
        };
        drop(state);
        match mapped {
            Ok(m) => {
                if let State::Frame(f) = &mut frame.lock().state {
                    f.mapped[channel as usize] = true;
                }
                Some(m)
            }
            Err(e) => fail(self, StatusCode::InvalidOperation, e),
        }
    }

    pub fn unmap_frame(&mut self, handle: u64, channel_name: &str) {
        let Some(frame) = self.frame(handle, "anariUnmapFrame") else {
            return;
        };
        let was = Channel::parse(channel_name).and_then(|c| match &mut frame.lock().state {
            State::Frame(f) => Some(std::mem::replace(&mut f.mapped[c as usize], false)),
            _ => None,
        });
        if was != Some(true) {
            self.error(
                StatusCode::InvalidOperation,
                Some(&frame),
                format!(
                    "anariUnmapFrame: '{channel_name}' of {} is not mapped",
                    frame.describe()
                ),
            );
        }
    }

    /// `anariDiscardFrame`: the render in flight stops (the CPU reference
    /// between rows, the GPU between bands of rows) and the frame keeps no
    /// image of it.
    pub fn discard_frame(&mut self, handle: u64) {
        let Some(frame) = self.frame(handle, "anariDiscardFrame") else {
            return;
        };
        if let State::Frame(f) = &mut frame.lock().state {
            f.slot.cancel();
            f.background.cancel();
            // What was kept no longer stands for the frame's next render.
            f.last = None;
        };
    }
}
