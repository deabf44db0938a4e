//! Re-projection planned from the eyes' real matrices, for any pair of
//! views whose image planes are one plane (a CAVE wall seen by both eyes)
//! or parallel with the same pixel grid (an HMD's two screens).
//!
//! Then a point at depth z (along the common view axis) seen by the left
//! eye at pixel p is seen by the right eye at `p + lambda(z) g(p)`, where
//! `g(p) = w p - (x, y)` and `(x, y, w)` is the epipole in homogeneous
//! pixel coordinates: the point where the baseline meets the image plane.
//! A baseline parallel to the plane puts the epipole at infinity (w = 0):
//! every point shifts along the same direction, the rows of a level head
//! or tilted lines of a rolled one. A baseline with a component towards
//! the plane (a side wall, a turned head) gives a finite epipole: points
//! move along lines radiating from it, by a share of their distance to it.
//!
//! Each left ray's right-eye segments are written per whole pixel along
//! the major axis of its epipolar line: lines closer to the rows than to
//! the columns ("columns" family) are cut at right-eye columns, the others
//! ("rows" family) at right-eye rows. docs/reprojection_stereo.md gives
//! the layer assignment and why no two rays share a texel.

use glam::{DVec2, DVec3, IVec2, UVec2};
use thiserror::Error;

use super::bounds::Bounds;
use super::layers::{layer_memory, LayerFormat};
use crate::geometry::MatrixCamera;

/// Why a view pair cannot use re-projection (it then renders two passes).
#[derive(Debug, Error, PartialEq)]
pub enum NotEpipolar {
    #[error("a point leaves its epipolar line by {0:.2} pixels between the eyes (the eyes' image planes are neither one plane nor parallel)")]
    OffLine(f64),
    #[error("the shift between the eyes varies by {0:.2} pixels at one depth (the image planes are not parallel)")]
    UnevenShift(f64),
    #[error("the volume reaches so close to the right eye that the left eye sees it {0:.2}x as large (at most 2x re-projects)")]
    TooClose(f64),
    #[error("the volume reaches between the eyes' planes parallel to the image: one eye sees parts of it that lie behind the other")]
    BetweenEyes,
    #[error("the volume is outside both eyes' views")]
    Behind,
    #[error("{0}")]
    Matrices(String),
}

/// The two ways a right-eye segment is cut: at whole columns or rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    Columns = 0,
    Rows = 1,
}

/// A planned pair of views.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewPlan {
    pub size: UVec2,
    /// The epipole (x, y, w) in homogeneous pixel coordinates (pixel
    /// centres on whole numbers), scaled so that `max(|x|, |y|, |w| s)` is
    /// 1 with s the image's larger side.
    pub epipole: DVec3,
    /// `lambda` at the nearest and at the farthest visible depth.
    pub lambda: [f64; 2],
    /// Which families of lines cross the image: `[columns, rows]`.
    pub families: [bool; 2],
    /// The first left pixel cast and how many: the image plus the pixels
    /// beyond it whose rays the right eye sees.
    pub first: IVec2,
    pub cast: UVec2,
    /// Longest run of pixels one ray writes along its major axis.
    pub span_px: f64,
    /// Layers of each family.
    pub layers: u32,
}

impl ViewPlan {
    /// The direction a left pixel's right-eye image moves in with depth
    /// (up to the sign and size of lambda).
    pub fn g(&self, p: DVec2) -> DVec2 {
        self.epipole.z * p - glam::DVec2::new(self.epipole.x, self.epipole.y)
    }

    /// The family a right pixel reads: its line's major axis.
    pub fn axis_at(&self, q: DVec2) -> Axis {
        let g = self.g(q);
        if g.x.abs() >= g.y.abs() {
            Axis::Columns
        } else {
            Axis::Rows
        }
    }

    /// Whether left pixel `p` writes family `axis`: a little past the
    /// diagonal, since the rays a right pixel reads lie up to half a pixel
    /// off its line (docs/reprojection_stereo.md).
    pub fn writes(&self, p: DVec2, axis: Axis) -> bool {
        if !self.families[axis as usize] {
            return false;
        }
        let g = self.g(p);
        let (major, minor) = match axis {
            Axis::Columns => (g.x, g.y),
            Axis::Rows => (g.y, g.x),
        };
        major.abs() >= minor.abs() - self.epipole.z.abs()
    }

    /// The whole-pixel offsets along `axis` (right pixel minus left
    /// pixel) a ray of left pixel `p` writes, nearest first.
    pub fn ray_offsets(&self, p: DVec2, axis: Axis) -> [i32; 2] {
        let g = self.g(p)[axis as usize];
        self.lambda.map(|l| (l * g).round() as i32)
    }

    /// The offsets, nearest first, of the left rays right pixel `q`
    /// reads along `axis`, one past each end for rounding.
    pub fn read_offsets(&self, q: DVec2, axis: Axis) -> [i32; 2] {
        let w = self.epipole.z;
        let g = self.g(q)[axis as usize];
        let [near, far] = self.lambda.map(|l| (l * g / (1.0 + l * w)).round() as i32);
        let step = if far >= near { 1 } else { -1 };
        [near - step, far + step]
    }

    /// The left pixels whose rays right pixel `q` reads at `offset`
    /// along `axis`, with their shares: q's epipolar line passes between
    /// them, and the composite blends them by where.
    pub fn read_pixels(&self, q: IVec2, offset: i32, axis: Axis) -> [(IVec2, f64); 2] {
        let g = self.g(q.as_dvec2());
        let (i, j) = match axis {
            Axis::Columns => (0, 1),
            Axis::Rows => (1, 0),
        };
        let slope = if g[i] == 0.0 { 0.0 } else { g[j] / g[i] };
        let across = f64::from(q[j]) - f64::from(offset) * slope;
        let below = across.floor();
        let f = across - below;
        [(0, 1.0 - f), (1, f)].map(|(k, share)| {
            let mut p = q;
            p[i] = q[i] - offset;
            p[j] = below as i32 + k;
            (p, share)
        })
    }

    /// Families in use.
    pub fn family_count(&self) -> u32 {
        self.families.iter().filter(|&&f| f).count() as u32
    }

    /// The layer textures' width and height: right-eye columns by cast
    /// rows for the columns family, cast columns by right-eye rows for the
    /// rows family.
    pub fn texture_size(&self) -> UVec2 {
        UVec2::new(
            if self.families[1] {
                self.cast.x
            } else {
                self.size.x
            },
            if self.families[0] {
                self.cast.y
            } else {
                self.size.y
            },
        )
    }

    /// Bytes of the layers in `format`.
    pub fn memory(&self, layers: u32, format: LayerFormat) -> u64 {
        layer_memory(self.texture_size(), layers * self.family_count(), format)
    }
}

/// The pixel of a world point, centres on whole numbers, lower left first.
fn pixel(m: &MatrixCamera, p: DVec3, size: DVec2) -> DVec2 {
    let ndc = m.project(p);
    (DVec2::new(ndc.x, ndc.y) + 1.0) * 0.5 * size - 0.5
}

/// The epipole of the right image: the left eye as the right eye sees it,
/// normalised as `ViewPlan::epipole` says. `None` if the eyes coincide.
fn epipole(right: &MatrixCamera, left_eye: DVec3, size: DVec2) -> Option<DVec3> {
    let c = right.proj() * right.view() * left_eye.extend(1.0);
    let h = DVec3::new(
        (c.x + c.w) * 0.5 * size.x - 0.5 * c.w,
        (c.y + c.w) * 0.5 * size.y - 0.5 * c.w,
        c.w,
    );
    let n = h.x.abs().max(h.y.abs()).max(h.z.abs() * size.max_element());
    (n > 0.0 && n.is_finite()).then(|| h / n)
}

/// Plans re-projection from the OpenGL matrices of both eyes for an image
/// of `width` x `height` pixels and the scene's bounds. Fails with the
/// reason when the views do not share an image plane's geometry.
pub fn plan_views(
    left: &MatrixCamera,
    right: &MatrixCamera,
    width: u32,
    height: u32,
    bounds: Bounds,
) -> Result<ViewPlan, NotEpipolar> {
    let size = DVec2::new(width.into(), height.into());
    let matrices = |e: crate::geometry::GeometryError| NotEpipolar::Matrices(e.to_string());
    let eye = crate::geometry::pinhole_from_matrices(left.view(), left.proj())
        .map_err(matrices)?
        .eye;
    let right_eye = crate::geometry::pinhole_from_matrices(right.view(), right.proj())
        .map_err(matrices)?
        .eye;
    // Depth is measured along the view's -Z (the wall normal on a CAVE
    // wall), not through the off-axis frustum's centre.
    let axis = left
        .view()
        .inverse()
        .transform_vector3(DVec3::NEG_Z)
        .normalize();
    let near = (left.unproject(DVec3::new(0.0, 0.0, -1.0)) - eye).dot(axis);
    let (z_near, z_far) = bounds
        .depths(&[left, right], eye, axis)
        .ok_or(NotEpipolar::Behind)?;
    let z_near = z_near.max(near);
    if z_far <= near {
        return Err(NotEpipolar::Behind);
    }
    // Eyes in one place see one image: a row-wise plan with no shift.
    // Rounding noise must not turn a level head's rows into lines that
    // meet a trillion pixels away.
    let epipole =
        epipole(right, eye, size)
            .unwrap_or(DVec3::X)
            .map(|c| if c.abs() < 1e-9 { 0.0 } else { c });
    let mut plan = ViewPlan {
        size: UVec2::new(width, height),
        epipole,
        lambda: [0.0; 2],
        families: [true, false],
        first: IVec2::ZERO,
        cast: UVec2::new(width, height),
        span_px: 0.0,
        layers: 1,
    };
    if (right_eye - eye).length() > 0.0 {
        for (slot, z) in [z_near, z_far].into_iter().enumerate() {
            plan.lambda[slot] = lambda_at(&plan, left, right, eye, axis, z, size)?;
        }
    }
    // 1 + lambda w is the scale from the left image to the right one
    // about the epipole; below 1 the rays a texel could receive crowd.
    let shrink = shrink(&plan);
    if shrink <= 0.0 {
        return Err(NotEpipolar::BetweenEyes);
    }
    if shrink < 0.5 {
        return Err(NotEpipolar::TooClose(1.0 / shrink));
    }
    plan.families = families(&plan);
    plan.first_and_cast();
    plan.layers = layers(&plan);
    plan.span_px = span(&plan);
    Ok(plan)
}

/// lambda at depth `z`, fitted over a grid of the left view, with the
/// checks that the model holds there.
fn lambda_at(
    plan: &ViewPlan,
    left: &MatrixCamera,
    right: &MatrixCamera,
    eye: DVec3,
    axis: DVec3,
    z: f64,
    size: DVec2,
) -> Result<f64, NotEpipolar> {
    let mut points = Vec::with_capacity(9);
    for u in [-1.0, 0.0, 1.0] {
        for v in [-1.0, 0.0, 1.0] {
            let through = left.unproject(DVec3::new(u, v, 0.0));
            let dir = (through - eye).normalize();
            let p = eye + dir * (z / dir.dot(axis));
            let l = pixel(left, p, size);
            points.push((l, pixel(right, p, size) - l, plan.g(l)));
        }
    }
    let (num, den) = points.iter().fold((0.0, 0.0), |(n, d), (_, shift, g)| {
        (n + shift.dot(*g), d + g.dot(*g))
    });
    if !(den > 0.0 && num.is_finite()) {
        return Err(NotEpipolar::Matrices(
            "the eyes' matrices give no finite pixel offsets".into(),
        ));
    }
    let lambda = num / den;
    let (mut off, mut uneven) = (0.0f64, 0.0f64);
    for (_, shift, g) in &points {
        let along = g.normalize_or_zero();
        let error = *shift - lambda * *g;
        off = off.max(error.perp_dot(along).abs());
        uneven = uneven.max(error.dot(along).abs());
    }
    if off > 0.5 {
        return Err(NotEpipolar::OffLine(off));
    }
    if uneven > 0.5 {
        return Err(NotEpipolar::UnevenShift(uneven));
    }
    Ok(lambda)
}

/// The image's corners as pixel centres.
fn corners(size: UVec2) -> [DVec2; 4] {
    let (x, y) = (f64::from(size.x) - 1.0, f64::from(size.y) - 1.0);
    [
        DVec2::ZERO,
        DVec2::new(x, 0.0),
        DVec2::new(0.0, y),
        DVec2::new(x, y),
    ]
}

/// The smallest and largest |value| of an affine function of p over the
/// rectangle `lo..=hi`, per axis of g.
fn g_range(plan: &ViewPlan, lo: DVec2, hi: DVec2, i: usize) -> (f64, f64) {
    let (a, b) = (plan.g(lo)[i], plan.g(hi)[i]);
    let min = if a * b <= 0.0 {
        0.0
    } else {
        a.abs().min(b.abs())
    };
    (min, a.abs().max(b.abs()))
}

/// Which families some right pixel reads.
fn families(plan: &ViewPlan) -> [bool; 2] {
    let hi = plan.size.as_dvec2() - 1.0;
    let (min_x, max_x) = g_range(plan, DVec2::ZERO, hi, 0);
    let (min_y, max_y) = g_range(plan, DVec2::ZERO, hi, 1);
    [max_x >= min_y, max_y > min_x]
}

impl ViewPlan {
    /// The left pixels right pixels read: `p - q = -lambda g(q) / (1 +
    /// lambda w)` at the ends of the depth range, affine in q, so the
    /// image's corners bound it; plus the read's rounding.
    fn first_and_cast(&mut self) {
        let w = self.epipole.z;
        let (mut lo, mut hi) = (DVec2::ZERO, DVec2::ZERO);
        for q in corners(self.size) {
            for l in self.lambda {
                let d = -l * self.g(q) / (1.0 + l * w);
                lo = lo.min(d);
                hi = hi.max(d);
            }
        }
        // Reads reach one offset past the rounded ends, and round across
        // the line: a pixel more on each side where anything moves.
        let g = self.g(DVec2::ZERO);
        let moves = DVec2::new(
            f64::from(u8::from(w != 0.0 || g.x != 0.0)),
            f64::from(u8::from(w != 0.0 || g.y != 0.0)),
        );
        let lo = lo.floor() - moves;
        let hi = hi.ceil() + moves;
        self.first = lo.as_ivec2();
        self.cast = (self.size.as_ivec2() - lo.as_ivec2() + hi.as_ivec2()).as_uvec2();
    }
}

/// The smallest scale `1 + lambda w` from the left image to the right
/// one over the depth range.
fn shrink(plan: &ViewPlan) -> f64 {
    plan.lambda
        .iter()
        .map(|l| 1.0 + l * plan.epipole.z)
        .fold(f64::INFINITY, f64::min)
}

/// Layers per family so that two rays whose writes could meet in one
/// texel never share a layer: with the epipole at infinity every ray
/// writes the same rounded offsets; otherwise two rays that reach one
/// texel are at most `(spread g + 1) / (1 + lambda w)` pixels apart
/// (docs/reprojection_stereo.md).
fn layers(plan: &ViewPlan) -> u32 {
    let lo = plan.first.as_dvec2();
    let hi = lo + plan.cast.as_dvec2() - 1.0;
    let w = plan.epipole.z;
    let shrink = shrink(plan);
    let spread = (plan.lambda[1] - plan.lambda[0]).abs();
    let mut layers = 1u32;
    for axis in [Axis::Columns, Axis::Rows] {
        if !plan.families[axis as usize] {
            continue;
        }
        let (_, g_max) = g_range(plan, lo, hi, axis as usize);
        let needed = if w == 0.0 {
            let [a, b] = plan.ray_offsets(lo, axis);
            a.abs_diff(b) + 1
        } else {
            ((spread * g_max + 1.0) / shrink).floor() as u32 + 1
        };
        layers = layers.max(needed);
    }
    layers
}

/// `plan.span_px`: the longest run one ray writes.
fn span(plan: &ViewPlan) -> f64 {
    let lo = plan.first.as_dvec2();
    let hi = lo + plan.cast.as_dvec2() - 1.0;
    let spread = (plan.lambda[1] - plan.lambda[0]).abs();
    (0..2)
        .map(|i| spread * g_range(plan, lo, hi, i).1)
        .fold(0.0, f64::max)
}
