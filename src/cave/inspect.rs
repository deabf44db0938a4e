//! `caveray inspect`: what every wall and eye sees under each strategy, and
//! how far the four ray generators disagree.

use glam::UVec2;
use serde::Serialize;

use super::{Eye, HeadPose, Rig, View, Wall};
use crate::geometry::{pixel_centre, PinholeCamera, PrimaryRays, Result};

/// Pixels per axis of the grid on which the generators are compared.
const COMPARE_GRID: u32 = 65;

#[derive(Serialize)]
pub struct Report {
    pub rig: String,
    pub units: &'static str,
    pub head: HeadReport,
    pub views: Vec<ViewReport>,
}

#[derive(Serialize)]
pub struct HeadReport {
    pub position: [f64; 3],
    /// Unit quaternion (x, y, z, w) relative to the rig's rest frame.
    pub orientation: [f64; 4],
}

#[derive(Serialize)]
pub struct ViewReport {
    pub wall: String,
    pub eye: Eye,
    pub eye_position: [f64; 3],
    pub resolution: [u32; 2],
    /// Why this view has no camera (eye on or behind the wall).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub cameras: Option<Cameras>,
}

#[derive(Serialize)]
pub struct Cameras {
    pub matrix: Matrices,
    pub pinhole: Pinhole,
    pub from_matrices: Recovered,
    /// Largest distance, in rig units, by which the four generators' rays
    /// for one pixel disagree: where they meet the wall, or how far a ray's
    /// line passes from the eye.
    pub max_ray_disagreement: f64,
    /// Number of pixels compared for `max_ray_disagreement`.
    pub pixels_compared: usize,
    pub rays: Vec<RaySample>,
}

#[derive(Serialize)]
pub struct Matrices {
    /// Column-major, as glLoadMatrixf takes it.
    pub view: [f64; 16],
    pub proj: [f64; 16],
}

#[derive(Serialize)]
pub struct Pinhole {
    pub position: [f64; 3],
    pub direction: [f64; 3],
    pub up: [f64; 3],
    /// Radians.
    pub fovy: f64,
    pub aspect: f64,
    pub image_region: [f64; 4],
}

#[derive(Serialize)]
pub struct Recovered {
    #[serde(flatten)]
    pub pinhole: Pinhole,
    pub recovered_eye: [f64; 3],
}

#[derive(Serialize)]
pub struct RaySample {
    pub pixel: [u32; 2],
    pub origin: [f64; 3],
    pub direction: [f64; 3],
}

/// Which views to report.
pub struct Selection<'a> {
    pub wall: Option<&'a str>,
    pub eyes: &'a [Eye],
    /// Strategy-2 rays to list per view.
    pub rays: u32,
}

/// Inspects the selected views for one head pose.
pub fn inspect(rig: &Rig, head: &HeadPose, selection: &Selection) -> Report {
    let views = rig
        .walls
        .iter()
        .filter(|w| {
            selection
                .wall
                .is_none_or(|n| w.name.eq_ignore_ascii_case(n))
        })
        .flat_map(|w| {
            w.eyes
                .iter()
                .filter(|e| selection.eyes.contains(e))
                .map(move |&e| view_report(rig, w, e, head, selection.rays))
        })
        .collect();
    Report {
        rig: rig.name.clone(),
        units: rig.units.symbol(),
        head: HeadReport {
            position: head.position.to_array(),
            orientation: head.orientation.to_array(),
        },
        views,
    }
}

fn view_report(rig: &Rig, wall: &Wall, eye: Eye, head: &HeadPose, rays: u32) -> ViewReport {
    let eye_position = rig.eye_position(head, eye);
    let cameras = rig.view(wall, eye, head).and_then(|v| cameras(&v, rays));
    let (error, cameras) = match cameras {
        Ok(c) => (None, Some(c)),
        Err(e) => (Some(e.to_string()), None),
    };
    ViewReport {
        wall: wall.name.clone(),
        eye,
        eye_position: eye_position.to_array(),
        resolution: wall.resolution.to_array(),
        error,
        cameras,
    }
}

fn cameras(view: &View, rays: u32) -> Result<Cameras> {
    let matrix = view.matrix_camera()?;
    let pinhole = view.pinhole()?;
    let recovered = view.pinhole_from_matrices()?;
    let generators: [&dyn PrimaryRays; 4] = [&view.camera, &matrix, &pinhole, &recovered.camera];
    let compared = grid(view.resolution, COMPARE_GRID);
    let max_ray_disagreement = compared
        .iter()
        .map(|&p| disagreement(view, &generators, p))
        .fold(0.0, f64::max);
    Ok(Cameras {
        matrix: Matrices {
            view: view.projection.view.to_cols_array(),
            proj: view.projection.proj.to_cols_array(),
        },
        pinhole: pinhole_report(&pinhole),
        from_matrices: Recovered {
            pinhole: pinhole_report(&recovered.camera),
            recovered_eye: recovered.eye.to_array(),
        },
        max_ray_disagreement,
        pixels_compared: compared.len(),
        rays: spread(view.resolution, rays)
            .into_iter()
            .map(|p| {
                let r = pinhole.pixel_ray(p.x, p.y, view.resolution);
                RaySample {
                    pixel: p.to_array(),
                    origin: r.origin.to_array(),
                    direction: r.direction.to_array(),
                }
            })
            .collect(),
    })
}

/// How far apart the generators' rays for one pixel are, measured where it
/// matters: at the wall, and at the eye.
fn disagreement(view: &View, generators: &[&dyn PrimaryRays], pixel: UVec2) -> f64 {
    let screen = view.camera.screen();
    let target = screen.point(pixel_centre(pixel.x, pixel.y, view.resolution));
    generators
        .iter()
        .map(|g| {
            let ray = g.pixel_ray(pixel.x, pixel.y, view.resolution);
            let at_wall = ray
                .hit_plane(screen.ll(), screen.normal())
                .map_or(f64::INFINITY, |p| (p - target).length());
            at_wall.max(ray.distance_to_point(view.eye_position))
        })
        .fold(0.0, f64::max)
}

fn pinhole_report(p: &PinholeCamera) -> Pinhole {
    Pinhole {
        position: p.position().to_array(),
        direction: p.direction().to_array(),
        up: p.up().to_array(),
        fovy: p.fovy(),
        aspect: p.aspect(),
        image_region: p.image_region().to_array(),
    }
}

/// An n x n grid of pixels from the first to the last row and column.
fn grid(size: UVec2, n: u32) -> Vec<UVec2> {
    let axis = |len: u32| -> Vec<u32> {
        let n = n.min(len);
        (0..n)
            .map(|i| {
                if n == 1 {
                    len / 2
                } else {
                    (u64::from(i) * u64::from(len - 1) / u64::from(n - 1)) as u32
                }
            })
            .collect()
    };
    let (xs, ys) = (axis(size.x), axis(size.y));
    ys.iter()
        .flat_map(|&y| xs.iter().map(move |&x| UVec2::new(x, y)))
        .collect()
}

/// `count` pixels spread evenly over the image, lower-left first, row by
/// row; a single pixel is the centre one.
pub fn spread(size: UVec2, count: u32) -> Vec<UVec2> {
    if count == 0 {
        return Vec::new();
    }
    let cols = (f64::from(count).sqrt().ceil() as u32).max(1);
    let rows = count.div_ceil(cols);
    let place = |i: u32, n: u32, len: u32| -> u32 {
        let t = if n == 1 {
            0.5
        } else {
            f64::from(i) / f64::from(n - 1)
        };
        (t * f64::from(len - 1)).round() as u32
    };
    (0..count)
        .map(|k| UVec2::new(place(k % cols, cols, size.x), place(k / cols, rows, size.y)))
        .collect()
}
