//! Point location by walking from tetrahedron to tetrahedron, and rays
//! followed through them.
//!
//! Samples along a ray come one after another a cell's width apart, so the
//! tetrahedron holding a sample is, nearly always, the previous sample's or
//! one a face or two away from it. Each tetrahedron keeps the affine map
//! from a point to its four barycentric coordinates (three four-lane
//! multiply-adds from its first vertex), its field's change along them,
//! and its four face neighbours. A walk starts in the previous cell and
//! crosses the face opposite the most negative barycentric coordinate until
//! one cell holds the point; a ray crosses the face its coordinates reach
//! first. Both give up after a few cells, at the mesh's boundary, or in any
//! cell that is not a tetrahedron, and the caller then asks the BVH. Where
//! they succeed their answer is the BVH's to rounding (conforming meshes:
//! neighbours agree on shared faces).

use std::collections::TryReserveError;

use glam::{Mat3, Vec3, Vec4};
use rayon::prelude::*;

/// No cell: the mesh's boundary, or a cell the walk cannot enter.
pub const NO_CELL: u32 = u32::MAX;

/// Cells a walk visits before it hands over to the BVH: a step of the
/// march crosses one or two cells of the mesh it is spaced by.
pub const WALK_STEPS: u32 = 8;

/// One tetrahedron as a walk reads it: 96 bytes, in four-lane vectors
/// so that its four barycentric coordinates, and how they change along a
/// ray, are each three vector multiply-adds.
// Aligned to 32 bytes so that a cell spans two cache lines, never three.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
struct Tet {
    /// Columns of the map from `q = p - origin` to the barycentric
    /// coordinates: lambda = `bary[0] q.x + bary[1] q.y + bary[2] q.z +
    /// (1, 0, 0, 0)`. NaN where the cell is flat or no tetrahedron, which
    /// no point then lies in.
    bary: [Vec4; 3],
    /// The first vertex; every coordinate is taken from it. In `w`, the
    /// field there.
    origin: Vec4,
    /// The field at each vertex less the field at the first: the field is
    /// `origin.w + dot(change, lambda)` (exactly `origin.w` for cell data).
    change: Vec4,
    /// The cell across the face opposite each vertex, or NO_CELL.
    next: [u32; 4],
}

impl Tet {
    const NONE: Tet = Tet {
        bary: [Vec4::NAN; 3],
        origin: Vec4::ZERO,
        change: Vec4::ZERO,
        next: [NO_CELL; 4],
    };

    /// The barycentric coordinates at `q` (from the first vertex), and
    /// their change along `d`.
    fn lambda(&self, q: Vec3) -> Vec4 {
        self.bary[0] * q.x + self.bary[1] * q.y + self.bary[2] * q.z + Vec4::X
    }

    fn lambda_along(&self, d: Vec3) -> Vec4 {
        self.bary[0] * d.x + self.bary[1] * d.y + self.bary[2] * d.z
    }

    /// The inverse edge matrix's rows: lambda 1 to 3 are their dot
    /// products with `q`.
    fn rows(&self) -> [Vec3; 3] {
        let [x, y, z] = self.bary;
        [1, 2, 3].map(|k| Vec3::new(x[k], y[k], z[k]))
    }
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
            let rows = t.rows();
            let usable = rows.iter().all(|r| r.is_finite());
            let rows = if usable { rows } else { [Vec3::ZERO; 3] };
            let gradient = rows
                .iter()
                .zip(&t.change.to_array()[1..])
                .fold(Vec3::ZERO, |g, (r, &f)| g + f * *r);
            let floats = t
                .origin
                .to_array()
                .into_iter()
                .chain(rows.into_iter().flat_map(|r| r.to_array()))
                .chain(gradient.to_array());
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
            let l = t.lambda(p - t.origin.truncate());
            // Written so that NaN (no tetrahedron) is never inside.
            if l.cmpge(Vec4::ZERO).all() {
                return Some((t.origin.w + t.change.dot(l), c));
            }
            // Across the face opposite the most negative coordinate (none
            // where they are NaN: the walk ends).
            let worst = l
                .cmpeq(Vec4::splat(l.min_element()))
                .bitmask()
                .trailing_zeros();
            c = *t.next.get(worst as usize)?;
        }
        None
    }
}

/// Where a ray `o + t d` runs through one tetrahedron: from `t_in` to
/// `t_out`, the field along it linear in t, and the cell it leaves into.
#[derive(Clone, Copy, Debug)]
pub struct Stretch {
    pub cell: u32,
    pub t_in: f32,
    pub t_out: f32,
    /// The field is `a + b t` in here.
    a: f32,
    b: f32,
    /// The neighbour across the face the ray leaves by, or NO_CELL.
    next: u32,
}

impl Stretch {
    pub fn value(&self, t: f32) -> f32 {
        self.a + self.b * t
    }

    /// Whether `t` lies in here.
    pub fn holds(&self, t: f32) -> bool {
        self.t_in <= t && t <= self.t_out
    }
}

impl TetWalk {
    /// Cell `c`'s stretch of the ray `o + t d`; `None` where the ray
    /// misses it or it is no tetrahedron a point can lie in.
    ///
    /// Each barycentric coordinate is linear in t: the ray is inside
    /// while all four are >= 0, and leaves where the first falls to 0,
    /// through the face opposite that vertex.
    pub fn stretch(&self, c: u32, o: Vec3, d: Vec3) -> Option<Stretch> {
        let t = self.tets.get(c as usize)?;
        for n in t.next {
            self.prefetch(n);
        }
        let l = t.lambda(o - t.origin.truncate());
        let dl = t.lambda_along(d);
        if (dl.cmpeq(Vec4::ZERO) & l.cmplt(Vec4::ZERO)).any() {
            // Parallel to a face and outside it.
            return None;
        }
        let at = -l / dl;
        let leaving = Vec4::select(dl.cmplt(Vec4::ZERO), at, Vec4::INFINITY);
        let t_out = leaving.min_element();
        let t_in = Vec4::select(dl.cmpgt(Vec4::ZERO), at, Vec4::NEG_INFINITY).max_element();
        // A ray with a direction leaves every tetrahedron (the changes
        // sum to 0); NaN (no tetrahedron) is never in one.
        if !(t_in <= t_out && t_out < f32::INFINITY) {
            return None;
        }
        let exit = leaving.cmpeq(Vec4::splat(t_out)).bitmask().trailing_zeros();
        let next = t.next.get(exit as usize).copied().unwrap_or(NO_CELL);
        Some(Stretch {
            cell: c,
            t_in,
            t_out,
            a: t.origin.w + t.change.dot(l),
            b: t.change.dot(dl),
            next,
        })
    }

    /// Asks for cell `c` to be brought into cache: a ray's next cell is
    /// known a sample's work before it is read, and the walk is a chain
    /// of loads that each wait on the one before.
    fn prefetch(&self, c: u32) {
        #[cfg(target_arch = "x86_64")]
        if let Some(t) = self.tets.get(c as usize) {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            let at = std::ptr::from_ref(t).cast::<i8>();
            // SAFETY: prefetching reads nothing; both addresses lie in `t`.
            unsafe {
                _mm_prefetch::<_MM_HINT_T0>(at);
                _mm_prefetch::<_MM_HINT_T0>(at.add(64));
            }
        }
    }

    /// The stretch holding `t` of a ray whose last sample was in
    /// `from`, crossing at most `steps` faces forward; `None` where the
    /// ray leaves the mesh's tetrahedra (or goes back) first.
    pub fn follow(&self, from: Stretch, o: Vec3, d: Vec3, t: f32, steps: u32) -> Option<Stretch> {
        let mut s = from;
        for _ in 0..steps {
            if t <= s.t_out {
                break;
            }
            s = self.stretch(s.next, o, d)?;
        }
        s.holds(t).then_some(s)
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
    // lambda_0 = 1 - lambda_1 - lambda_2 - lambda_3.
    let first = -(rows[0] + rows[1] + rows[2]);
    let column = |k: usize| Vec4::new(first[k], rows[0][k], rows[1][k], rows[2][k]);
    let f = cells.values(c, ids);
    Tet {
        bary: [column(0), column(1), column(2)],
        origin: v[0].extend(f[0]),
        // f(p) = f0 + sum_k (f_k - f0) lambda_k(p).
        change: Vec4::new(0.0, f[1] - f[0], f[2] - f[0], f[3] - f[0]),
        next: [NO_CELL; 4],
    }
}
