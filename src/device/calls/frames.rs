//! Frame operations: the frame's snapshot handed to the engine, map and
//! unmap. Calls that need the frame's render finished come in two forms:
//! one that waits (for Rust hosts that own the device) and one that never
//! waits but answers `Err(slot)` while the render runs, for the C layer,
//! which waits on the slot without holding the device and calls again.

use std::sync::Arc;

use glam::UVec2;

use super::Device;
use crate::device::frame::hit_channel_type;
use crate::device::frame::state::{Channel, HIT_CHANNEL_NAMES};
use crate::device::object::ObjectRef;
use crate::device::snapshot::{self, FrameSnapshot};
use crate::device::types::{DataType, StatusCode};
use crate::engine::{Deadline, FrameSlot, OwnEye, Partner, Present, RenderJob, Unpaired};
use crate::render::ColorData;

/// A frame completion callback.
pub type OnDone = Box<dyn FnOnce() + Send>;

/// What a render call does: a whole render on the render thread, or a
/// deadline frame's presentation.
enum Next {
    Render,
    Present(Box<Present>),
}

/// A mapped channel: pointer to the first (lower-left) pixel, size, type.
pub struct Mapped {
    pub ptr: *const u8,
    pub size: UVec2,
    pub ty: DataType,
}

/// Where a mapped channel's pixels are: in the rendered frame, or
/// encoded for the host in a buffer the frame keeps (hit channel i).
enum Pixels {
    Rendered(*const u8),
    Encoded(usize, Vec<u8>),
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

    /// The frame's snapshot: the one kept if nothing changed since it was
    /// taken, else a new one (kept in its turn).
    fn snapshot(&self, frame: &ObjectRef) -> Result<Arc<FrameSnapshot>, String> {
        let epoch = self.epoch;
        let kept = frame.with_frame(|f| match &f.snapshot {
            Some((taken, s)) if *taken == epoch => Some(s.clone()),
            _ => None,
        });
        if let Some(Some(kept)) = kept {
            return kept;
        }
        let taken = snapshot::take(
            frame,
            self.backend(),
            self.gpu_budget(),
            self.stream_wait(),
            self.ranks(),
        )
        .map(Arc::new);
        frame.with_frame(|f| f.snapshot = Some((epoch, taken.clone())));
        taken
    }

    /// `anariRenderFrame`: returns at once; the render thread fills the
    /// frame. `on_done` runs on that thread when the frame is ready. One
    /// render per frame at a time: the previous one finishes first.
    pub fn render_frame(&mut self, handle: u64, on_done: Option<OnDone>) {
        let mut on_done = on_done;
        while let Err(slot) = self.start_render(handle, &mut on_done) {
            drop(slot.wait());
        }
        for done in self.take_due() {
            done();
        }
    }

    /// `render_frame` without waiting: `Err(slot)` while the frame's last
    /// render runs. `on_done` is taken once the call is answered.
    pub fn start_render(
        &mut self,
        handle: u64,
        on_done: &mut Option<OnDone>,
    ) -> Result<(), Arc<FrameSlot>> {
        let Some(frame) = self.frame(handle, "anariRenderFrame") else {
            return Ok(());
        };
        let Some((slot, mapped)) =
            frame.with_frame(|f| (f.renders.slot.clone(), f.mapped.iter().any(|&m| m)))
        else {
            return Ok(());
        };
        if mapped {
            self.error(
                StatusCode::InvalidOperation,
                Some(&frame),
                format!(
                    "anariRenderFrame: {} is mapped; unmap its channels before rendering into it",
                    frame.describe()
                ),
            );
            return Ok(());
        }
        if slot.is_busy() {
            if slot.finishes_here() {
                self.still_rendering(&frame, "anariRenderFrame");
                return Ok(());
            }
            return Err(slot);
        }
        let on_done = on_done.take();
        let next = self.snapshot(&frame).and_then(|snap| {
            let next = match snap.deadline {
                Some(deadline) => {
                    Next::Present(Box::new(self.present_by(&frame, &snap, deadline)?))
                }
                None => Next::Render,
            };
            Ok((next, snap))
        });
        match next {
            Ok((Next::Present(present), snap)) => {
                frame.with_frame(|f| {
                    f.color_type = snap.color_type;
                    f.hit_channels = snap.hit_channels.clone();
                    f.renders.presenting();
                });
                slot.start();
                self.engine.spawn_presenter(*present, on_done);
            }
            Ok((Next::Render, snap)) => {
                let job = frame.with_frame(|f| {
                    f.color_type = snap.color_type;
                    f.hit_channels = snap.hit_channels.clone();
                    f.renders.job(frame.handle, Arc::clone(&snap.inputs))
                });
                let Some(mut job) = job else { return Ok(()) };
                if job.wants_partner() {
                    job.partner = self.partner(&frame, &job);
                }
                slot.start();
                job.on_done = on_done;
                self.engine.submit(job);
            }
            Err(e) => {
                self.error(
                    StatusCode::InvalidOperation,
                    Some(&frame),
                    format!("anariRenderFrame: {}: {e}", frame.describe()),
                );
                // The other ranks of a data-parallel frame wait for this
                // one: it takes part in the frame, saying it cannot render.
                let stand_in = self.ranks().map(|ranks| {
                    let inputs = crate::engine::cannot_render(Arc::clone(ranks), self.backend());
                    frame.with_frame(|f| f.renders.job(frame.handle, Arc::new(inputs)))
                });
                match stand_in.flatten() {
                    Some(mut job) => {
                        slot.start();
                        job.on_done = on_done;
                        self.engine.submit(job);
                    }
                    None => {
                        slot.finish(Err(e), Default::default());
                        // Called once the device is unlocked: the callback
                        // may call into it.
                        self.due.extend(on_done);
                    }
                }
            }
        }
        Ok(())
    }

    /// A call on the render thread (a completion callback) that would wait
    /// for a render queued behind its own, which never ends.
    pub(super) fn still_rendering(&mut self, frame: &ObjectRef, call: &str) {
        self.error(
            StatusCode::InvalidOperation,
            Some(frame),
            format!(
                "{call}: {} is still rendering, on the thread running this frame completion callback, once the callback returns: it cannot be waited for here",
                frame.describe()
            ),
        );
    }

    /// A deadline frame's render, started by the engine.
    fn present_by(
        &mut self,
        frame: &ObjectRef,
        snap: &FrameSnapshot,
        deadline: Deadline,
    ) -> Result<Present, String> {
        let mut warnings = Vec::new();
        let engine = &mut self.engine;
        let present = frame
            .with_frame(|f| {
                engine.begin_deadline(
                    frame.handle,
                    &f.renders,
                    Arc::clone(&snap.inputs),
                    deadline,
                    &mut |w| warnings.push(w),
                )
            })
            .unwrap_or_else(|| Err(format!("{} is not a frame", frame.describe())));
        for w in warnings {
            self.warn(
                Some(frame),
                format!("anariRenderFrame: {} has a deadline: {w}", frame.describe()),
            );
        }
        present
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
        if named.is_none() && !self.pairing {
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
        let own = OwnEye::of(job);
        let mut best: Option<(f64, Partner)> = None;
        for c in &candidates {
            let paired = match &own {
                Err(e) => Err(e.clone()),
                Ok(own) => self
                    .snapshot(c)
                    .map_err(|e| Unpaired::Unsuited(format!("cannot render: {e}")))
                    .and_then(|theirs| {
                        c.with_frame(|f| own.with(c.handle, &theirs.inputs, &f.renders))
                            .unwrap_or_else(|| {
                                Err(Unpaired::Unsuited(format!(
                                    "cannot render: {} is not a frame",
                                    c.describe()
                                )))
                            })
                    }),
            };
            match paired {
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

    /// `anariFrameReady(NO_WAIT)`: whether no render is in flight. (The C
    /// layer waits for `WAIT` itself, without holding the device.)
    pub fn frame_ready(&mut self, handle: u64) -> bool {
        let Some(frame) = self.frame(handle, "anariFrameReady") else {
            return false;
        };
        frame
            .with_frame(|f| !f.renders.slot.is_busy())
            .unwrap_or(false)
    }

    /// `anariMapFrame`: waits for the frame, then lends the channel's pixels
    /// (lower-left first) until `unmap_frame`.
    pub fn map_frame(&mut self, handle: u64, channel_name: &str) -> Option<Mapped> {
        loop {
            match self.try_map_frame(handle, channel_name) {
                Ok(mapped) => return mapped,
                Err(slot) => drop(slot.wait()),
            }
        }
    }

    /// `map_frame` without waiting: `Err(slot)` while a render runs.
    pub fn try_map_frame(
        &mut self,
        handle: u64,
        channel_name: &str,
    ) -> Result<Option<Mapped>, Arc<FrameSlot>> {
        let Some(frame) = self.frame(handle, "anariMapFrame") else {
            return Ok(None);
        };
        let Some(channel) = Channel::parse(channel_name) else {
            self.error(
                StatusCode::InvalidArgument,
                Some(&frame),
                format!("anariMapFrame: unknown channel '{channel_name}'; expected channel.color, channel.depth or one of {}", HIT_CHANNEL_NAMES.join(", ")),
            );
            return Ok(None);
        };
        let Some((slot, color_type, hit_channels, already)) = frame.with_frame(|f| {
            (
                f.renders.slot.clone(),
                f.color_type,
                f.hit_channels.clone(),
                f.mapped[channel.index()],
            )
        }) else {
            return Ok(None);
        };
        let fail = |d: &mut Self, code, m: String| {
            d.error(
                code,
                Some(&frame),
                format!("anariMapFrame: {}: {m}", frame.describe()),
            );
            Ok(None)
        };
        if already {
            return fail(
                self,
                StatusCode::InvalidOperation,
                format!("'{channel_name}' is already mapped; unmap it first"),
            );
        }
        let state = slot.lock();
        if state.busy {
            drop(state);
            if slot.finishes_here() {
                self.still_rendering(&frame, "anariMapFrame");
                return Ok(None);
            }
            return Err(slot);
        }
        let mapped = match &state.result {
            None => Err("the frame has not been rendered yet".to_owned()),
            Some(Err(e)) => Err(format!("the last render failed: {e}")),
            Some(Ok(f)) => match channel {
                Channel::Color => match (color_type, &f.color) {
                    (None, _) => {
                        Err("the frame has no color channel; set 'channel.color'".to_owned())
                    }
                    (Some(ty), ColorData::Rgba8(b) | ColorData::Srgba8(b)) => {
                        Ok((Pixels::Rendered(b.as_ptr()), ty))
                    }
                    (Some(ty), ColorData::Rgba32F(v)) => {
                        Ok((Pixels::Rendered(v.as_ptr().cast()), ty))
                    }
                },
                Channel::Depth => match &f.depth {
                    Some(d) => Ok((Pixels::Rendered(d.as_ptr().cast()), DataType::FLOAT32)),
                    None => Err(
                        "the frame has no depth channel; set 'channel.depth' to FLOAT32".to_owned(),
                    ),
                },
                Channel::Hit(i) => {
                    let name = HIT_CHANNEL_NAMES[i];
                    let format = hit_channels.iter().find(|(n, _)| *n == name);
                    match (format, &f.hits) {
                        (Some((_, format)), Some(hits)) => Ok((
                            Pixels::Encoded(i, format.encode(hits)),
                            hit_channel_type(*format),
                        )),
                        _ => Err(format!("the frame has no {name} channel; set '{name}'")),
                    }
                }
            }
            .map(|(pixels, ty)| (pixels, f.size, ty)),
        };
        drop(state);
        match mapped {
            Ok((pixels, size, ty)) => {
                let ptr = frame.with_frame(|f| {
                    f.mapped[channel.index()] = true;
                    match pixels {
                        Pixels::Rendered(ptr) => ptr,
                        // Kept until unmapped: the host reads through ptr.
                        Pixels::Encoded(i, bytes) => {
                            f.encoded[i] = bytes;
                            f.encoded[i].as_ptr()
                        }
                    }
                });
                Ok(ptr.map(|ptr| Mapped { ptr, size, ty }))
            }
            Err(e) => fail(self, StatusCode::InvalidOperation, e),
        }
    }

    pub fn unmap_frame(&mut self, handle: u64, channel_name: &str) {
        let Some(frame) = self.frame(handle, "anariUnmapFrame") else {
            return;
        };
        let was = Channel::parse(channel_name).and_then(|c| {
            frame.with_frame(|f| {
                if let Channel::Hit(i) = c {
                    f.encoded[i] = Vec::new();
                }
                std::mem::replace(&mut f.mapped[c.index()], false)
            })
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
    /// between rows, the GPU between bands of rows, a deadline frame's
    /// presenter while it waits) and the frame keeps no image of it.
    pub fn discard_frame(&mut self, handle: u64) {
        let Some(frame) = self.frame(handle, "anariDiscardFrame") else {
            return;
        };
        frame.with_frame(|f| f.renders.discard());
    }
}
