//! A volume's scalar field as the isosurface caster reads it: trilinear or
//! tricubic B-spline filtering in grid space, with the gradient and the
//! Hessian, carried back to world space.

use glam::{DMat3, Mat3, UVec3, Vec3};
use rayon::prelude::*;

use crate::scene::PlacedVolume;

/// How the field between voxels is reconstructed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IsoFilter {
    /// Trilinear: values interpolated, derivatives by central differences.
    Trilinear,
    /// The cubic B-spline: smooth to the second derivative, so gradients
    /// and curvatures come from the filter itself.
    #[default]
    TricubicBSpline,
}

impl IsoFilter {
    pub const NAMES: [&'static str; 2] = ["trilinear", "tricubic"];

    pub fn name(self) -> &'static str {
        match self {
            IsoFilter::Trilinear => "trilinear",
            IsoFilter::TricubicBSpline => "tricubic",
        }
    }
}

impl std::str::FromStr for IsoFilter {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "trilinear" => Ok(IsoFilter::Trilinear),
            "tricubic" => Ok(IsoFilter::TricubicBSpline),
            _ => Err(format!(
                "unknown filter '{s}'; expected trilinear or tricubic"
            )),
        }
    }
}

/// Value, world gradient and world Hessian at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub value: f32,
    pub gradient: Vec3,
    pub hessian: Mat3,
}

/// The grid-space box outside which a field filtered by `filter` cannot
/// cross `iso` (empty, lo > hi, where it crosses nowhere): a crossing
/// point lies within the filter's reach of a vertex at or above the
/// iso-value and of one below it. `value(i)` is vertex i, x fastest.
pub fn crossing_box(
    dims: UVec3,
    value: impl Fn(usize) -> f32 + Sync,
    iso: f32,
    filter: IsoFilter,
) -> (Vec3, Vec3) {
    let (nx, slice) = (dims.x as usize, dims.x as usize * dims.y as usize);
    let empty = (UVec3::MAX, UVec3::ZERO);
    let grow = |b: (UVec3, UVec3), p: UVec3| (b.0.min(p), b.1.max(p));
    let join = |a: (UVec3, UVec3), b: (UVec3, UVec3)| (a.0.min(b.0), a.1.max(b.1));
    let (above, below) = (0..dims.z as usize)
        .into_par_iter()
        .map(|z| {
            let (mut above, mut below) = (empty, empty);
            for i in 0..slice {
                let p = UVec3::new((i % nx) as u32, (i / nx) as u32, z as u32);
                if value(z * slice + i) >= iso {
                    above = grow(above, p);
                } else {
                    below = grow(below, p);
                }
            }
            (above, below)
        })
        .reduce(|| (empty, empty), |a, b| (join(a.0, b.0), join(a.1, b.1)));
    if above.0.x > above.1.x || below.0.x > below.1.x {
        return (Vec3::ONE, Vec3::ZERO);
    }
    let reach = match filter {
        IsoFilter::Trilinear => 1.0,
        // The B-spline at a point weighs the vertices up to 2 away.
        IsoFilter::TricubicBSpline => 2.0,
    };
    let last = (dims - UVec3::ONE).as_vec3();
    let lo = (above.0.max(below.0).as_vec3() - reach).max(Vec3::ZERO);
    let hi = (above.1.min(below.1).as_vec3() + reach).min(last);
    (lo, hi)
}

/// One placed volume's values, and the maps between world and grid.
pub struct IsoField<'a> {
    values: &'a [f32],
    dims: UVec3,
    /// World point to grid point: linear part and offset.
    to_grid: Mat3,
    offset: Vec3,
    filter: IsoFilter,
}

impl<'a> IsoField<'a> {
    pub fn new(placed: &PlacedVolume, values: &'a [f32], filter: IsoFilter) -> Self {
        let m = placed.world_to_grid();
        Self {
            values,
            dims: placed.volume.dims(),
            to_grid: DMat3::from_mat4(m).as_mat3(),
            offset: m.w_axis.truncate().as_vec3(),
            filter,
        }
    }

    pub fn grid(&self, p: Vec3) -> Vec3 {
        self.to_grid * p + self.offset
    }

    /// The ray `o + t d` in grid space: origin and direction.
    pub fn grid_ray(&self, o: Vec3, d: Vec3) -> (Vec3, Vec3) {
        (self.grid(o), self.to_grid * d)
    }

    /// The last vertex of the grid.
    pub fn last_vertex(&self) -> Vec3 {
        (self.dims - UVec3::ONE).as_vec3()
    }

    fn voxel(&self, x: i32, y: i32, z: i32) -> f32 {
        let d = self.dims.as_ivec3();
        let (x, y, z) = (
            x.clamp(0, d.x - 1),
            y.clamp(0, d.y - 1),
            z.clamp(0, d.z - 1),
        );
        self.values[(x + d.x * (y + d.y * z)) as usize]
    }

    /// The march's innermost work: the cell's eight values are fetched
    /// once each, from one index and three strides (zero at the grid's
    /// last vertex, where the clamped point's cell has no far side).
    #[inline]
    fn trilinear(&self, g: Vec3) -> f32 {
        let g = g.clamp(Vec3::ZERO, self.last_vertex());
        // Not negative, so truncation is the floor.
        let (x, y, z) = (g.x as usize, g.y as usize, g.z as usize);
        let f = g - Vec3::new(x as f32, y as f32, z as f32);
        let (nx, ny, nz) = (
            self.dims.x as usize,
            self.dims.y as usize,
            self.dims.z as usize,
        );
        let sx = usize::from(x + 1 < nx);
        let sy = if y + 1 < ny { nx } else { 0 };
        let sz = if z + 1 < nz { nx * ny } else { 0 };
        let v = self.values;
        let i = x + nx * (y + ny * z);
        let (c000, c100, c010, c110) = (v[i], v[i + sx], v[i + sy], v[i + sx + sy]);
        let j = i + sz;
        let (c001, c101, c011, c111) = (v[j], v[j + sx], v[j + sy], v[j + sx + sy]);
        let x00 = c000 + (c100 - c000) * f.x;
        let x10 = c010 + (c110 - c010) * f.x;
        let x01 = c001 + (c101 - c001) * f.x;
        let x11 = c011 + (c111 - c011) * f.x;
        let y0 = x00 + (x10 - x00) * f.y;
        let y1 = x01 + (x11 - x01) * f.y;
        y0 + (y1 - y0) * f.z
    }

    /// The value at grid point `g` (no derivatives: the march's test).
    pub fn value(&self, g: Vec3) -> f32 {
        match self.filter {
            IsoFilter::Trilinear => self.trilinear(g),
            IsoFilter::TricubicBSpline => self.bspline(g, false).0,
        }
    }

    /// Value, gradient and Hessian at grid point `g`, in world space.
    pub fn sample(&self, g: Vec3) -> Sample {
        self.sample_with(g, true)
    }

    /// `sample`, with the Hessian (zero otherwise) only if `hessian`: the
    /// trilinear Hessian takes six gradients more.
    pub fn sample_with(&self, g: Vec3, hessian: bool) -> Sample {
        let (value, grad, hess) = match self.filter {
            IsoFilter::TricubicBSpline => self.bspline(g, true),
            IsoFilter::Trilinear if !hessian => {
                let grad = Vec3::new(
                    self.trilinear(g + Vec3::X) - self.trilinear(g - Vec3::X),
                    self.trilinear(g + Vec3::Y) - self.trilinear(g - Vec3::Y),
                    self.trilinear(g + Vec3::Z) - self.trilinear(g - Vec3::Z),
                ) * 0.5;
                (self.trilinear(g), grad, Mat3::ZERO)
            }
            IsoFilter::Trilinear => {
                // Central differences of the trilinear field, a voxel apart
                // for the gradient and again for the Hessian.
                let grad_at = |p: Vec3| {
                    Vec3::new(
                        self.trilinear(p + Vec3::X) - self.trilinear(p - Vec3::X),
                        self.trilinear(p + Vec3::Y) - self.trilinear(p - Vec3::Y),
                        self.trilinear(p + Vec3::Z) - self.trilinear(p - Vec3::Z),
                    ) * 0.5
                };
                let cols =
                    [Vec3::X, Vec3::Y, Vec3::Z].map(|e| (grad_at(g + e) - grad_at(g - e)) * 0.5);
                let h = Mat3::from_cols(cols[0], cols[1], cols[2]);
                // Symmetric, as a Hessian is.
                let h = (h + h.transpose()) * 0.5;
                (self.trilinear(g), grad_at(g), h)
            }
        };
        // grid = M world + c: d/dworld = Mᵀ d/dgrid.
        let m = self.to_grid;
        Sample {
            value,
            gradient: m.transpose() * grad,
            hessian: m.transpose() * hess * m,
        }
    }

    /// The cubic B-spline at `g` from its 4 x 4 x 4 neighbours: value, and
    /// with `derivatives` the grid-space gradient and Hessian.
    fn bspline(&self, g: Vec3, derivatives: bool) -> (f32, Vec3, Mat3) {
        let g = g.clamp(Vec3::ZERO, self.last_vertex());
        let i = g.floor();
        let f = g - i;
        let w = [weights(f.x), weights(f.y), weights(f.z)];
        let (x0, y0, z0) = (i.x as i32 - 1, i.y as i32 - 1, i.z as i32 - 1);
        let mut value = 0.0;
        let mut grad = Vec3::ZERO;
        let mut h = [[0.0f32; 3]; 3];
        for (c, wz) in (0..4).map(|c| (c, [w[2].0[c], w[2].1[c], w[2].2[c]])) {
            for (b, wy) in (0..4).map(|b| (b, [w[1].0[b], w[1].1[b], w[1].2[b]])) {
                for (a, wx) in (0..4).map(|a| (a, [w[0].0[a], w[0].1[a], w[0].2[a]])) {
                    let v = self.voxel(x0 + a as i32, y0 + b as i32, z0 + c as i32);
                    value += wx[0] * wy[0] * wz[0] * v;
                    if derivatives {
                        grad += Vec3::new(
                            wx[1] * wy[0] * wz[0],
                            wx[0] * wy[1] * wz[0],
                            wx[0] * wy[0] * wz[1],
                        ) * v;
                        h[0][0] += wx[2] * wy[0] * wz[0] * v;
                        h[1][1] += wx[0] * wy[2] * wz[0] * v;
                        h[2][2] += wx[0] * wy[0] * wz[2] * v;
                        h[0][1] += wx[1] * wy[1] * wz[0] * v;
                        h[0][2] += wx[1] * wy[0] * wz[1] * v;
                        h[1][2] += wx[0] * wy[1] * wz[1] * v;
                    }
                }
            }
        }
        let hess = Mat3::from_cols(
            Vec3::new(h[0][0], h[0][1], h[0][2]),
            Vec3::new(h[0][1], h[1][1], h[1][2]),
            Vec3::new(h[0][2], h[1][2], h[2][2]),
        );
        (value, grad, hess)
    }
}

/// The cubic B-spline's four weights at fraction `t`, and their first and
/// second derivatives.
fn weights(t: f32) -> ([f32; 4], [f32; 4], [f32; 4]) {
    let (t2, t3) = (t * t, t * t * t);
    let s = 1.0 - t;
    (
        [
            s * s * s / 6.0,
            (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0,
            (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0,
            t3 / 6.0,
        ],
        [
            -0.5 * s * s,
            1.5 * t2 - 2.0 * t,
            -1.5 * t2 + t + 0.5,
            0.5 * t2,
        ],
        [s, 3.0 * t - 2.0, -3.0 * t + 1.0, t],
    )
}

/// Principal curvatures (larger first) of the isosurface through a point
/// with world gradient `g` and Hessian `h` (Kindlmann et al. 2003), for the
/// normal -g/|g|: positive where the surface bulges towards the lower
/// values (a ball of high values is convex).
pub fn curvatures(g: Vec3, h: Mat3) -> (f32, f32) {
    let len = g.length();
    if len <= f32::MIN_POSITIVE {
        return (0.0, 0.0);
    }
    let n = -g / len;
    let p = Mat3::IDENTITY - Mat3::from_cols(n * n.x, n * n.y, n * n.z);
    let gm = -(p * h * p) / len;
    let t = gm.x_axis.x + gm.y_axis.y + gm.z_axis.z;
    let f2 = [gm.x_axis, gm.y_axis, gm.z_axis]
        .iter()
        .map(|c| c.length_squared())
        .sum::<f32>();
    let root = (2.0 * f2 - t * t).max(0.0).sqrt();
    ((t + root) / 2.0, (t - root) / 2.0)
}
