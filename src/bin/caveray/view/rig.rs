//! A rig in `caveray view`: its walls and eyes live through the engine
//! (`live`), the volume rebuilt when its look changes, and what the rig's
//! part of the window draws from outside, from the head or laid flat.

use std::path::Path;

use anari_library_caveray::cave::{Eye, Rig};
use anari_library_caveray::engine::Deadline;
use anari_library_caveray::render::{FrameDesc, RenderSettings};
use anari_library_caveray::scene::Scene;
use glam::{DMat4, DVec3, DVec4, Vec4};
use serde::Serialize;

use super::compose::{flat_stage, LineVertex, Stage, WallDraw};
use super::controls::{Controls, Look, Rendering};
use super::live::{self, Ask, Live, PaneStats};
use super::scenes::{same_look, Placing, Scenes};
use crate::options::{RenderOptions, Strategy};
use crate::render::wall_size;
use crate::scene::VolumeArgs;
use crate::Failure;

pub struct RigShow {
    pub rig: Rig,
    /// The volume's name.
    pub name: String,
    /// Where the volume's scenes are made, the one shown and what it was
    /// made for.
    scenes: Scenes,
    scene: Scene,
    pub built_for: Rendering,
    /// The placed volume's centre, which it turns about.
    volume_centre: DVec3,
    /// Why the last look asked for was refused, until one is made.
    refused: Option<String>,
    pub live: Live,
    settings: RenderSettings,
    strategy: Strategy,
    pub scale: f64,
    /// The rig's centre and the length of its bounding box's diagonal.
    pub centre: DVec3,
    pub extent: f64,
    /// The panes asked for last refresh.
    pub asked: Vec<usize>,
}

#[derive(Serialize)]
pub struct PaneReport {
    wall: String,
    eye: &'static str,
    size: [u32; 2],
    pub frames: u64,
    /// Frames ready more than 1 ms after their deadline.
    pub late: u64,
    mean_ready_ms: f64,
    max_ready_ms: f64,
    mean_age_ms: f64,
    max_age_ms: f64,
    warped: u64,
    own: u64,
    rate_hz: f64,
}

impl RigShow {
    /// What the 3D part draws this frame, as `c.look` says.
    pub fn stage(&self, c: &Controls, viewport: [f32; 4]) -> Stage {
        let aspect = viewport[2] / viewport[3];
        let stereo = c.stereo as u32;
        if c.look == Look::Flat {
            return flat_stage(
                viewport,
                &self
                    .rig
                    .walls
                    .iter()
                    .map(|w| wall_size(w.resolution, self.scale))
                    .collect::<Vec<_>>(),
                stereo,
            );
        }
        let clip = match c.look {
            Look::Head => {
                let pose = c.pose(&self.rig);
                let f = &self.rig.viewer.frame;
                let eye = self.rig.eye_position(&pose, Eye::Mono);
                let view = look_at(
                    eye,
                    eye + pose.orientation * f.forward,
                    pose.orientation * f.up,
                );
                let proj = perspective(
                    75f64.to_radians(),
                    f64::from(aspect),
                    self.rig.near,
                    self.rig.far,
                );
                proj * view
            }
            _ => {
                let f = &self.rig.viewer.frame;
                let turn = glam::DQuat::from_axis_angle(f.up, c.orbit[0].to_radians())
                    * glam::DQuat::from_axis_angle(f.right, -c.orbit[1].to_radians());
                let eye = self.centre - turn * f.forward * (c.orbit[2] * self.extent);
                let view = look_at(eye, self.centre, f.up);
                let proj = perspective(
                    50f64.to_radians(),
                    f64::from(aspect),
                    self.extent * 0.01,
                    self.extent * 20.0,
                );
                proj * view
            }
        };
        let clip = clip.as_mat4();
        let walls = self
            .rig
            .walls
            .iter()
            .map(|w| {
                Some(WallDraw {
                    clip,
                    corners: w.screen.corners().map(|p| p.as_vec3()),
                    stereo,
                    exact: false,
                })
            })
            .collect();
        Stage {
            viewport,
            walls,
            lines: self.lines(c),
            lines_clip: clip,
            rects: Vec::new(),
        }
    }

    pub fn new(
        config: &Path,
        volume: &VolumeArgs,
        render: &RenderOptions,
        scale: f64,
    ) -> Result<Self, Failure> {
        let rig = Rig::load(config).map_err(|e| Failure::Usage(e.to_string()))?;
        for wall in &rig.walls {
            FrameDesc::new(wall_size(wall.resolution, scale))
                .validate()
                .map_err(|e| Failure::Usage(format!("wall \"{}\": {e}", wall.name)))?;
        }
        let loaded = volume.load()?;
        let built_for = Rendering::at_rest(loaded.tf_name().to_string(), render);
        let scene = loaded.placed(rig.scene, &rig.viewer.frame, rig.units)?;
        let (vlo, vhi) = scene.bounds();
        let corners: Vec<DVec3> = rig.walls.iter().flat_map(|w| w.screen.corners()).collect();
        let lo = corners.iter().fold(DVec3::MAX, |m, c| m.min(*c));
        let hi = corners.iter().fold(DVec3::MIN, |m, c| m.max(*c));
        let panes = 2 * rig.walls.len();
        let name = loaded.name.clone();
        let mut scenes = Scenes::new(
            loaded,
            Placing {
                placement: rig.scene,
                frame: rig.viewer.frame,
                units: rig.units,
            },
        )?;
        scenes.shown(&built_for);
        Ok(Self {
            name,
            scenes,
            scene,
            built_for,
            volume_centre: (0.5 * (vlo + vhi)).as_dvec3(),
            refused: None,
            live: Live::new(panes),
            settings: render.settings(),
            strategy: render.strategy,
            scale,
            centre: 0.5 * (lo + hi),
            extent: (hi - lo).length().max(1e-9),
            asked: Vec::new(),
            rig,
        })
    }

    /// Takes the scene made since the last refresh, and asks for a new
    /// one where the volume's look changed (one at a time, off this thread).
    pub fn rebuild(&mut self, c: &Controls) {
        let want = &c.rendering;
        self.settings.step_factor = want.step_factor;
        self.settings.shading = want.shading;
        if let Some(made) = self.scenes.take() {
            match made.scene {
                Ok(scene) => {
                    self.scene = scene;
                    self.built_for = made.rendering;
                    self.refused = None;
                    for pane in 0..2 * self.rig.walls.len() {
                        self.live.forget(pane);
                    }
                }
                Err(e) => {
                    eprintln!("caveray view: {e}");
                    self.refused = Some(e);
                }
            }
        }
        if !same_look(want, &self.built_for) {
            let moved = c.volume_move(&self.rig, self.volume_centre).as_mat4();
            self.scenes.want(want, moved);
        }
    }

    /// Hands the engine every wanted wall and eye of the current head.
    pub fn refresh(&mut self, c: &Controls, deadline: Deadline) -> Vec<(usize, live::Presented)> {
        let pose = c.pose(&self.rig);
        let wanted = c.stereo.eyes();
        let mut views = Vec::new();
        for (w, wall) in self.rig.walls.iter().enumerate() {
            let size = wall_size(wall.resolution, self.scale);
            let mono = !wall.eyes.contains(&Eye::Left) && !wall.eyes.contains(&Eye::Right);
            for (slot, eye) in [Eye::Left, Eye::Right].into_iter().enumerate() {
                let eye = if mono {
                    if slot == 1 {
                        continue;
                    }
                    Eye::Mono
                } else {
                    if !wanted[slot] || !wall.eyes.contains(&eye) {
                        continue;
                    }
                    eye
                };
                let rays = self
                    .rig
                    .view(wall, eye, &pose)
                    .map_err(|e| e.to_string())
                    .and_then(|v| self.strategy.rays(&v, size));
                if let Ok(rays) = rays {
                    views.push((2 * w + slot, rays, size));
                }
            }
        }
        self.asked = views.iter().map(|v| v.0).collect();
        let ask = Ask {
            scene: &self.scene,
            settings: &self.settings,
            backend: c.rendering.backend,
            deadline,
        };
        self.live.refresh(&ask, &views)
    }

    /// The engine's newest messages, and why a look was refused.
    pub fn notes(&self) -> Vec<String> {
        let mut notes = self.live.notes();
        notes.extend(self.refused.clone());
        notes
    }

    /// Each wall's name and its eyes' figures.
    pub fn figures(&self) -> Vec<(&str, Vec<PaneStats>)> {
        self.rig
            .walls
            .iter()
            .enumerate()
            .map(|(w, wall)| {
                let eyes = [0, 1]
                    .into_iter()
                    .filter(|s| self.asked.contains(&(2 * w + s)))
                    .map(|s| self.live.stats(2 * w + s))
                    .collect();
                (wall.name.as_str(), eyes)
            })
            .collect()
    }

    pub fn pane_reports(&self) -> Vec<PaneReport> {
        let mut out = Vec::new();
        for (w, wall) in self.rig.walls.iter().enumerate() {
            let size = wall_size(wall.resolution, self.scale);
            for s in 0..2 {
                let st = self.live.stats(2 * w + s);
                if st.frames == 0 {
                    continue;
                }
                let n = st.frames as f64;
                out.push(PaneReport {
                    wall: wall.name.clone(),
                    eye: ["left", "right"][s],
                    size: size.to_array(),
                    frames: st.frames,
                    late: st.late,
                    mean_ready_ms: st.sum_ready_ms / n,
                    max_ready_ms: st.max_ready_ms,
                    mean_age_ms: st.sum_age_ms / n,
                    max_age_ms: st.max_age_ms,
                    warped: st.warped,
                    own: st.own,
                    rate_hz: st.rate_hz,
                });
            }
        }
        out
    }

    /// Wall edges, the volume's box and the head (its gaze and eyes).
    pub fn lines(&self, c: &Controls) -> Vec<LineVertex> {
        let mut out = Vec::new();
        let mut line = |a: DVec3, b: DVec3, color: Vec4| {
            out.push(LineVertex::new(a.as_vec3(), color));
            out.push(LineVertex::new(b.as_vec3(), color));
        };
        let edge = Vec4::new(0.75, 0.75, 0.8, 1.0);
        for w in &self.rig.walls {
            let k = w.screen.corners();
            for i in 0..4 {
                line(k[i], k[(i + 1) % 4], edge);
            }
        }
        // The person in the rig sees the walls' images alone.
        if c.look != Look::Head {
            let (lo, hi) = self.scene.bounds();
            let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
            let boxc = Vec4::new(0.95, 0.8, 0.3, 1.0);
            for i in 0..4u32 {
                let corner = |bits: u32| {
                    DVec3::new(
                        if bits & 1 != 0 { hi.x } else { lo.x },
                        if bits & 2 != 0 { hi.y } else { lo.y },
                        if bits & 4 != 0 { hi.z } else { lo.z },
                    )
                };
                // Each axis's four edges.
                for axis in 0..3 {
                    let others: Vec<u32> = (0..3).filter(|&a| a != axis).collect();
                    let base = ((i & 1) << others[0]) | (((i >> 1) & 1) << others[1]);
                    line(corner(base), corner(base | (1 << axis)), boxc);
                }
            }
        }
        if c.look == Look::Outside {
            let pose = c.pose(&self.rig);
            let f = &self.rig.viewer.frame;
            let size = self.extent * 0.04;
            let eye = self.rig.eye_position(&pose, Eye::Mono);
            let gaze = pose.orientation * f.forward;
            line(eye, eye + gaze * size * 3.0, Vec4::new(0.3, 1.0, 0.4, 1.0));
            let left = self.rig.eye_position(&pose, Eye::Left);
            let right = self.rig.eye_position(&pose, Eye::Right);
            line(left, right, Vec4::new(1.0, 0.3, 0.3, 1.0));
            line(
                eye,
                eye + pose.orientation * f.up * size,
                Vec4::new(0.4, 0.6, 1.0, 1.0),
            );
        }
        out
    }
}

/// A right-handed view matrix from `eye` towards `target`.
fn look_at(eye: DVec3, target: DVec3, up: DVec3) -> DMat4 {
    let f = (target - eye).normalize();
    let s = f.cross(up).normalize();
    let u = s.cross(f);
    DMat4::from_cols(
        DVec4::new(s.x, u.x, -f.x, 0.0),
        DVec4::new(s.y, u.y, -f.y, 0.0),
        DVec4::new(s.z, u.z, -f.z, 0.0),
        DVec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
    )
}

/// A perspective projection to wgpu's clip space (depth 0 to 1).
fn perspective(fovy: f64, aspect: f64, near: f64, far: f64) -> DMat4 {
    let h = 1.0 / (0.5 * fovy).tan();
    let r = far / (near - far);
    DMat4::from_cols(
        DVec4::new(h / aspect, 0.0, 0.0, 0.0),
        DVec4::new(0.0, h, 0.0, 0.0),
        DVec4::new(0.0, 0.0, r, -1.0),
        DVec4::new(0.0, 0.0, r * near, 0.0),
    )
}
