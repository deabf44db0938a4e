//! `caveray view`: a rig on the desktop, live. Every wall and eye is a
//! deadline frame of the device's engine (`live`), rendered off-axis for
//! the simulated head exactly as `caveray render` renders it; the window
//! shows the walls as a person would stand among them (`compose`), with
//! egui's controls and an overlay of per-wall figures (`panel`). The head
//! walks and turns by keys and drags (`controls`). In a window (`window`)
//! or without one (`--headless-frames`).

mod compose;
mod controls;
mod display;
mod live;
mod panel;
mod rig;
mod scenes;
mod window;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anari_library_caveray::engine::Deadline;
use anari_library_caveray::render::warp::WarpMode;
use clap::Args;
use glam::{DVec3, UVec2};
use serde::Serialize;

use crate::options::RenderOptions;
use crate::scene::VolumeArgs;
use crate::{Failure, Given, HeadArgs};

use compose::{Composer, Gpu, Overlay, Stage};
use controls::{Controls, Held, Look, Rendering, Stereo};
use display::DisplayView;
use panel::{Figures, WallFigures};
use rig::{PaneReport, RigShow};

#[derive(Args)]
pub struct ViewArgs {
    /// Rig file (TOML), e.g. cave_configs/cologne_5wall.toml; or a
    /// multi-view display (its interleaved panel and one view).
    #[arg(long)]
    config: PathBuf,
    #[command(flatten)]
    volume: VolumeArgs,
    #[command(flatten)]
    head: HeadArgs,
    #[command(flatten)]
    render: RenderOptions,
    /// Render each wall at this fraction of its resolution.
    #[arg(long, default_value_t = 0.1)]
    scale: f64,
    /// Window (and headless canvas) size WIDTHxHEIGHT.
    #[arg(long, default_value = "800x600", value_parser = window_size)]
    size: UVec2,
    /// Display refreshes a second (default: the monitor's, else 60).
    #[arg(long)]
    hz: Option<f64>,
    /// How long after its render call each wall's frame must be ready
    /// (ms; default: one refresh).
    #[arg(long)]
    deadline: Option<f32>,
    /// How an older image is brought to the current head: none, quad,
    /// grid or layers.
    #[arg(long, default_value = "quad")]
    warp: WarpMode,
    /// left, right, anaglyph or side-by-side.
    #[arg(long, default_value = "left")]
    eyes: Stereo,
    /// outside, head or flat: how the rig is seen at the start (V switches).
    #[arg(long, default_value = "outside")]
    look: Look,
    /// Play the rig's head path from the start.
    #[arg(long)]
    play: bool,
    /// Start with the controls hidden (H shows them).
    #[arg(long)]
    no_controls: bool,
    /// Render this many displayed frames without a window, then stop.
    #[arg(long)]
    headless_frames: Option<u64>,
    /// In a window, stop after this many displayed frames.
    #[arg(long)]
    frames: Option<u64>,
    /// Where screenshots go: F12 writes one once every wall shows its own
    /// image (FILE, then FILE-2, ...); headless, the last frame.
    #[arg(long)]
    screenshot: Option<PathBuf>,
    /// Also write a strip of this many frames, evenly spread over the
    /// run, beside the screenshot (headless).
    #[arg(long)]
    strip: Option<u32>,
    /// Write the run's figures (frame rate, each wall's frames, ages,
    /// warps, late frames) here when it ends.
    #[arg(long)]
    json: Option<PathBuf>,
}

fn window_size(s: &str) -> Result<UVec2, String> {
    let parsed = s
        .split_once('x')
        .and_then(|(w, h)| Some((w.trim().parse::<u32>().ok()?, h.trim().parse::<u32>().ok()?)));
    match parsed {
        Some((w, h)) if (64..=8192).contains(&w) && (64..=8192).contains(&h) => {
            Ok(UVec2::new(w, h))
        }
        _ => Err(format!(
            "expected WIDTHxHEIGHT, each 64 to 8192 pixels, got '{s}'"
        )),
    }
}

/// A key or button that does something once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Action {
    NextLook,
    NextStereo,
    TogglePlay,
    ResetHead,
    Screenshot,
    TogglePanel,
    ToggleFigures,
    /// Moves the volume by this fraction of the rig's size.
    MoveVolume(DVec3),
    Quit,
}

/// What the person did since the last refresh.
#[derive(Default)]
pub struct Input {
    pub held: Held,
    /// Left drag: turns the head; with shift, the volume.
    pub drag_head: (f64, f64),
    pub drag_volume: (f64, f64),
    /// Right drag: orbits the outside observer.
    pub drag_orbit: (f64, f64),
    pub zoom: f64,
    pub actions: Vec<Action>,
}

/// What the viewer shows: a rig's walls, or a multi-view display.
enum Shown {
    Rig(Box<RigShow>),
    Display(DisplayView),
}

/// Screenshots asked for and not written yet.
struct Shots {
    path: Option<PathBuf>,
    taken: u32,
    /// Asked for at (waiting for the walls to converge).
    pending: Option<Instant>,
}

/// How long a screenshot waits for every wall's own image.
const SHOT_PATIENCE: Duration = Duration::from_secs(60);

pub struct Viewer {
    shown: Shown,
    controls: Controls,
    rest: (DVec3, DVec3),
    gpu: Gpu,
    composer: Composer,
    egui: egui::Context,
    hz: f64,
    shots: Shots,
    frames: Vec<f64>,
    last_frame: Option<Instant>,
    fps: f64,
    frame_ms: f64,
    started: Instant,
    config: String,
    /// The volume's name (a rig's; a display's is in its file).
    volume_name: String,
    converged: bool,
    quit: bool,
    renderer_label: String,
    /// Laid flat: where each image is on the canvas (x, y, w, h).
    rects: Vec<[u32; 4]>,
    /// When egui last ran, when it asked to run again, and the canvas's
    /// part (x, y, w, h in pixels) it left for the rig.
    ui_at: Option<Instant>,
    ui_again: Instant,
    viewport: [f32; 4],
}

/// How often the overlay's figures are drawn anew.
const UI_PERIOD: Duration = Duration::from_millis(250);

/// What a screenshot's sidecar (`FILE.json`) says: the head it shows,
/// whether every wall showed its own image, and where each wall's image is
/// when laid flat.
#[derive(Serialize)]
struct ShotInfo {
    head: [f64; 3],
    head_ypr: [f64; 3],
    converged: bool,
    look: &'static str,
    eyes: &'static str,
    walls: Vec<ShotWall>,
}

#[derive(Serialize)]
struct ShotWall {
    name: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    rect: Option<[u32; 4]>,
}

/// What `--json` writes when the run ends.
#[derive(Serialize)]
struct Report {
    config: String,
    volume: String,
    window: [u32; 2],
    adapter: String,
    backend: String,
    hz: f64,
    deadline_ms: f32,
    warp: &'static str,
    eyes: &'static str,
    scale: f64,
    frames: u64,
    seconds: f64,
    /// Displayed frames a second over the run.
    fps: f64,
    frame_ms: Percentiles,
    converged: bool,
    walls: Vec<PaneReport>,
}

#[derive(Serialize)]
struct Percentiles {
    mean: f64,
    p50: f64,
    p95: f64,
    max: f64,
}

pub fn run(args: ViewArgs, given: &Given) -> Result<(), Failure> {
    if crate::render_display::is_display(&args.config) {
        given.refuse(
            &[
                "--head",
                "--head-ypr",
                "--time",
                "--play",
                "--eyes",
                "--look",
                "--warp",
                "--deadline",
                "--strategy",
                "--shading",
                "--backend",
                "--step-factor",
                "--gpu-sampling",
            ],
            ["does", "do"],
            "not apply to a multi-view display, which shows its panel and one view, each an \
             isosurface rendered on the CPU from the display's own eye line",
        )?;
    }
    if !(args.scale.is_finite() && args.scale > 0.0 && args.scale <= 4.0) {
        return Err(Failure::Usage(format!(
            "--scale must be in (0, 4], got {}",
            args.scale
        )));
    }
    if let Some(hz) = args.hz {
        if !(hz.is_finite() && (1.0..=1000.0).contains(&hz)) {
            return Err(Failure::Usage(format!("--hz must be 1 to 1000, got {hz}")));
        }
    }
    if let Some(d) = args.deadline {
        if !(d.is_finite() && (1.0..=10_000.0).contains(&d)) {
            return Err(Failure::Usage(format!(
                "--deadline must be 1 to 10000 ms, got {d}"
            )));
        }
    }
    if args.strip.is_some() && (args.headless_frames.is_none() || args.screenshot.is_none()) {
        return Err(Failure::Usage(
            "--strip goes with --headless-frames and --screenshot (it is written beside the screenshot)".into(),
        ));
    }
    if args.strip == Some(0) {
        return Err(Failure::Usage("--strip must be at least 1".into()));
    }
    yield_renders_to_display();
    match args.headless_frames {
        Some(0) => Err(Failure::Usage(
            "--headless-frames must be at least 1".into(),
        )),
        Some(n) => headless(args, n),
        None => window::run(args),
    }
}

/// The nice value of the CPU ray caster's workers: the lowest priority
/// that still gets a share of a busy machine (SCHED_IDLE would get none,
/// and a machine busy with other work would never see the walls converge).
const RENDER_NICENESS: i32 = 19;

/// Lowers the priority of rayon's global pool, where the CPU ray caster
/// works: on a machine of few cores, the window's frames and the deadline
/// frames' warps (on a pool of their own) then keep the display's rate,
/// and the background renders take the time that is left, which is what
/// asynchronous rendering assumes of them.
fn yield_renders_to_display() {
    rayon::broadcast(|_| {
        // SAFETY: a plain system call on this thread's own id.
        unsafe {
            let tid = libc::gettid();
            libc::setpriority(libc::PRIO_PROCESS, tid as libc::id_t, RENDER_NICENESS);
        }
    });
}

/// N displayed frames at the display's rate, into the canvas alone.
fn headless(args: ViewArgs, frames: u64) -> Result<(), Failure> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::VULKAN,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let gpu = Gpu::open(&instance, None)?;
    let strip_every = args.strip.map(|k| (frames / u64::from(k)).max(1));
    let mut viewer = Viewer::new(&args, gpu, None, args.size)?;
    let period = Duration::from_secs_f64(1.0 / viewer.hz);
    let mut strip = Vec::new();
    let mut next = Instant::now();
    for i in 0..frames {
        let raw = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(args.size.x as f32, args.size.y as f32),
            )),
            time: Some(viewer.started.elapsed().as_secs_f64()),
            ..Default::default()
        };
        let raw = viewer.wants_ui(&raw).then_some(raw);
        viewer.frame(Input::default(), raw)?;
        if let Some(every) = strip_every {
            if (i + 1) % every == 0 && strip.len() < args.strip.unwrap_or(0) as usize {
                strip.push(viewer.composer.read(&viewer.gpu)?);
            }
        }
        next += period;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        } else {
            next = now;
        }
    }
    if let Some(path) = &args.screenshot {
        viewer.write_shot(path)?;
        if !strip.is_empty() {
            let strip_path = sibling(path, "strip");
            save(&strip_of(&strip), &strip_path)?;
            println!("caveray view: wrote {}", strip_path.display());
        }
    }
    viewer.finish(args.json.as_deref())
}

fn save(image: &image::RgbaImage, path: &Path) -> Result<(), Failure> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| Failure::Runtime(format!("cannot create {}: {e}", dir.display())))?;
    }
    image
        .save(path)
        .map_err(|e| Failure::Runtime(format!("cannot write {}: {e}", path.display())))
}

/// `dir/stem-suffix.ext` beside `path`.
fn sibling(path: &Path, suffix: &str) -> PathBuf {
    let stem = path
        .file_stem()
        .map_or("view".into(), |s| s.to_string_lossy());
    let ext = path
        .extension()
        .map_or("png".into(), |s| s.to_string_lossy());
    path.with_file_name(format!("{stem}-{suffix}.{ext}"))
}

/// Frames side by side at half size.
fn strip_of(frames: &[image::RgbaImage]) -> image::RgbaImage {
    let (w, h) = (frames[0].width() / 2, frames[0].height() / 2);
    let mut out =
        image::RgbaImage::from_pixel(w * frames.len() as u32, h, image::Rgba([0, 0, 0, 255]));
    for (i, f) in frames.iter().enumerate() {
        let small = image::imageops::resize(f, w, h, image::imageops::FilterType::Triangle);
        image::imageops::overlay(&mut out, &small, i64::from(w) * i as i64, 0);
    }
    out
}

impl Viewer {
    fn new(
        args: &ViewArgs,
        gpu: Gpu,
        monitor_hz: Option<f64>,
        size: UVec2,
    ) -> Result<Self, Failure> {
        let hz = args.hz.or(monitor_hz).unwrap_or(60.0);
        let shown = if crate::render_display::is_display(&args.config) {
            Shown::Display(DisplayView::new(&args.config, &args.volume, args.scale)?)
        } else {
            Shown::Rig(Box::new(RigShow::new(
                &args.config,
                &args.volume,
                &args.render,
                args.scale,
            )?))
        };
        let (head, ypr, tf, time, path) = match &shown {
            Shown::Rig(r) => {
                let pose = args.head.pose(&r.rig)?;
                let ypr = controls::ypr_of(&r.rig, pose.orientation);
                (
                    pose.position,
                    ypr,
                    r.built_for.tf.clone(),
                    args.head.time().unwrap_or(0.0),
                    !r.rig.viewer.path.is_empty(),
                )
            }
            Shown::Display(_) => (DVec3::ZERO, DVec3::ZERO, String::new(), 0.0, false),
        };
        let rendering = match &shown {
            Shown::Rig(r) => r.built_for.clone(),
            Shown::Display(_) => Rendering::at_rest(tf, &args.render),
        };
        let controls = Controls {
            head,
            ypr,
            rendering,
            warp: args.warp,
            deadline_ms: args.deadline.unwrap_or((1000.0 / hz) as f32),
            stereo: args.eyes,
            look: args.look,
            playing: args.play && path,
            time,
            orbit: [0.0, 20.0, 0.9],
            display_view: 0,
            show_panel: !args.no_controls,
            show_figures: true,
        };
        let walls = match &shown {
            Shown::Rig(r) => r.rig.walls.len(),
            Shown::Display(_) => 2,
        };
        let composer = Composer::new(&gpu, size, walls);
        let renderer_label = format!(
            "walls: {} · window: {} ({:?})",
            args.render.backend.name(),
            gpu.info.name,
            gpu.info.backend
        );
        let volume_name = match &shown {
            Shown::Rig(r) => r.name.clone(),
            Shown::Display(_) => String::new(),
        };
        let egui = egui::Context::default();
        egui.set_visuals(egui::Visuals::dark());
        Ok(Self {
            shown,
            rest: (controls.head, controls.ypr),
            controls,
            gpu,
            composer,
            egui,
            hz,
            shots: Shots {
                path: args.screenshot.clone(),
                taken: 0,
                pending: None,
            },
            frames: Vec::new(),
            last_frame: None,
            fps: 0.0,
            frame_ms: 0.0,
            started: Instant::now(),
            config: args.config.display().to_string(),
            volume_name,
            converged: false,
            quit: false,
            renderer_label,
            rects: Vec::new(),
            ui_at: None,
            ui_again: Instant::now(),
            viewport: [0.0, 0.0, size.x as f32, size.y as f32],
        })
    }

    /// The canvas at the window's new `size`; egui draws its layer anew.
    fn resize(&mut self, size: UVec2) {
        self.composer.resize(&self.gpu, size);
        self.ui_at = None;
    }

    /// Whether egui must run this frame for `pending` input: a key, a
    /// click or the pointer over its controls, a repaint it asked for, or
    /// the overlay's figures due again.
    fn wants_ui(&self, pending: &egui::RawInput) -> bool {
        let Some(at) = self.ui_at else { return true };
        let now = Instant::now();
        if now >= self.ui_again || now.duration_since(at) >= UI_PERIOD {
            return true;
        }
        let over = self.egui.is_pointer_over_egui() || self.egui.egui_is_using_pointer();
        pending.events.iter().any(|e| match e {
            egui::Event::PointerMoved(_) | egui::Event::MouseMoved(_) => over,
            _ => true,
        })
    }

    /// One displayed frame: applies `input`, hands the engine the current
    /// head, takes the frames that are ready and draws the canvas; egui
    /// runs on `raw` where given (see `wants_ui`).
    fn frame(
        &mut self,
        input: Input,
        raw: Option<egui::RawInput>,
    ) -> Result<Option<egui::PlatformOutput>, Failure> {
        let now = Instant::now();
        let dt = self
            .last_frame
            .map_or(1.0 / self.hz, |t| now.duration_since(t).as_secs_f64())
            .min(0.25);
        if let Some(t) = self.last_frame {
            let ms = now.duration_since(t).as_secs_f64() * 1e3;
            self.frames.push(ms);
            self.frame_ms = if self.frame_ms == 0.0 {
                ms
            } else {
                0.9 * self.frame_ms + 0.1 * ms
            };
            self.fps = 1e3 / self.frame_ms.max(1e-3);
        }
        self.last_frame = Some(now);
        self.apply(input, dt);

        match &mut self.shown {
            Shown::Rig(r) => {
                r.rebuild(&self.controls);
                let deadline = Deadline {
                    after: Duration::from_secs_f32(self.controls.deadline_ms / 1e3),
                    warp: self.controls.warp,
                };
                let fresh = r.refresh(&self.controls, deadline);
                for (pane, presented) in fresh {
                    self.composer.set_image(
                        &self.gpu,
                        pane / 2,
                        pane % 2,
                        Some((presented.size, &presented.pixels)),
                    );
                }
                self.converged = r.live.converged(&r.asked);
            }
            Shown::Display(d) => {
                d.want(self.controls.display_view);
                for (slot, size, pixels) in d.take() {
                    self.composer
                        .set_image(&self.gpu, slot, 0, Some((size, &pixels)));
                }
                self.converged = d.converged(self.controls.display_view);
            }
        }
        let mut platform = None;
        if let Some(raw) = raw {
            // What the panel and the overlay show, gathered only when egui
            // runs.
            let (walls, notes, path_seconds, display_views) = match &self.shown {
                Shown::Rig(r) => (
                    r.figures(),
                    r.notes(),
                    r.rig.viewer.path.last().map_or(0.0, |k| k.time),
                    0,
                ),
                Shown::Display(d) => (Vec::new(), d.notes(), 0.0, d.views()),
            };
            let figures = Figures {
                fps: self.fps,
                frame_ms: self.frame_ms,
                walls: walls
                    .into_iter()
                    .map(|(name, eyes)| WallFigures { name, eyes })
                    .collect(),
                converged: self.converged,
                renderer: &self.renderer_label,
                notes,
                path_seconds,
                display_views,
            };
            let mut controls = std::mem::replace(&mut self.controls, placeholder_controls());
            let mut rect = egui::Rect::NOTHING;
            let output = self.egui.run_ui(raw, |ui| {
                rect = panel::draw(ui, &mut controls, &figures);
            });
            self.controls = controls;
            let ppp = output.pixels_per_point;
            self.viewport = [
                (rect.min.x * ppp).round(),
                (rect.min.y * ppp).round(),
                (rect.width() * ppp).round().max(1.0),
                (rect.height() * ppp).round().max(1.0),
            ];
            let delay = output
                .viewport_output
                .get(&egui::ViewportId::ROOT)
                .map_or(UI_PERIOD, |v| v.repaint_delay.min(UI_PERIOD));
            let now = Instant::now();
            self.ui_at = Some(now);
            self.ui_again = now + delay;
            let primitives = self.egui.tessellate(output.shapes, ppp);
            self.composer.draw_ui(
                &self.gpu,
                Overlay {
                    primitives,
                    textures: output.textures_delta,
                    pixels_per_point: ppp,
                },
            );
            platform = Some(output.platform_output);
        }
        let viewport = self.viewport;
        let stage = self.stage(viewport);
        self.rects = stage
            .rects
            .iter()
            .map(|&[x, y, w, h]| [x + viewport[0], y + viewport[1], w, h].map(|v| v as u32))
            .collect();
        self.composer.draw(&self.gpu, &stage);
        self.take_shot()?;
        Ok(platform)
    }

    fn apply(&mut self, input: Input, dt: f64) {
        let c = &mut self.controls;
        for a in &input.actions {
            match *a {
                Action::NextLook => c.look = c.look.next(),
                Action::NextStereo => c.stereo = c.stereo.next(),
                Action::TogglePlay => c.playing = !c.playing,
                Action::ResetHead => {
                    (c.head, c.ypr) = self.rest;
                    c.playing = false;
                }
                Action::Screenshot => {
                    if self.shots.path.is_some() {
                        self.shots.pending = Some(Instant::now());
                    } else {
                        eprintln!("caveray view: F12 writes a screenshot where --screenshot says; none was given");
                    }
                }
                Action::TogglePanel => c.show_panel = !c.show_panel,
                Action::ToggleFigures => c.show_figures = !c.show_figures,
                Action::MoveVolume(by) => match &self.shown {
                    Shown::Rig(r) => c.rendering.volume_offset += by * r.extent,
                    // A display's arrows step through its views.
                    Shown::Display(d) => {
                        let last = d.views().saturating_sub(1);
                        c.display_view = match by.x.partial_cmp(&0.0) {
                            Some(std::cmp::Ordering::Greater) => (c.display_view + 1).min(last),
                            Some(std::cmp::Ordering::Less) => c.display_view.saturating_sub(1),
                            _ => c.display_view,
                        };
                    }
                },
                Action::Quit => self.quit = true,
            }
        }
        if let Shown::Rig(r) = &self.shown {
            c.play(&r.rig, dt);
            c.walk(&r.rig, input.held, dt);
            c.turn(input.drag_head.0, input.drag_head.1);
        }
        if input.drag_volume != (0.0, 0.0) {
            c.turn_volume(input.drag_volume.0, input.drag_volume.1);
        }
        c.orbit_by(input.drag_orbit.0, input.drag_orbit.1);
        c.zoom(input.zoom);
    }

    /// What the 3D part draws this frame.
    fn stage(&self, viewport: [f32; 4]) -> Stage {
        match &self.shown {
            Shown::Display(d) => d.stage(viewport),
            Shown::Rig(r) => r.stage(&self.controls, viewport),
        }
    }

    /// Writes the screenshot asked for once every wall shows its own
    /// image of the current head (or after `SHOT_PATIENCE`, saying so).
    fn take_shot(&mut self) -> Result<(), Failure> {
        let Some(asked) = self.shots.pending else {
            return Ok(());
        };
        let Some(path) = self.shots.path.clone() else {
            return Ok(());
        };
        if !self.converged && asked.elapsed() < SHOT_PATIENCE {
            return Ok(());
        }
        self.shots.pending = None;
        self.shots.taken += 1;
        let path = match self.shots.taken {
            1 => path,
            k => sibling(&path, &k.to_string()),
        };
        self.write_shot(&path)
    }

    /// Writes the canvas to `path` and its sidecar beside it.
    fn write_shot(&self, path: &Path) -> Result<(), Failure> {
        let image = self.composer.read(&self.gpu)?;
        save(&image, path)?;
        let c = &self.controls;
        let names: Vec<String> = match &self.shown {
            Shown::Rig(r) => r.rig.walls.iter().map(|w| w.name.clone()).collect(),
            Shown::Display(_) => vec!["panel".into(), format!("view {}", c.display_view)],
        };
        let flat = c.look == Look::Flat || matches!(self.shown, Shown::Display(_));
        let info = ShotInfo {
            head: c.head.to_array(),
            head_ypr: c.ypr.to_array(),
            converged: self.converged,
            look: c.look.name(),
            eyes: c.stereo.name(),
            walls: names
                .into_iter()
                .enumerate()
                .map(|(i, name)| ShotWall {
                    name,
                    rect: self.rects.get(i).copied().filter(|_| flat),
                })
                .collect(),
        };
        crate::report::write_json(&info, &path.with_extension("json"))?;
        println!("{}", self.shot_line(path));
        Ok(())
    }

    /// The line a screenshot is announced with: where, the head, and
    /// whether every wall showed its own image.
    fn shot_line(&self, path: &Path) -> String {
        let c = &self.controls;
        format!(
            "caveray view: wrote {} (head {:.3},{:.3},{:.3} ypr {:.4},{:.4},{:.4}; {})",
            path.display(),
            c.head.x,
            c.head.y,
            c.head.z,
            c.ypr.x,
            c.ypr.y,
            c.ypr.z,
            if self.converged {
                "converged"
            } else {
                "not converged"
            }
        )
    }

    /// Writes the run's figures and prints a summary.
    fn finish(&self, json: Option<&Path>) -> Result<(), Failure> {
        let mut sorted = self.frames.clone();
        sorted.sort_by(f64::total_cmp);
        let pick = |q: f64| {
            sorted
                .get(((sorted.len() as f64 - 1.0) * q).round() as usize)
                .copied()
                .unwrap_or(0.0)
        };
        let seconds = self.frames.iter().sum::<f64>() / 1e3;
        let frames = self.frames.len() as u64;
        let fps = if seconds > 0.0 {
            frames as f64 / seconds
        } else {
            0.0
        };
        let walls = match &self.shown {
            Shown::Rig(r) => r.pane_reports(),
            Shown::Display(_) => Vec::new(),
        };
        let late: u64 = walls.iter().map(|w| w.late).sum();
        println!(
            "caveray view: {frames} frames in {seconds:.1} s, {fps:.1} fps (p95 {:.1} ms a frame); {} wall frames, {late} late",
            pick(0.95),
            walls.iter().map(|w| w.frames).sum::<u64>()
        );
        let Some(path) = json else { return Ok(()) };
        let report = Report {
            config: self.config.clone(),
            volume: self.volume_name.clone(),
            window: self.composer.size().to_array(),
            adapter: format!("{} ({:?})", self.gpu.info.name, self.gpu.info.backend),
            backend: self.controls.rendering.backend.name().to_string(),
            hz: self.hz,
            deadline_ms: self.controls.deadline_ms,
            warp: self.controls.warp.name(),
            eyes: self.controls.stereo.name(),
            scale: match &self.shown {
                Shown::Rig(r) => r.scale,
                Shown::Display(d) => d.scale(),
            },
            frames,
            seconds,
            fps,
            frame_ms: Percentiles {
                mean: if frames > 0 {
                    seconds * 1e3 / frames as f64
                } else {
                    0.0
                },
                p50: pick(0.5),
                p95: pick(0.95),
                max: pick(1.0),
            },
            converged: self.converged,
            walls,
        };
        crate::report::write_json(&report, path)
    }
}

/// Stands in for the controls while egui has them.
fn placeholder_controls() -> Controls {
    Controls {
        head: DVec3::ZERO,
        ypr: DVec3::ZERO,
        rendering: Rendering::at_rest(String::new(), &RenderOptions::default()),
        warp: WarpMode::None,
        deadline_ms: 0.0,
        stereo: Stereo::Left,
        look: Look::Flat,
        playing: false,
        time: 0.0,
        orbit: [0.0; 3],
        display_view: 0,
        show_panel: true,
        show_figures: true,
    }
}
