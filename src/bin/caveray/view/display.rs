//! A multi-view display in `caveray view`: its interleaved panel beside
//! one of its views, each rendered as `caveray render` renders them (an
//! isosurface per view, on the CPU) on a thread of their own, so the
//! window never waits for them.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::{Arc, Mutex};

use anari_library_caveray::render::Watch;
use glam::UVec2;

use super::compose::{flat_stage, Stage};
use crate::render_display::Prepared;
use crate::scene::VolumeArgs;
use crate::Failure;

/// The display's isosurface, as a fraction of the value range (`render`'s
/// default).
const ISO: f32 = 0.4;

/// An image from the display's thread: slot 0 the panel, 1 a view.
struct Made {
    slot: usize,
    view: Option<u32>,
    size: UVec2,
    pixels: Vec<u8>,
}

pub struct DisplayView {
    want: Sender<u32>,
    made: Receiver<Made>,
    /// The view asked for last, and the one shown.
    asked: Option<u32>,
    shown: Option<u32>,
    panel: bool,
    views: u32,
    scale: f64,
    size: UVec2,
    notes: Arc<Mutex<Vec<String>>>,
    /// Set when the viewer goes: the thread's render stops.
    stop: Arc<AtomicBool>,
}

impl DisplayView {
    pub fn new(config: &Path, volume: &VolumeArgs, scale: f64) -> Result<Self, Failure> {
        let prepared = Prepared::new(config, volume, scale, ISO, Default::default())?;
        let views = prepared.rays.len() as u32;
        let size = prepared.resolution;
        let (want, wanted) = channel::<u32>();
        let (made_tx, made) = channel();
        let notes = Arc::new(Mutex::new(Vec::new()));
        let stop = Arc::new(AtomicBool::new(false));
        let (thread_notes, thread_stop) = (Arc::clone(&notes), Arc::clone(&stop));
        std::thread::Builder::new()
            .name("caveray-view-display".into())
            .spawn(move || render(prepared, wanted, made_tx, thread_notes, thread_stop))
            .map_err(|e| {
                Failure::Runtime(format!("cannot start the display's render thread: {e}"))
            })?;
        Ok(Self {
            want,
            made,
            asked: None,
            shown: None,
            panel: false,
            views,
            scale,
            size,
            notes,
            stop,
        })
    }

    pub fn views(&self) -> u32 {
        self.views
    }

    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Asks for view `v` beside the panel (once; the thread renders the
    /// newest asked for).
    pub fn want(&mut self, v: u32) {
        let v = v.min(self.views.saturating_sub(1));
        if self.asked != Some(v) {
            self.asked = Some(v);
            let _ = self.want.send(v);
        }
    }

    /// The images made since the last call: (slot, size, pixels).
    pub fn take(&mut self) -> Vec<(usize, UVec2, Vec<u8>)> {
        let mut out = Vec::new();
        while let Ok(m) = self.made.try_recv() {
            if m.slot == 0 {
                self.panel = true;
            } else {
                self.shown = m.view;
            }
            out.push((m.slot, m.size, m.pixels));
        }
        out
    }

    /// Whether the panel and view `v` are shown.
    pub fn converged(&self, v: u32) -> bool {
        self.panel && self.shown == Some(v.min(self.views.saturating_sub(1)))
    }

    pub fn notes(&self) -> Vec<String> {
        self.notes.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    pub fn stage(&self, viewport: [f32; 4]) -> Stage {
        flat_stage(viewport, &[self.size, self.size], 0)
    }
}

impl Drop for DisplayView {
    fn drop(&mut self) {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
    }
}

fn render(
    prepared: Prepared,
    wanted: Receiver<u32>,
    made: Sender<Made>,
    notes: Arc<Mutex<Vec<String>>>,
    stop: Arc<AtomicBool>,
) {
    let say = |e: Failure| {
        let (Failure::Usage(m) | Failure::Runtime(m)) = e;
        notes.lock().unwrap_or_else(|e| e.into_inner()).push(m);
    };
    let send = |slot, view, frame: anari_library_caveray::render::Frame| {
        made.send(Made {
            slot,
            view,
            size: frame.size,
            pixels: frame.to_srgb8_top_down(),
        })
        .is_ok()
    };
    match prepared.interleaved(Watch::from(&*stop)) {
        Ok(frame) => {
            if !send(0, None, frame) {
                return;
            }
        }
        Err(e) => say(e),
    }
    while let Ok(mut v) = wanted.recv() {
        // Only the newest view asked for.
        while let Ok(newer) = wanted.try_recv() {
            v = newer;
        }
        match prepared.view(v as usize, Watch::from(&*stop)) {
            Ok(frame) => {
                if !send(1, Some(v), frame) {
                    return;
                }
            }
            Err(e) => say(e),
        }
    }
}
