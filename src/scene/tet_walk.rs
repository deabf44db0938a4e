//! Point location by walking from tetrahedron to tetrahedron.
//!
//! Samples along a ray come one after another a cell's width apart, so the
//! tetrahedron holding a sample is, nearly always, the previous sample's or
//! one a face or two away from it. Each tetrahedron keeps the inverse of
//! its edge matrix (its barycentric coordinates are then nine
//! multiply-adds from its first vertex), the gradient of its linear field,
//! and its four face neighbours. A walk starts in the previous cell and
//! crosses the face opposite the most negative barycentric coordinate until
//! one cell holds the point; it gives up after a few cells, at the mesh's
//! boundary, or in any cell that is not a tetrahedron, and the caller then
//! asks the BVH. Where a walk succeeds its answer is the BVH's to rounding
//! (conforming meshes: neighbours agree on shared faces).

use std::collections::TryReserveError;

use glam::{Mat3, Vec3};
use rayon::prelude::*;

/// No cell: the mesh's boundary, or a cell the walk cannot enter.
pub const NO_CELL: u32 = u32::MAX;

/// Cells a walk visits before it hands over to the BVH: a step of the
/// march crosses one or two cells of the mesh it is spaced by.
pub const WALK_STEPS: u32 = 8;

/// One tetrahedron as a walk reads it: 80 bytes, one or two cache lines.
#[derive(Clone, Copy, Debug)]
struct Tet {
    /// The first vertex; every coordinate is taken from it.
    origin: Vec3,
    /// The field at `origin`.
    value: f32,
    /// Rows of the inverse edge matrix: barycentric coordinates 1 to 3
    /// of `p` are their dot products with `p - origin`. NaN where the
    /// cell is flat or no tetrahedron, which no point then lies in.
    rows: [Vec3; 3],
    /// The field's gradient: zero for cell data.
    gradient: Vec3,
    /// The cell across the face opposite each vertex, or NO_CELL.
    next: [u32; 4],
}

impl Tet {
    const NONE: Tet = Tet {
        origin: Vec3::ZERO,
        value: 0.0,
        rows: [Vec3::NAN; 3],
        gradient: Vec3::ZERO,
        next: [NO_CELL; 4],
    };
}

/// The tetrahedra of a mesh, indexed by the mesh's cell numbers, with
/// their neighbours.
#[derive(Clone, Debug, Default)]
pub struct TetWalk {
    tets: Vec<Tet>,
}

/// What a walk needs to know of a mesh's cells.
pub trait TetCells: Sync {
    fn len(&self) -> usize;
    /// How many of the cells are tetrahedra.
    fn tetrahedra(&self) -> usize;

    /// Cell `c`'s four vertex numbers, if it is a tetrahedron.
    fn tetrahedron(&self, c: usize) -> Option<[u32; 4]>;
    fn position(&self, vertex: u32) -> Vec3;
    /// The field at each of tetrahedron `c`'s four vertices (`ids`).
    fn values(&self, c: usize, ids: [u32; 4]) -> [f32; 4];
}

impl TetWalk {
    /// Bytes per cell.
    pub const CELL_BYTES: u64 = std::mem::size_of::<Tet>() as u64;

    pub fn new(cells: &impl TetCells) -> Result<Self, TryReserveError> {
        let n = cells.len();
        let mut tets = Vec::new();
        tets.try_reserve_exact(n)?;
        // Each tetrahedron's faces as their sorted vertex numbers (the
        // high 96 bits) and cell << 2 | the vertex opposite (the low 32):
        // shared faces sort together.
        let mut faces: Vec<u128> = Vec::new();
        faces.try_reserve_exact(4 * cells.tetrahedra())?;
        for c in 0..n {
            let Some(ids) = cells.tetrahedron(c) else {
                tets.push(Tet::NONE);
                continue;
            };
            tets.push(tetrahedron(cells, c, ids));
            for (i, face) in [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]
                .into_iter()
                .enumerate()
            {
                let mut key = face.map(|k| ids[k]);
                key.sort_unstable();
                faces.push(
                    u128::from(key[0]) << 96
                        | u128::from(key[1]) << 64
                        | u128::from(key[2]) << 32
                        | u128::from((c as u32) << 2 | i as u32),
                );
            }
        }
        faces.par_sort_unstable();
        let mut k = 0;
        while k < faces.len() {
            let mut end = k + 1;
            while end < faces.len() && faces[end] >> 32 == faces[k] >> 32 {
                end += 1;
            }
            // Exactly two cells on a face are neighbours; a face of three
            // or more (a non-manifold mesh) is left to the BVH.
            if end - k == 2 {
                let (a, b) = (faces[k] as u32, faces[k + 1] as u32);
                tets[(a >> 2) as usize].next[(a & 3) as usize] = b >> 2;
                tets[(b >> 2) as usize].next[(b & 3) as usize] = a >> 2;
            }
            k = end;
        }
        Ok(Self { tets })
    }

    /// Words per cell in [`words`](Self::words).
    pub const CELL_WORDS: usize = 21;

    /// Every cell as the GPU's walk reads it, 21 u32 words: the first
    /// vertex (3 f32), the field there, the three rows of the inverse edge
    /// matrix (9 f32), the gradient (3 f32), the four neighbours, and 1
    /// for a tetrahedron a point can lie in (0 for a flat cell or another
    /// kind, whose NaN rows a shader may not see as NaN).
    pub fn words(&self) -> impl Iterator<Item = u32> + '_ {
        self.tets.iter().flat_map(|t| {
            let usable = t.rows.iter().all(|r| r.is_finite());
            let rows = if usable { t.rows } else { [Vec3::ZERO; 3] };
            let floats = t
                .origin
                .to_array()
                .into_iter()
                .chain([t.value])
                .chain(rows.into_iter().flat_map(|r| r.to_array()))
                .chain(t.gradient.to_array());
            floats
                .map(f32::to_bits)
                .chain(t.next)
                .chain([u32::from(usable)])
        })
    }

    /// The field at `p` and the tetrahedron strictly holding it (within
    /// a tolerance a point may lie in two cells, which would make cell
    /// data depend on where a walk began), walking from cell `start`;
    /// `None` where the walk gives up.
    pub fn walk(&self, p: Vec3, start: u32) -> Option<(f32, u32)> {
        let mut c = start;
        for _ in 0..WALK_STEPS {
            let t = self.tets.get(c as usize)?;
            let q = p - t.origin;
            let l = [0.0, t.rows[0].dot(q), t.rows[1].dot(q), t.rows[2].dot(q)];
            let l0 = 1.0 - l[1] - l[2] - l[3];
            // Written so that NaN (no tetrahedron) is never inside.
            if l0 >= 0.0 && l[1] >= 0.0 && l[2] >= 0.0 && l[3] >= 0.0 {
                return Some((t.value + t.gradient.dot(q), c));
            }
            let mut worst = 0;
            let mut least = l0;
            for (i, &x) in l.iter().enumerate().skip(1) {
                if x < least {
                    least = x;
                    worst = i;
                }
            }
            c = t.next[worst];
        }
        None
    }
}

/// Tetrahedron `c` of vertices `ids`, its neighbours not yet known.
fn tetrahedron(cells: &impl TetCells, c: usize, ids: [u32; 4]) -> Tet {
    let v = ids.map(|i| cells.position(i));
    let edges = Mat3::from_cols(v[1] - v[0], v[2] - v[0], v[3] - v[0]);
    let det = edges.determinant();
    if det == 0.0 || !det.is_finite() {
        return Tet::NONE;
    }
    let inverse = edges.inverse().transpose();
    let rows = [inverse.x_axis, inverse.y_axis, inverse.z_axis];
    if rows.iter().any(|r| !r.is_finite()) {
        return Tet::NONE;
    }
    let f = cells.values(c, ids);
    // f(p) = f0 + sum_k (f_k - f0) * lambda_k(p), each lambda_k linear.
    let gradient = if f.iter().all(|&x| x == f[0]) {
        Vec3::ZERO
    } else {
        (f[1] - f[0]) * rows[0] + (f[2] - f[0]) * rows[1] + (f[3] - f[0]) * rows[2]
    };
    Tet {
        origin: v[0],
        value: f[0],
        rows,
        gradient,
        next: [NO_CELL; 4],
    }
}
