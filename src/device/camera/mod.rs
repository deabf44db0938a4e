//! Cameras: one module per subtype, each lowering to the renderer's
//! `RayGen` for a frame through `CameraModel`. What the perspective and
//! orthographic cameras share (their frame of reference, image region and
//! clip range) is read here once.

pub mod matrix;
pub mod multi_view;
pub mod off_axis;
pub mod orthographic;
pub mod perspective;
pub mod stereo;

use glam::{DVec2, DVec3, UVec2, Vec3};

use self::multi_view::MultiViewCamera;
use self::stereo::{Stereo, StereoMode};
use super::object::State;
use super::table::Read;
use super::table::{p, DefaultValue, ParamInfo, F32, VEC3};
use super::types::DataType as T;
use crate::engine::{EyeView, PanelViews, Views};
use crate::geometry::{
    ImageRegion, MatrixCamera, OffAxisCamera, OrthographicCamera, PinholeCamera, PrimaryRays,
    RayGen, Rounded,
};

/// The parameters ANARI's perspective and orthographic cameras share,
/// then the subtype's own one (`fovy`, `height`).
pub const fn placed_params(own: ParamInfo) -> [ParamInfo; 8] {
    [
        p(
            "position",
            VEC3,
            false,
            DefaultValue::Floats(&[0.0, 0.0, 0.0]),
            "eye position",
        ),
        p(
            "direction",
            VEC3,
            false,
            DefaultValue::Floats(&[0.0, 0.0, -1.0]),
            "viewing direction",
        ),
        p(
            "up",
            VEC3,
            false,
            DefaultValue::Floats(&[0.0, 1.0, 0.0]),
            "up vector",
        ),
        p(
            "aspect",
            F32,
            false,
            DefaultValue::None,
            "width / height (default: the frame's)",
        ),
        p(
            "imageRegion",
            &[T::FLOAT32_BOX2],
            false,
            DefaultValue::Floats(&[0.0, 0.0, 1.0, 1.0]),
            "part of the image that is rendered, (min.x, min.y, max.x, max.y) in [0, 1]",
        ),
        p(
            "near",
            F32,
            false,
            DefaultValue::None,
            "distance along each ray before which nothing is seen (default 0)",
        ),
        p(
            "far",
            F32,
            false,
            DefaultValue::None,
            "distance along each ray beyond which nothing is seen (default: none)",
        ),
        own,
    ]
}

/// A wall seen from `eye` as OpenGL matrices, with a near plane a
/// thousandth of the eye's distance to the wall.
fn off_axis_matrices(screen: &crate::geometry::Screen, eye: DVec3) -> Option<MatrixCamera> {
    let distance = (eye - screen.ll()).dot(screen.normal()).abs();
    let near = 1e-3 * distance;
    let p = crate::geometry::OffAxisProjection::new(screen, eye, near, near * 1e9).ok()?;
    MatrixCamera::new(p.view, p.proj).ok()
}

/// Where a perspective or orthographic camera stands and what it shows.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    pub position: DVec3,
    pub direction: DVec3,
    pub up: DVec3,
    /// `None`: the frame's.
    pub aspect: Option<f64>,
    pub region: ImageRegion,
    pub clip: Option<(f32, f32)>,
}

impl Placement {
    pub fn read(r: &Read<'_>) -> Result<Self, String> {
        let [x0, y0, x1, y1] = r.floats::<4>("imageRegion")?;
        let optional = |name| r.set(name).map(|_| r.f32(name)).transpose();
        let clip = match (optional("near")?, optional("far")?) {
            (None, None) => None,
            (near, far) => {
                let (near, far) = (near.unwrap_or(0.0), far.unwrap_or(f32::INFINITY));
                if !(near >= 0.0 && far > near) {
                    return Err(format!(
                        "near {near} and far {far} must satisfy 0 <= near < far"
                    ));
                }
                Some((near, far))
            }
        };
        Ok(Self {
            position: r.vec3("position")?.as_dvec3(),
            direction: r.vec3("direction")?.as_dvec3(),
            up: r.vec3("up")?.as_dvec3(),
            aspect: optional("aspect")?.map(f64::from),
            region: ImageRegion {
                min: DVec2::new(x0.into(), y0.into()),
                max: DVec2::new(x1.into(), y1.into()),
            },
            clip,
        })
    }

    /// This pinhole as OpenGL view and projection matrices; an image
    /// region crops the frustum off axis. The near plane is the camera's
    /// `near`, else a millimetre-scale 1e-3 units; the far plane its `far`,
    /// else 1e9 times the near.
    fn matrix_camera(&self, fovy: f64, aspect: f64) -> Option<MatrixCamera> {
        // One match, so no comparison is made on an absent value's bytes
        // (valgrind flags the speculative compare an Option chain compiles to).
        let (near, far) = match self.clip {
            Some((n, f)) => (f64::from(n), f64::from(f)),
            None => (0.0, f64::INFINITY),
        };
        let near = if near > 0.0 { near } else { 1e-3 };
        let far = if far.is_finite() { far } else { near * 1e9 };
        let top = near * (0.5 * fovy).tan();
        let half = DVec2::new(top * aspect, top);
        let (lo, hi) = (
            half * (2.0 * self.region.min - 1.0),
            half * (2.0 * self.region.max - 1.0),
        );
        let proj = crate::geometry::frustum(lo.x, hi.x, lo.y, hi.y, near, far);
        // The right-handed look-at: rows right, up, back; the eye at 0.
        let f = self.direction.try_normalize()?;
        let s = f.cross(self.up).try_normalize()?;
        let u = s.cross(f);
        let e = self.position;
        let view = glam::DMat4::from_cols(
            glam::DVec4::new(s.x, u.x, -f.x, 0.0),
            glam::DVec4::new(s.y, u.y, -f.y, 0.0),
            glam::DVec4::new(s.z, u.z, -f.z, 0.0),
            glam::DVec4::new(-s.dot(e), -u.dot(e), f.dot(e), 1.0),
        );
        MatrixCamera::new(view, proj).ok()
    }

    fn aspect(&self, size: UVec2) -> f64 {
        self.aspect.unwrap_or(f64::from(size.x) / f64::from(size.y))
    }

    /// The rays of the camera `make` builds for this placement and the
    /// frame's aspect, clipped to `near`..`far`.
    fn rays<C: PrimaryRays>(
        &self,
        size: UVec2,
        make: impl FnOnce(&Self, f64) -> crate::geometry::Result<C>,
    ) -> Result<RayGen, String> {
        let rays = make(self, self.aspect(size))
            .map_err(|e| e.to_string())?
            .ray_gen(size);
        Ok(match self.clip {
            Some((near, far)) => rays.clipped(near, far),
            None => rays,
        })
    }
}

#[derive(Clone, Debug)]
pub enum CameraModel {
    /// ANARI's perspective camera.
    Perspective {
        placement: Placement,
        fovy: f64,
        stereo: Stereo,
    },
    /// ANARI's orthographic camera.
    Orthographic {
        placement: Placement,
        height: f64,
    },
    Matrix(Box<MatrixCamera>),
    /// caveray's wall-and-eye camera; `axis` runs from the left eye to the
    /// right one (unit length).
    OffAxis {
        camera: OffAxisCamera,
        stereo: Stereo,
        axis: DVec3,
    },
    /// caveray's autostereoscopic panel.
    MultiView(Box<MultiViewCamera>),
}

impl CameraModel {
    pub fn ray_gen(&self, size: UVec2) -> Result<RayGen, String> {
        match self {
            CameraModel::Perspective {
                placement, fovy, ..
            } => placement.rays(size, |p, aspect| {
                PinholeCamera::new(p.position, p.direction, p.up, *fovy, aspect, p.region)
            }),
            CameraModel::Orthographic { placement, height } => placement.rays(size, |p, aspect| {
                OrthographicCamera::new(p.position, p.direction, p.up, *height, aspect, p.region)
            }),
            CameraModel::Matrix(c) => Ok(c.ray_gen(size)),
            CameraModel::OffAxis { camera, .. } => Ok(camera.ray_gen(size)),
            // The view asked for, else the one nearest the middle.
            CameraModel::MultiView(m) => m
                .display
                .view_camera(m.view.unwrap_or(m.display.views / 2))
                .map(|c| c.ray_gen(size))
                .map_err(|e| e.to_string()),
        }
    }

    /// The camera as OpenGL matrices for a frame of `size`, where it is
    /// a perspective one: what stereo re-projection plans with.
    pub fn matrix(&self, size: UVec2) -> Option<MatrixCamera> {
        match self {
            CameraModel::Perspective {
                placement, fovy, ..
            } => placement.matrix_camera(*fovy, placement.aspect(size)),
            CameraModel::OffAxis { camera, .. } => off_axis_matrices(camera.screen(), camera.eye()),
            CameraModel::Matrix(c) => c.eye().is_some().then_some(**c),
            CameraModel::MultiView(m) => {
                let view = m.view?;
                off_axis_matrices(&m.display.screen, m.display.eye(view))
            }
            CameraModel::Orthographic { .. } => None,
        }
    }

    /// What a frame of `size` shows and where each eye goes in it: one
    /// view of the whole frame, the two eyes of a stereo perspective
    /// camera, or a multi-view camera's panel.
    pub fn views(&self, size: UVec2) -> Result<Views, String> {
        let whole = || {
            Ok(Views::Mono(EyeView {
                rays: self.ray_gen(size)?,
                offset: UVec2::ZERO,
                size,
                matrix: self.matrix(size),
            }))
        };
        let stereo = match self {
            CameraModel::Perspective { stereo, .. } | CameraModel::OffAxis { stereo, .. } => {
                *stereo
            }
            // The panel image: every view over the whole frame, which the
            // frame interleaves.
            CameraModel::MultiView(m) if m.view.is_none() => {
                let display = m.panel(size);
                let rays = display.view_rays().map_err(|e| e.to_string())?;
                let views = rays
                    .into_iter()
                    .map(|rays| EyeView {
                        rays,
                        offset: UVec2::ZERO,
                        size,
                        matrix: None,
                    })
                    .collect();
                return Ok(Views::Panel(PanelViews {
                    views,
                    display,
                    method: m.method,
                }));
            }
            _ => return whole(),
        };
        if stereo.mode == StereoMode::None {
            return whole();
        }
        stereo.mode.fits(size)?;
        let pair = matches!(stereo.mode, StereoMode::SideBySide | StereoMode::TopBottom);
        let mut eyes = stereo
            .mode
            .layout(size)
            .into_iter()
            .map(|(side, offset, eye_size)| {
                let (rays, matrix) = match self {
                    CameraModel::Perspective {
                        placement, fovy, ..
                    } => {
                        let eye = Placement {
                            position: stereo.eye(
                                side,
                                placement.position,
                                placement.direction,
                                placement.up,
                            ),
                            ..*placement
                        };
                        let camera = CameraModel::Perspective {
                            placement: eye,
                            fovy: *fovy,
                            stereo: Stereo::default(),
                        };
                        let matrix = pair
                            .then(|| eye.matrix_camera(*fovy, eye.aspect(eye_size)))
                            .flatten();
                        (camera.ray_gen(eye_size)?, matrix)
                    }
                    CameraModel::OffAxis { camera, axis, .. } => {
                        let eye = stereo.along(side, camera.eye(), *axis);
                        let screen = *camera.screen();
                        // Eyes apart along an axis that leaves the wall's
                        // plane may put one behind it.
                        let one = OffAxisCamera::new(screen, eye).map_err(|e| {
                            format!(
                                "interpupillaryDistance {} along eyeAxis puts the {} eye at {}: {e}",
                                Rounded(stereo.ipd),
                                if side < 0.0 { "left" } else { "right" },
                                point(eye)
                            )
                        })?;
                        let matrix = pair.then(|| off_axis_matrices(&screen, eye)).flatten();
                        (one.ray_gen(eye_size), matrix)
                    }
                    _ => unreachable!("only stereo cameras get here"),
                };
                Ok(EyeView {
                    rays,
                    offset,
                    size: eye_size,
                    matrix,
                })
            })
            .collect::<Result<Vec<_>, String>>()?;
        match (eyes.pop(), eyes.pop()) {
            (Some(right), Some(left)) => Ok(Views::StereoPair([left, right])),
            (Some(one), None) => Ok(Views::Mono(one)),
            _ => Err("internal: a stereo mode without eyes".into()),
        }
    }

    /// Whether the eyes a stereo camera's `interpupillaryDistance` placed
    /// (the host's, in its own units) can give an image of a world within
    /// `bounds` in `views`: rays are single precision, so an eye so far
    /// out that the world spans fewer float steps than the view has
    /// pixels across sees nothing of it. Other cameras place no eyes.
    pub fn check_eyes(&self, views: &Views, (lo, hi): (Vec3, Vec3)) -> Result<(), String> {
        let stereo = match self {
            CameraModel::Perspective { stereo, .. } | CameraModel::OffAxis { stereo, .. } => stereo,
            _ => return Ok(()),
        };
        let eyes: &[EyeView] = match views {
            Views::Mono(one) => std::slice::from_ref(one),
            Views::StereoPair(pair) => pair,
            Views::Panel(_) => return Ok(()),
        };
        let across = (hi - lo).max_element();
        if stereo.mode == StereoMode::None || !(across.is_finite() && across > 0.0) {
            return Ok(());
        }
        for view in eyes {
            let eye = view.rays.eye.unwrap_or(view.rays.origin);
            let largest = eye.abs().max(lo.abs()).max(hi.abs()).max_element();
            let float_step = largest * f32::EPSILON;
            let pixels = view.size.max_element() as f32;
            if !float_step.is_finite() || across < float_step * pixels {
                return Err(format!(
                    "interpupillaryDistance {} puts an eye at {}, where single-precision rays step by {}: the world, {} across, would span fewer steps than the view's {} pixels, so no image of it can be made",
                    Rounded(stereo.ipd),
                    point(eye.as_dvec3()),
                    Rounded(f64::from(float_step)),
                    Rounded(f64::from(across)),
                    pixels
                ));
            }
        }
        Ok(())
    }

    /// The committed state, once the camera makes rays. A perspective
    /// camera is checked with a square frame; its aspect is only known for
    /// certain when a frame renders it.
    fn committed(self) -> Result<Option<State>, String> {
        self.ray_gen(UVec2::ONE)?;
        Ok(Some(State::ready(self)))
    }
}

/// A point as messages show it.
fn point(p: DVec3) -> String {
    format!("({}, {}, {})", Rounded(p.x), Rounded(p.y), Rounded(p.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The matrices a stereo pair is planned with must be the rays the
    /// camera casts (to the rays' single precision), an image region
    /// included (OpenCOVER's cropped walls).
    #[test]
    fn a_cropped_perspective_camera_has_the_matrices_of_its_rays() {
        let placement = Placement {
            position: DVec3::new(0.1, -0.2, 3.0),
            direction: DVec3::new(0.1, 0.0, -1.0),
            up: DVec3::Y,
            aspect: Some(1.6),
            region: ImageRegion {
                min: DVec2::new(0.1, 0.25),
                max: DVec2::new(0.7, 0.95),
            },
            clip: None,
        };
        let camera = CameraModel::Perspective {
            placement,
            fovy: 0.9,
            stereo: Stereo::default(),
        };
        let size = UVec2::new(30, 20);
        let rays = camera.ray_gen(size).unwrap();
        let matrix = camera.matrix(size).unwrap().ray_gen(size);
        for (x, y) in [(0, 0), (29, 0), (0, 19), (29, 19), (13, 7)] {
            let (a, b) = (rays.pixel_ray(x, y).1, matrix.pixel_ray(x, y).1);
            assert!((a - b).length() < 1e-5, "pixel ({x}, {y}): {a} vs {b}");
        }
    }
}
