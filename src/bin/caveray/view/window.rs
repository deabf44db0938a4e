//! `caveray view` in a desktop window: winit's events to `Input`, a
//! redraw at the display's rate, the canvas copied to the window's surface.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{DVec3, UVec2};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, KeyCode, ModifiersState, NamedKey, PhysicalKey};
use winit::window::{Window, WindowId};

use super::compose::Gpu;
use super::{Action, Input, ViewArgs, Viewer};
use crate::Failure;

pub fn run(args: ViewArgs) -> Result<(), Failure> {
    let event_loop = EventLoop::new().map_err(|e| {
        Failure::Runtime(format!(
            "caveray view cannot open a window ({e}); without a display, use --headless-frames N"
        ))
    })?;
    let mut app = App {
        args,
        open: None,
        failure: None,
        input: Input::default(),
        pointer: None,
        buttons: [false; 2],
        modifiers: ModifiersState::empty(),
        next: Instant::now(),
        shown: 0,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| Failure::Runtime(format!("the window's event loop failed: {e}")))?;
    if let Some(f) = app.failure {
        return Err(f);
    }
    match app.open {
        Some(open) => open.viewer.finish(app.args.json.as_deref()),
        None => Ok(()),
    }
}

struct Open {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// The surface's format without sRGB encoding: the canvas is encoded.
    view_format: wgpu::TextureFormat,
    egui: egui_winit::State,
    viewer: Viewer,
}

struct App {
    args: ViewArgs,
    open: Option<Open>,
    failure: Option<Failure>,
    input: Input,
    pointer: Option<(f64, f64)>,
    /// Left and right button down (over the rig, not the controls).
    buttons: [bool; 2],
    modifiers: ModifiersState,
    next: Instant,
    shown: u64,
}

impl App {
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<Open, Failure> {
        let size = self.args.size;
        let attributes = Window::default_attributes()
            .with_title(format!("caveray view: {}", self.args.config.display()))
            .with_inner_size(winit::dpi::PhysicalSize::new(size.x, size.y));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| Failure::Runtime(format!("cannot open a window: {e}")))?,
        );
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::VULKAN,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let surface = instance
            .create_surface(Arc::clone(&window))
            .map_err(|e| Failure::Runtime(format!("cannot draw into the window: {e}")))?;
        let gpu = Gpu::open(&instance, Some(&surface))?;
        let caps = surface.get_capabilities(&gpu.adapter);
        // An 8-bit format: the canvas is copied into it as it is.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                matches!(
                    f.remove_srgb_suffix(),
                    wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
                )
            })
            .ok_or_else(|| {
                Failure::Runtime(format!(
                    "the window offers no 8-bit RGBA format ({:?})",
                    caps.formats
                ))
            })?;
        let view_format = format.remove_srgb_suffix();
        // The viewer paces itself at the display's rate: presenting must
        // not wait for a vertical blank as well.
        let present_mode = [wgpu::PresentMode::Mailbox, wgpu::PresentMode::Immediate]
            .into_iter()
            .find(|m| caps.present_modes.contains(m))
            .unwrap_or(wgpu::PresentMode::Fifo);
        let inner = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: inner.width.max(1),
            height: inner.height.max(1),
            present_mode,
            color_space: Default::default(),
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: if view_format == format {
                vec![]
            } else {
                vec![view_format]
            },
        };
        surface.configure(&gpu.device, &config);
        let monitor_hz = window
            .current_monitor()
            .and_then(|m| m.refresh_rate_millihertz())
            .map(|mhz| f64::from(mhz) / 1e3)
            .filter(|hz| *hz >= 10.0);
        let size = UVec2::new(config.width, config.height);
        let viewer = Viewer::new(&self.args, gpu, monitor_hz, size)?;
        let egui = egui_winit::State::new(
            viewer.egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        Ok(Open {
            window,
            surface,
            config,
            view_format,
            egui,
            viewer,
        })
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.open.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(open) => {
                open.window.request_redraw();
                self.open = Some(open);
            }
            Err(f) => {
                self.failure = Some(f);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(open) = &mut self.open else { return };
        let response = open.egui.on_window_event(&open.window, &event);
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                open.config.width = size.width;
                open.config.height = size.height;
                open.surface
                    .configure(&open.viewer.gpu.device, &open.config);
                open.viewer.resize(UVec2::new(size.width, size.height));
            }
            WindowEvent::ModifiersChanged(m) => self.modifiers = m.state(),
            WindowEvent::KeyboardInput { event, .. } if !response.consumed => {
                let down = event.state == ElementState::Pressed;
                let held = &mut self.input.held;
                if let PhysicalKey::Code(code) = event.physical_key {
                    match code {
                        KeyCode::KeyW => held.forward = down,
                        KeyCode::KeyS => held.back = down,
                        KeyCode::KeyA => held.left = down,
                        KeyCode::KeyD => held.right = down,
                        KeyCode::KeyE => held.up = down,
                        KeyCode::KeyQ => held.down = down,
                        _ => {}
                    }
                }
                if down && !event.repeat {
                    if let Some(a) = action(&event.logical_key, event.physical_key) {
                        self.input.actions.push(a);
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                let i = match button {
                    MouseButton::Left => 0,
                    MouseButton::Right => 1,
                    _ => return,
                };
                // A press over the controls is theirs; a release always ends a drag.
                if !down || !response.consumed {
                    self.buttons[i] = down && !open.egui.egui_ctx().egui_wants_pointer_input();
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let p = (position.x, position.y);
                if let Some((x, y)) = self.pointer {
                    let d = (p.0 - x, p.1 - y);
                    if self.buttons[0] {
                        let target = if self.modifiers.shift_key() {
                            &mut self.input.drag_volume
                        } else {
                            &mut self.input.drag_head
                        };
                        target.0 += d.0;
                        target.1 += d.1;
                    }
                    if self.buttons[1] {
                        self.input.drag_orbit.0 += d.0;
                        self.input.drag_orbit.1 += d.1;
                    }
                }
                self.pointer = Some(p);
            }
            WindowEvent::MouseWheel { delta, .. } if !response.consumed => {
                self.input.zoom += match delta {
                    MouseScrollDelta::LineDelta(_, y) => f64::from(y),
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                };
            }
            WindowEvent::RedrawRequested => {
                if let Err(f) = self.redraw() {
                    self.failure = Some(f);
                    event_loop.exit();
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let Some(open) = &self.open else { return };
        if open.viewer.quit || self.args.frames.is_some_and(|n| self.shown >= n) {
            event_loop.exit();
            return;
        }
        let now = Instant::now();
        if now >= self.next {
            let period = Duration::from_secs_f64(1.0 / open.viewer.hz);
            self.next = (self.next + period).max(now);
            open.window.request_redraw();
        }
        event_loop.set_control_flow(ControlFlow::WaitUntil(self.next));
    }
}

impl App {
    fn redraw(&mut self) -> Result<(), Failure> {
        let Some(open) = &mut self.open else {
            return Ok(());
        };
        let input = std::mem::take(&mut self.input);
        // Keys stay held across refreshes.
        self.input.held = input.held;
        let raw = open
            .viewer
            .wants_ui(open.egui.egui_input())
            .then(|| open.egui.take_egui_input(&open.window));
        if let Some(output) = open.viewer.frame(input, raw)? {
            open.egui.handle_platform_output(&open.window, output);
        }
        let texture = match open.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            _ => {
                open.surface
                    .configure(&open.viewer.gpu.device, &open.config);
                return Ok(());
            }
        };
        let view = texture.texture.create_view(&wgpu::TextureViewDescriptor {
            format: Some(open.view_format),
            ..Default::default()
        });
        open.viewer
            .composer
            .show(&open.viewer.gpu, &view, open.view_format);
        open.window.pre_present_notify();
        open.viewer.gpu.queue.present(texture);
        self.shown += 1;
        Ok(())
    }
}

/// The action of a key pressed, if any.
fn action(key: &Key, physical: PhysicalKey) -> Option<Action> {
    let step = 0.02;
    Some(match (key, physical) {
        (Key::Named(NamedKey::F12), _) => Action::Screenshot,
        (Key::Named(NamedKey::Escape), _) => Action::Quit,
        (Key::Named(NamedKey::Tab), _) | (_, PhysicalKey::Code(KeyCode::KeyV)) => Action::NextLook,
        (_, PhysicalKey::Code(KeyCode::KeyM)) => Action::NextStereo,
        (_, PhysicalKey::Code(KeyCode::KeyP)) => Action::TogglePlay,
        (_, PhysicalKey::Code(KeyCode::KeyR)) => Action::ResetHead,
        (_, PhysicalKey::Code(KeyCode::KeyH)) => Action::TogglePanel,
        (_, PhysicalKey::Code(KeyCode::KeyO)) => Action::ToggleFigures,
        (Key::Named(NamedKey::ArrowLeft), _) => Action::MoveVolume(DVec3::new(-step, 0.0, 0.0)),
        (Key::Named(NamedKey::ArrowRight), _) => Action::MoveVolume(DVec3::new(step, 0.0, 0.0)),
        (Key::Named(NamedKey::ArrowUp), _) => Action::MoveVolume(DVec3::new(0.0, step, 0.0)),
        (Key::Named(NamedKey::ArrowDown), _) => Action::MoveVolume(DVec3::new(0.0, -step, 0.0)),
        (Key::Named(NamedKey::PageUp), _) => Action::MoveVolume(DVec3::new(0.0, 0.0, step)),
        (Key::Named(NamedKey::PageDown), _) => Action::MoveVolume(DVec3::new(0.0, 0.0, -step)),
        _ => return None,
    })
}
