//! Unstructured volumes: tetrahedra, hexahedra, wedges and pyramids with
//! VTK's vertex order and shape functions, values per vertex or per cell,
//! as ANARI's `unstructured` spatial field and VTK's unstructured grids
//! hold them.
//!
//! A sample is exact: barycentric inside a tetrahedron, VTK's shape
//! functions inverted by Newton's method inside the other cells, a cell's
//! own value for cell data, and nothing (NaN) outside every cell. The cell
//! holding a point is found through a BVH over the cells' boxes, built
//! once by median splits (so its depth is bounded by the cell count's
//! logarithm, which the shaders' fixed traversal stack relies on). Cells
//! are kept in the BVH's leaf order, so that a leaf's cells are one run,
//! on the CPU and in the GPU's words alike.
//!
//! Rays march an unstructured volume through a lattice over its bounds
//! (its `dims`, `origin` and `spacing`, as a structured grid's), spaced by
//! the mesh's typical cell edge: the march, its step and the empty-space
//! bricks are then the structured ones, and only the sample differs.

use glam::{Mat3, UVec3, Vec3};
use thiserror::Error;

pub use super::tet_walk::WALK_STEPS;
use super::tet_walk::{Stretch, TetCells, TetWalk};

/// The most vertex positions, cells and index entries an unstructured
/// volume takes. A cell's first index shares a word with its type on the
/// GPU (30 bits of it); 2^28 positions are 3 GiB of them.
pub const MAX_MESH_VERTICES: u64 = 1 << 28;
pub const MAX_MESH_CELLS: u64 = 1 << 28;
pub const MAX_MESH_INDICES: u64 = 1 << 30;

/// The most lattice vertices per axis: enough for the empty-space bricks
/// to follow a mesh; past it the lattice is coarser than its cells.
const MAX_LATTICE: u32 = 1024;

/// Cells per BVH leaf.
const LEAF_CELLS: usize = 4;

/// The deepest a BVH of MAX_MESH_CELLS cells gets by median splits, and
/// so the traversal stack both renderers keep.
pub const MESH_STACK: usize = 32;

/// Newton steps at most, and the change in parametric coordinates at
/// which they stop.
pub const NEWTON_STEPS: u32 = 12;
pub const NEWTON_TOLERANCE: f32 = 1e-6;

/// How far outside a cell, in its parametric coordinates, a point still
/// counts as in it: rounding must not open cracks between neighbours.
pub const CELL_TOLERANCE: f32 = 1e-4;

/// A cell's shape, by its VTK code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellKind {
    Tetrahedron,
    Hexahedron,
    Wedge,
    Pyramid,
}

impl CellKind {
    pub const ALL: [CellKind; 4] = [
        CellKind::Tetrahedron,
        CellKind::Hexahedron,
        CellKind::Wedge,
        CellKind::Pyramid,
    ];

    pub fn from_vtk(code: u64) -> Option<Self> {
        match code {
            10 => Some(CellKind::Tetrahedron),
            12 => Some(CellKind::Hexahedron),
            13 => Some(CellKind::Wedge),
            14 => Some(CellKind::Pyramid),
            _ => None,
        }
    }

    pub fn vtk(self) -> u8 {
        match self {
            CellKind::Tetrahedron => 10,
            CellKind::Hexahedron => 12,
            CellKind::Wedge => 13,
            CellKind::Pyramid => 14,
        }
    }

    /// The code the shaders read (the low two bits of a cell's word).
    pub fn code(self) -> u32 {
        match self {
            CellKind::Tetrahedron => 0,
            CellKind::Hexahedron => 1,
            CellKind::Wedge => 2,
            CellKind::Pyramid => 3,
        }
    }

    fn from_code(code: u32) -> Self {
        Self::ALL[(code & 3) as usize]
    }

    pub fn vertices(self) -> usize {
        match self {
            CellKind::Tetrahedron => 4,
            CellKind::Hexahedron => 8,
            CellKind::Wedge => 6,
            CellKind::Pyramid => 5,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            CellKind::Tetrahedron => "tetrahedron",
            CellKind::Hexahedron => "hexahedron",
            CellKind::Wedge => "wedge",
            CellKind::Pyramid => "pyramid",
        }
    }

    /// The edges, as pairs of the cell's vertices (VTK's order).
    fn edges(self) -> &'static [(usize, usize)] {
        match self {
            CellKind::Tetrahedron => &[(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)],
            CellKind::Hexahedron => &[
                (0, 1),
                (1, 2),
                (2, 3),
                (3, 0),
                (4, 5),
                (5, 6),
                (6, 7),
                (7, 4),
                (0, 4),
                (1, 5),
                (2, 6),
                (3, 7),
            ],
            CellKind::Wedge => &[
                (0, 1),
                (1, 2),
                (2, 0),
                (3, 4),
                (4, 5),
                (5, 3),
                (0, 3),
                (1, 4),
                (2, 5),
            ],
            CellKind::Pyramid => &[
                (0, 1),
                (1, 2),
                (2, 3),
                (3, 0),
                (0, 4),
                (1, 4),
                (2, 4),
                (3, 4),
            ],
        }
    }

    /// Where Newton's method starts: the parametric centre.
    fn centre(self) -> Vec3 {
        match self {
            CellKind::Tetrahedron => Vec3::splat(0.25),
            CellKind::Hexahedron => Vec3::splat(0.5),
            CellKind::Wedge => Vec3::new(1.0 / 3.0, 1.0 / 3.0, 0.5),
            CellKind::Pyramid => Vec3::new(0.5, 0.5, 0.2),
        }
    }

    /// Whether parametric point `r` lies in the cell, within `eps`.
    pub fn holds(self, r: Vec3, eps: f32) -> bool {
        let unit = |x: f32| x >= -eps && x <= 1.0 + eps;
        match self {
            CellKind::Tetrahedron => r.min_element() >= -eps && r.x + r.y + r.z <= 1.0 + eps,
            CellKind::Hexahedron | CellKind::Pyramid => unit(r.x) && unit(r.y) && unit(r.z),
            CellKind::Wedge => r.x >= -eps && r.y >= -eps && r.x + r.y <= 1.0 + eps && unit(r.z),
        }
    }

    /// VTK's interpolation weights at parametric point `r` (unused
    /// entries 0) and their derivatives along r, s and t.
    pub fn shape(self, r: Vec3) -> ([f32; 8], [Vec3; 8]) {
        let (x, y, z) = (r.x, r.y, r.z);
        let (xm, ym, zm) = (1.0 - x, 1.0 - y, 1.0 - z);
        let mut w = [0.0; 8];
        let mut d = [Vec3::ZERO; 8];
        match self {
            CellKind::Tetrahedron => {
                w[..4].copy_from_slice(&[1.0 - x - y - z, x, y, z]);
                d[..4].copy_from_slice(&[Vec3::splat(-1.0), Vec3::X, Vec3::Y, Vec3::Z]);
            }
            CellKind::Hexahedron => {
                // Vertices 0..3 at t = 0 counter-clockwise from (0, 0),
                // 4..7 above them.
                let corners = [
                    (0.0, 0.0, 0.0),
                    (1.0, 0.0, 0.0),
                    (1.0, 1.0, 0.0),
                    (0.0, 1.0, 0.0),
                    (0.0, 0.0, 1.0),
                    (1.0, 0.0, 1.0),
                    (1.0, 1.0, 1.0),
                    (0.0, 1.0, 1.0),
                ];
                for (i, &(cx, cy, cz)) in corners.iter().enumerate() {
                    let f = |c: f32, v: f32, m: f32| if c > 0.5 { v } else { m };
                    let s = |c: f32| if c > 0.5 { 1.0 } else { -1.0 };
                    let (a, b, c) = (f(cx, x, xm), f(cy, y, ym), f(cz, z, zm));
                    w[i] = a * b * c;
                    d[i] = Vec3::new(s(cx) * b * c, a * s(cy) * c, a * b * s(cz));
                }
            }
            CellKind::Wedge => {
                let base = 1.0 - x - y;
                w[..6].copy_from_slice(&[base * zm, x * zm, y * zm, base * z, x * z, y * z]);
                d[..6].copy_from_slice(&[
                    Vec3::new(-zm, -zm, -base),
                    Vec3::new(zm, 0.0, -x),
                    Vec3::new(0.0, zm, -y),
                    Vec3::new(-z, -z, base),
                    Vec3::new(z, 0.0, x),
                    Vec3::new(0.0, z, y),
                ]);
            }
            CellKind::Pyramid => {
                w[..5].copy_from_slice(&[xm * ym * zm, x * ym * zm, x * y * zm, xm * y * zm, z]);
                d[..5].copy_from_slice(&[
                    Vec3::new(-ym * zm, -xm * zm, -xm * ym),
                    Vec3::new(ym * zm, -x * zm, -x * ym),
                    Vec3::new(y * zm, x * zm, -x * y),
                    Vec3::new(-y * zm, xm * zm, -xm * y),
                    Vec3::Z,
                ]);
            }
        }
        (w, d)
    }

    /// The parametric coordinates of `p` in the cell of vertices `v`
    /// (the first `vertices()` of them): exact for a tetrahedron, by
    /// Newton's method for the others; `None` where the map is singular.
    pub fn parametric(self, v: &[Vec3; 8], p: Vec3) -> Option<Vec3> {
        if self == CellKind::Tetrahedron {
            let m = Mat3::from_cols(v[1] - v[0], v[2] - v[0], v[3] - v[0]);
            let det = m.determinant();
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            // Cramer's rule, column by column.
            let q = p - v[0];
            let r = Mat3::from_cols(q, m.y_axis, m.z_axis).determinant() / det;
            let s = Mat3::from_cols(m.x_axis, q, m.z_axis).determinant() / det;
            let t = Mat3::from_cols(m.x_axis, m.y_axis, q).determinant() / det;
            return Some(Vec3::new(r, s, t));
        }
        let n = self.vertices();
        let mut r = self.centre();
        for _ in 0..NEWTON_STEPS {
            let (w, d) = self.shape(r);
            let mut x = Vec3::ZERO;
            let mut jac = Mat3::ZERO;
            for i in 0..n {
                x += w[i] * v[i];
                jac.x_axis += d[i].x * v[i];
                jac.y_axis += d[i].y * v[i];
                jac.z_axis += d[i].z * v[i];
            }
            let det = jac.determinant();
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            let step = jac.inverse() * (x - p);
            r -= step;
            if step.abs().max_element() < NEWTON_TOLERANCE {
                break;
            }
        }
        r.is_finite().then_some(r)
    }
}

/// Words per cell of a mesh's walk on the GPU.
pub const WALK_WORDS: usize = TetWalk::CELL_WORDS;

/// Where an unstructured volume's values live.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshValues {
    /// One per vertex position, interpolated inside each cell.
    PerVertex(Vec<f32>),
    /// One per cell (in the host's cell order), constant inside it.
    PerCell(Vec<f32>),
}

/// What a host or a file hands over, as numbers; checked by
/// [`UnstructuredVolume::new`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshInput {
    pub positions: Vec<Vec3>,
    /// Vertex numbers, cell after cell.
    pub index: Vec<u32>,
    /// Each cell's first entry in `index`; a cell ends where the next
    /// begins (the last at the end of `index`).
    pub cell_index: Vec<u32>,
    /// VTK codes.
    pub cell_type: Vec<u32>,
}

/// Why an unstructured volume cannot be made: the array, the element and
/// the reason.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum UnstructuredError {
    #[error("{array} has {count} entries; caveray takes up to {max}")]
    TooMany {
        array: &'static str,
        count: u64,
        max: u64,
    },
    #[error("an unstructured field needs at least one cell (cell.index is empty)")]
    NoCells,
    #[error("vertex.position[{index}] = ({}, {}, {}) is not finite", .position.x, .position.y, .position.z)]
    PositionNotFinite { index: usize, position: Vec3 },
    #[error("index[{index}] = {value} is past the {positions} vertex positions")]
    IndexPastPositions {
        index: usize,
        value: u64,
        positions: usize,
    },
    #[error("cell.index[{index}] = {value} is past the end of index ({len} entries)")]
    CellPastIndex {
        index: usize,
        value: u64,
        len: usize,
    },
    #[error("cell.index[{index}] = {value} does not increase on cell.index[{}] = {previous}", .index - 1)]
    CellNotIncreasing {
        index: usize,
        value: u32,
        previous: u32,
    },
    #[error("cell.type has {got} entries for {cells} cells (cell.index has {cells})")]
    TypeCount { got: usize, cells: usize },
    #[error("cell.type[{index}] = {code} is not a VTK tetrahedron (10), hexahedron (12), wedge (13) or pyramid (14)")]
    UnknownType { index: usize, code: u64 },
    #[error("cell {index} ({}) has {got} indices; a {} has {}", .kind.name(), .kind.name(), .kind.vertices())]
    WrongCount {
        index: usize,
        kind: CellKind,
        got: usize,
    },
    #[error("{array} has {got} values; {reason}")]
    DataLength {
        array: &'static str,
        got: usize,
        reason: String,
    },
    #[error("{array}[{index}] = {value} is not a finite number")]
    DataNotFinite {
        array: &'static str,
        index: usize,
        value: f32,
    },
    #[error("cannot allocate {bytes} bytes for the unstructured field's {what}")]
    OutOfMemory { bytes: u64, what: &'static str },
}

/// A node of the cells' BVH, as both renderers read it: its box, and
/// either its children (at `first` and `first + 1`; count 0) or its
/// `count` cells from `first` on.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MeshNode {
    pub lo: [f32; 3],
    pub first: u32,
    pub hi: [f32; 3],
    pub count: u32,
}

impl MeshNode {
    fn holds(&self, p: Vec3) -> bool {
        p.cmpge(Vec3::from(self.lo)).all() && p.cmple(Vec3::from(self.hi)).all()
    }
}

/// Where the samples of one thread's rays were last found in a mesh
/// (cell numbers in BVH order; any number is a valid start).
#[derive(Clone, Copy, Debug, Default)]
pub struct NearCells {
    /// The previous sample's cell.
    pub last: u32,
    /// The cell where the last walk from `last` failed, most often the
    /// previous ray's first: the next ray starts beside it.
    pub entry: u32,
}

/// One ray `origin + t direction` through a mesh (its own coordinates),
/// and the tetrahedron its last sample lay in.
#[derive(Clone, Copy, Debug)]
pub struct RayCells {
    origin: Vec3,
    direction: Vec3,
    stretch: Option<Stretch>,
    /// Samples found by following the ray, not by point location.
    followed: u32,
}

impl RayCells {
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        Self {
            origin,
            direction,
            stretch: None,
            followed: 0,
        }
    }

    /// The cell of the ray's last sample, where it was a tetrahedron.
    pub fn cell(&self) -> Option<u32> {
        self.stretch.map(|s| s.cell)
    }

    /// How many of its samples were found by following it.
    pub fn followed(&self) -> u32 {
        self.followed
    }
}

/// A checked mesh with its values, its cells in BVH order and its BVH.
#[derive(Clone, Debug)]
pub struct UnstructuredVolume {
    positions: Vec<Vec3>,
    index: Vec<u32>,
    /// Per cell in BVH order: its first entry in `index` << 2 | its
    /// kind's code.
    cells: Vec<u32>,
    /// Per vertex, or per cell in BVH order.
    values: MeshValues,
    nodes: Vec<MeshNode>,
    /// Cells of each kind, in VTK's code order (10, 12, 13, 14).
    kinds: [u64; 4],
    bounds: (Vec3, Vec3),
    /// The median over cells of each cell's shortest edge: what a
    /// structured grid's voxel spacing is to its march.
    edge: f32,
    lattice_dims: UVec3,
    lattice_spacing: Vec3,
    value_range: (f32, f32),
    /// The tetrahedra's inverse maps and neighbours (empty without any).
    walk: TetWalk,
}

impl PartialEq for UnstructuredVolume {
    fn eq(&self, other: &Self) -> bool {
        self.positions == other.positions
            && self.index == other.index
            && self.cells == other.cells
            && self.values == other.values
    }
}

/// A vector of `n` items, or an error naming `what` when this machine
/// cannot hold it.
fn reserve<T>(n: usize, what: &'static str) -> Result<Vec<T>, UnstructuredError> {
    let mut v = Vec::new();
    v.try_reserve_exact(n)
        .map_err(|_| UnstructuredError::OutOfMemory {
            bytes: (n as u64).saturating_mul(std::mem::size_of::<T>() as u64),
            what,
        })?;
    Ok(v)
}

/// Checks the counts of a mesh before anything is allocated for it.
pub fn check_counts(positions: u64, index: u64, cells: u64) -> Result<(), UnstructuredError> {
    for (array, count, max) in [
        ("vertex.position", positions, MAX_MESH_VERTICES),
        ("index", index, MAX_MESH_INDICES),
        ("cell.index", cells, MAX_MESH_CELLS),
    ] {
        if count > max {
            return Err(UnstructuredError::TooMany { array, count, max });
        }
    }
    Ok(())
}

impl UnstructuredVolume {
    pub fn new(input: MeshInput, values: MeshValues) -> Result<Self, UnstructuredError> {
        let MeshInput {
            positions,
            index,
            cell_index,
            cell_type,
        } = input;
        check_counts(
            positions.len() as u64,
            index.len() as u64,
            cell_index.len() as u64,
        )?;
        if cell_index.is_empty() {
            return Err(UnstructuredError::NoCells);
        }
        if let Some((i, &p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(UnstructuredError::PositionNotFinite {
                index: i,
                position: p,
            });
        }
        let mut used = 0u32;
        for (i, &v) in index.iter().enumerate() {
            if v as usize >= positions.len() {
                return Err(UnstructuredError::IndexPastPositions {
                    index: i,
                    value: u64::from(v),
                    positions: positions.len(),
                });
            }
            used = used.max(v + 1);
        }
        let n = cell_index.len();
        if cell_type.len() != n {
            return Err(UnstructuredError::TypeCount {
                got: cell_type.len(),
                cells: n,
            });
        }
        for c in 0..n {
            let start = cell_index[c];
            if start as usize >= index.len() {
                return Err(UnstructuredError::CellPastIndex {
                    index: c,
                    value: u64::from(start),
                    len: index.len(),
                });
            }
            if c > 0 && start <= cell_index[c - 1] {
                return Err(UnstructuredError::CellNotIncreasing {
                    index: c,
                    value: start,
                    previous: cell_index[c - 1],
                });
            }
        }
        let mut kinds_of = reserve::<CellKind>(n, "cell types")?;
        let mut counts = [0u64; 4];
        for c in 0..n {
            let code = u64::from(cell_type[c]);
            let kind = CellKind::from_vtk(code)
                .ok_or(UnstructuredError::UnknownType { index: c, code })?;
            let end = cell_index.get(c + 1).map_or(index.len(), |&e| e as usize);
            let got = end - cell_index[c] as usize;
            if got != kind.vertices() {
                return Err(UnstructuredError::WrongCount {
                    index: c,
                    kind,
                    got,
                });
            }
            counts[kind.code() as usize] += 1;
            kinds_of.push(kind);
        }
        let data_check = |array: &'static str, data: &[f32]| -> Result<(), UnstructuredError> {
            match data.iter().position(|x| !x.is_finite()) {
                Some(i) => Err(UnstructuredError::DataNotFinite {
                    array,
                    index: i,
                    value: data[i],
                }),
                None => Ok(()),
            }
        };
        match &values {
            MeshValues::PerVertex(data) => {
                if data.len() < used as usize {
                    return Err(UnstructuredError::DataLength {
                        array: "vertex.data",
                        got: data.len(),
                        reason: format!(
                            "the cells use vertices up to {}, so it needs at least {used}",
                            used - 1
                        ),
                    });
                }
                if data.len() > positions.len() {
                    return Err(UnstructuredError::DataLength {
                        array: "vertex.data",
                        got: data.len(),
                        reason: format!("there are {} vertex positions", positions.len()),
                    });
                }
                data_check("vertex.data", data)?;
            }
            MeshValues::PerCell(data) => {
                if data.len() != n {
                    return Err(UnstructuredError::DataLength {
                        array: "cell.data",
                        got: data.len(),
                        reason: format!("there are {n} cells, one value each"),
                    });
                }
                data_check("cell.data", data)?;
            }
        }
        // Each cell's box and shortest edge.
        let mut boxes = reserve::<(Vec3, Vec3)>(n, "cell boxes")?;
        let mut edges = reserve::<f32>(n, "cell edges")?;
        for (c, kind) in kinds_of.iter().enumerate() {
            let start = cell_index[c] as usize;
            let ids = &index[start..start + kind.vertices()];
            let at = |k: usize| positions[ids[k] as usize];
            let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            for k in 0..kind.vertices() {
                lo = lo.min(at(k));
                hi = hi.max(at(k));
            }
            boxes.push((lo, hi));
            let shortest = kind
                .edges()
                .iter()
                .map(|&(a, b)| at(a).distance(at(b)))
                .fold(f32::INFINITY, f32::min);
            edges.push(shortest);
        }
        let bounds = boxes
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), (a, b)| {
                (l.min(*a), h.max(*b))
            });
        let middle = n / 2;
        edges.select_nth_unstable_by(middle, f32::total_cmp);
        let extent = bounds.1 - bounds.0;
        let mut edge = edges[middle];
        if edge.is_nan() || edge <= extent.max_element() * 1e-6 {
            // Most cells flat: a thousandth of the mesh's size.
            edge = (extent.max_element() * 1e-3).max(f32::MIN_POSITIVE);
        }
        drop(edges);
        let (nodes, order) = build_bvh(&boxes)?;
        drop(boxes);
        let mut cells = reserve::<u32>(n, "cells")?;
        cells.extend(
            order
                .iter()
                .map(|&c| cell_index[c as usize] << 2 | kinds_of[c as usize].code()),
        );
        let values = match values {
            MeshValues::PerCell(v) => {
                let mut sorted = reserve::<f32>(n, "cell values")?;
                sorted.extend(order.iter().map(|&c| v[c as usize]));
                MeshValues::PerCell(sorted)
            }
            per_vertex => per_vertex,
        };
        let value_range = match &values {
            MeshValues::PerVertex(v) => {
                index
                    .iter()
                    .fold((f32::INFINITY, f32::NEG_INFINITY), |r, &i| {
                        let x = v[i as usize];
                        (r.0.min(x), r.1.max(x))
                    })
            }
            MeshValues::PerCell(v) => v.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |r, &x| {
                (r.0.min(x), r.1.max(x))
            }),
        };
        let (lattice_dims, lattice_spacing) = lattice(extent, edge);
        let mut mesh = Self {
            positions,
            index,
            cells,
            values,
            nodes,
            kinds: counts,
            bounds,
            edge,
            lattice_dims,
            lattice_spacing,
            value_range,
            walk: TetWalk::default(),
        };
        if mesh.kinds[0] > 0 {
            mesh.walk = TetWalk::new(&mesh).map_err(|_| UnstructuredError::OutOfMemory {
                bytes: (n as u64).saturating_mul(TetWalk::CELL_BYTES),
                what: "the tetrahedra's neighbours",
            })?;
        }
        Ok(mesh)
    }

    /// The mesh's box.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// Cells of each kind, tetrahedra, hexahedra, wedges, pyramids.
    pub fn cell_counts(&self) -> [(CellKind, u64); 4] {
        let k = self.kinds;
        [
            (CellKind::Tetrahedron, k[0]),
            (CellKind::Hexahedron, k[1]),
            (CellKind::Wedge, k[2]),
            (CellKind::Pyramid, k[3]),
        ]
    }

    pub fn cell_count(&self) -> usize {
        self.cells.len()
    }

    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Whether values sit at vertices (else one per cell).
    pub fn per_vertex(&self) -> bool {
        matches!(self.values, MeshValues::PerVertex(_))
    }

    /// The median shortest edge of the cells: the step is laid by it as
    /// by a structured grid's voxel spacing.
    pub fn edge(&self) -> f32 {
        self.edge
    }

    /// The lattice rays march in and bricks are laid on: `dims` vertices
    /// `spacing` apart from the mesh box's low corner, covering the box.
    pub fn lattice(&self) -> (UVec3, Vec3) {
        (self.lattice_dims, self.lattice_spacing)
    }

    /// Smallest and largest value a sample can take.
    pub fn value_range(&self) -> (f32, f32) {
        self.value_range
    }

    /// Bytes held: positions, indices, cells, values, BVH and the
    /// tetrahedra's walk.
    pub fn bytes(&self) -> u64 {
        let values = match &self.values {
            MeshValues::PerVertex(v) | MeshValues::PerCell(v) => v.len(),
        };
        let walk = if self.kinds[0] > 0 {
            TetWalk::CELL_BYTES * self.cells.len() as u64
        } else {
            0
        };
        (12 * self.positions.len()
            + 4 * (self.index.len() + self.cells.len() + values)
            + std::mem::size_of::<MeshNode>() * self.nodes.len()) as u64
            + walk
    }

    pub fn nodes(&self) -> &[MeshNode] {
        &self.nodes
    }

    /// Per cell in BVH order, its first index << 2 | its kind's code.
    pub fn cell_words(&self) -> &[u32] {
        &self.cells
    }

    pub fn index(&self) -> &[u32] {
        &self.index
    }

    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// The values: per vertex, or per cell in BVH order.
    pub fn values(&self) -> &[f32] {
        match &self.values {
            MeshValues::PerVertex(v) | MeshValues::PerCell(v) => v,
        }
    }

    /// The tetrahedra's walk as the GPU reads it
    /// ([`TetWalk::CELL_WORDS`] a cell), where the mesh has tetrahedra.
    pub fn walk_words(&self) -> Option<impl Iterator<Item = u32> + '_> {
        (self.kinds[0] > 0).then(|| self.walk.words())
    }

    /// Cell `c` (BVH order): its kind and vertex numbers.
    pub fn cell(&self, c: usize) -> (CellKind, &[u32]) {
        let word = self.cells[c];
        let kind = CellKind::from_code(word);
        let start = (word >> 2) as usize;
        (kind, &self.index[start..start + kind.vertices()])
    }

    /// The cells whose boxes reach the box `lo..hi` (the mesh's own
    /// coordinates), with the vertices they use: what a brick of a split
    /// mesh holds, so that every point of the box finds its cell.
    pub fn cells_within(&self, lo: Vec3, hi: Vec3) -> Result<Self, UnstructuredError> {
        let mut input = MeshInput::default();
        let mut per_cell = Vec::new();
        let mut per_vertex = Vec::new();
        let mut renumber = reserve::<u32>(self.positions.len(), "the kept vertices")?;
        renumber.resize(self.positions.len(), u32::MAX);
        for (c, ((a, b), _)) in self.cell_ranges().enumerate() {
            // A cell holds points a hair outside its box (CELL_TOLERANCE).
            let margin = (b - a) * CELL_TOLERANCE;
            if (a - margin).cmpgt(hi).any() || (b + margin).cmplt(lo).any() {
                continue;
            }
            let (kind, ids) = self.cell(c);
            input.cell_index.push(input.index.len() as u32);
            input.cell_type.push(u32::from(kind.vtk()));
            for &i in ids {
                if renumber[i as usize] == u32::MAX {
                    renumber[i as usize] = input.positions.len() as u32;
                    input.positions.push(self.positions[i as usize]);
                    if let MeshValues::PerVertex(v) = &self.values {
                        per_vertex.push(v[i as usize]);
                    }
                }
                input.index.push(renumber[i as usize]);
            }
            if let MeshValues::PerCell(v) = &self.values {
                per_cell.push(v[c]);
            }
        }
        let values = match self.values {
            MeshValues::PerVertex(_) => MeshValues::PerVertex(per_vertex),
            MeshValues::PerCell(_) => MeshValues::PerCell(per_cell),
        };
        Self::new(input, values)
    }

    /// Each cell's box and the range of values a sample in it can take,
    /// in BVH order.
    pub fn cell_ranges(&self) -> impl Iterator<Item = ((Vec3, Vec3), (f32, f32))> + '_ {
        (0..self.cells.len()).map(move |c| {
            let (kind, ids) = self.cell(c);
            let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
            let (mut a, mut b) = (f32::INFINITY, f32::NEG_INFINITY);
            for &i in &ids[..kind.vertices()] {
                let p = self.positions[i as usize];
                lo = lo.min(p);
                hi = hi.max(p);
                if let MeshValues::PerVertex(v) = &self.values {
                    a = a.min(v[i as usize]);
                    b = b.max(v[i as usize]);
                }
            }
            if let MeshValues::PerCell(v) = &self.values {
                (a, b) = (v[c], v[c]);
            }
            ((lo, hi), (a, b))
        })
    }

    /// The field at `p` (the mesh's own coordinates): interpolated in the
    /// first cell holding it, NaN outside every cell.
    pub fn sample(&self, p: Vec3) -> f32 {
        self.locate(p).map_or(f32::NAN, |(v, _)| v)
    }

    /// The field at `p` as [`sample`](Self::sample) gives it, looked for
    /// first in and around the cells `near` remembers, which it is left
    /// remembering for the next sample.
    pub fn sample_near(&self, p: Vec3, near: &mut NearCells) -> f32 {
        if let Some((v, c)) = self.walk.walk(p, near.last) {
            near.last = c;
            return v;
        }
        if let Some((v, c)) = self.walk.walk(p, near.entry) {
            *near = NearCells { last: c, entry: c };
            return v;
        }
        // Other cells are tried on their own, their neighbours not known.
        if self.kinds[0] < self.cells.len() as u64 {
            if let Some(v) = self.in_cell_checked(near.last as usize, p) {
                return v;
            }
        }
        match self.locate(p) {
            Some((v, c)) => {
                *near = NearCells { last: c, entry: c };
                v
            }
            None => f32::NAN,
        }
    }

    /// The field at `o + t d` (the mesh's own coordinates) as
    /// [`sample`](Self::sample) gives it, for the samples of one ray in
    /// increasing t: found by following the ray from the tetrahedron of
    /// its previous sample through the faces it leaves by, where the
    /// field is linear in t; else as [`sample_near`](Self::sample_near)
    /// finds it from `near`.
    pub fn sample_along(&self, ray: &mut RayCells, t: f32, near: &mut NearCells) -> f32 {
        let (o, d) = (ray.origin, ray.direction);
        if let Some(from) = ray.stretch {
            if let Some(s) = self.walk.follow(from, o, d, t, WALK_STEPS) {
                ray.stretch = Some(s);
                ray.followed += 1;
                return s.value(t);
            }
            // The point walk starts where the ray was last, not where the
            // last point walk ended.
            near.last = from.cell;
        }
        let v = self.sample_near(o + d * t, near);
        ray.stretch = if v.is_nan() {
            None
        } else {
            self.walk.stretch(near.last, o, d).filter(|s| s.holds(t))
        };
        if let Some(s) = ray.stretch {
            near.last = s.cell;
        }
        v
    }

    /// The field at `p` and the first cell (BVH order) holding it.
    fn locate(&self, p: Vec3) -> Option<(f32, u32)> {
        let mut stack = [0u32; MESH_STACK];
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            let node = &self.nodes[stack[depth] as usize];
            if !node.holds(p) {
                continue;
            }
            if node.count == 0 {
                stack[depth] = node.first;
                stack[depth + 1] = node.first + 1;
                depth += 2;
                continue;
            }
            for c in node.first..node.first + node.count {
                if let Some(v) = self.in_cell(c as usize, p) {
                    return Some((v, c));
                }
            }
        }
        None
    }

    /// [`in_cell`](Self::in_cell) for any number `c`, `None` past the
    /// cells.
    fn in_cell_checked(&self, c: usize, p: Vec3) -> Option<f32> {
        (c < self.cells.len()).then(|| self.in_cell(c, p)).flatten()
    }

    /// The field at `p` if cell `c` (BVH order) holds it.
    pub fn in_cell(&self, c: usize, p: Vec3) -> Option<f32> {
        let (kind, ids) = self.cell(c);
        let mut v = [Vec3::ZERO; 8];
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for (k, &i) in ids.iter().enumerate() {
            v[k] = self.positions[i as usize];
            lo = lo.min(v[k]);
            hi = hi.max(v[k]);
        }
        // The box with a margin as wide as the parametric tolerance.
        let margin = (hi - lo) * CELL_TOLERANCE;
        if p.cmplt(lo - margin).any() || p.cmpgt(hi + margin).any() {
            return None;
        }
        let r = kind.parametric(&v, p)?;
        if !kind.holds(r, CELL_TOLERANCE) {
            return None;
        }
        match &self.values {
            MeshValues::PerCell(values) => Some(values[c]),
            MeshValues::PerVertex(values) => {
                let (w, _) = kind.shape(r);
                Some(
                    ids.iter()
                        .zip(w)
                        .map(|(&i, w)| w * values[i as usize])
                        .sum(),
                )
            }
        }
    }
}

impl TetCells for UnstructuredVolume {
    fn len(&self) -> usize {
        self.cells.len()
    }

    fn tetrahedra(&self) -> usize {
        self.kinds[0] as usize
    }

    fn tetrahedron(&self, c: usize) -> Option<[u32; 4]> {
        match self.cell(c) {
            (CellKind::Tetrahedron, ids) => Some([ids[0], ids[1], ids[2], ids[3]]),
            _ => None,
        }
    }

    fn position(&self, vertex: u32) -> Vec3 {
        self.positions[vertex as usize]
    }

    fn values(&self, c: usize, ids: [u32; 4]) -> [f32; 4] {
        match &self.values {
            MeshValues::PerVertex(v) => ids.map(|i| v[i as usize]),
            MeshValues::PerCell(v) => [v[c]; 4],
        }
    }
}

/// Lattice vertices per axis and their spacing over a box of `extent`
/// for cells whose typical edge is `edge`: that edge apart (a little
/// closer, so that the lattice ends on the box), at most MAX_LATTICE.
fn lattice(extent: Vec3, edge: f32) -> (UVec3, Vec3) {
    let mut dims = UVec3::ONE;
    let mut spacing = Vec3::ONE;
    for k in 0..3 {
        if extent[k] <= 0.0 {
            dims[k] = 2;
            spacing[k] = edge;
            continue;
        }
        // A hair under the quotient, so a mesh tiling a grid of that
        // edge gets exactly the grid.
        let cells = (extent[k] / edge * (1.0 - 1e-5))
            .ceil()
            .clamp(1.0, (MAX_LATTICE - 1) as f32);
        dims[k] = cells as u32 + 1;
        spacing[k] = extent[k] / cells;
    }
    (dims, spacing)
}

/// The BVH of cells with boxes `boxes` by median splits along the
/// longest axis of their centres, and the cells in its leaves' order.
fn build_bvh(boxes: &[(Vec3, Vec3)]) -> Result<(Vec<MeshNode>, Vec<u32>), UnstructuredError> {
    let n = boxes.len();
    let mut order = reserve::<u32>(n, "the cell order")?;
    order.extend(0..n as u32);
    let mut centres = reserve::<Vec3>(n, "the cells' centres")?;
    centres.extend(boxes.iter().map(|(lo, hi)| 0.5 * (*lo + *hi)));
    let nodes = subtree(&mut order, 0, boxes, &centres)?;
    Ok((nodes, order))
}

/// Subtrees of more cells than this are split on one thread and built on
/// two.
const PARALLEL_CELLS: usize = 1 << 16;

/// A node's box, and the axis its cells' centres spread most along.
fn split_axis(order: &[u32], boxes: &[(Vec3, Vec3)], centres: &[Vec3]) -> (MeshNode, usize) {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    let (mut clo, mut chi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for &c in order {
        let (a, b) = boxes[c as usize];
        lo = lo.min(a);
        hi = hi.max(b);
        clo = clo.min(centres[c as usize]);
        chi = chi.max(centres[c as usize]);
    }
    let spread = chi - clo;
    let axis = if spread.x >= spread.y && spread.x >= spread.z {
        0
    } else if spread.y >= spread.z {
        1
    } else {
        2
    };
    let node = MeshNode {
        lo: lo.to_array(),
        first: 0,
        hi: hi.to_array(),
        count: 0,
    };
    (node, axis)
}

/// The BVH over the cells `order` (which it reorders), the first of
/// them at `base` in the whole order; its root first, every node's two
/// children side by side.
fn subtree(
    order: &mut [u32],
    base: usize,
    boxes: &[(Vec3, Vec3)],
    centres: &[Vec3],
) -> Result<Vec<MeshNode>, UnstructuredError> {
    let n = order.len();
    if n <= PARALLEL_CELLS {
        return serial_subtree(order, base, boxes, centres);
    }
    let (mut root, axis) = split_axis(order, boxes, centres);
    let mid = n / 2;
    order.select_nth_unstable_by(mid, |&a, &b| {
        centres[a as usize][axis].total_cmp(&centres[b as usize][axis])
    });
    let (left, right) = order.split_at_mut(mid);
    let (left, right) = rayon::join(
        || subtree(left, base, boxes, centres),
        || subtree(right, base + mid, boxes, centres),
    );
    let (left, right) = (left?, right?);
    // [root, left's root, right's root, left's others, right's others]
    let mut nodes = reserve::<MeshNode>(1 + left.len() + right.len(), "the cells' BVH")?;
    let others = 3 + left.len() - 1;
    let place = |i: u32, root_at: u32, from: usize| {
        if i == 0 {
            root_at
        } else {
            (from + i as usize - 1) as u32
        }
    };
    root.first = 1;
    nodes.push(root);
    for (part, root_at, from) in [(&left, 1, 3), (&right, 2, others)] {
        let mut top = part[0];
        if top.count == 0 {
            top.first = place(top.first, root_at, from);
        }
        nodes.push(top);
    }
    for (part, root_at, from) in [(&left, 1, 3), (&right, 2, others)] {
        nodes.extend(part[1..].iter().map(|&node| {
            let mut node = node;
            if node.count == 0 {
                node.first = place(node.first, root_at, from);
            }
            node
        }));
    }
    Ok(nodes)
}

/// [`subtree`] on one thread.
fn serial_subtree(
    order: &mut [u32],
    base: usize,
    boxes: &[(Vec3, Vec3)],
    centres: &[Vec3],
) -> Result<Vec<MeshNode>, UnstructuredError> {
    let n = order.len();
    let mut nodes = reserve::<MeshNode>((2 * n / LEAF_CELLS).max(1) + 1, "the cells' BVH")?;
    nodes.push(MeshNode {
        lo: [0.0; 3],
        first: 0,
        hi: [0.0; 3],
        count: 0,
    });
    // (node, first cell, end)
    let mut work = vec![(0usize, 0usize, n)];
    while let Some((node, start, end)) = work.pop() {
        let (mut box_node, axis) = split_axis(&order[start..end], boxes, centres);
        let count = end - start;
        if count <= LEAF_CELLS {
            box_node.first = (base + start) as u32;
            box_node.count = count as u32;
            nodes[node] = box_node;
            continue;
        }
        let mid = start + count / 2;
        order[start..end].select_nth_unstable_by(count / 2, |&a, &b| {
            centres[a as usize][axis].total_cmp(&centres[b as usize][axis])
        });
        let child = nodes.len();
        let blank = nodes[node];
        nodes.push(blank);
        nodes.push(blank);
        box_node.first = child as u32;
        nodes[node] = box_node;
        work.push((child, start, mid));
        work.push((child + 1, mid, end));
    }
    Ok(nodes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small generator of numbers in [0, 1), fixed seed.
    struct Numbers(u64);
    impl Numbers {
        fn next(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 40) as f32) / (1u64 << 24) as f32
        }
        fn point(&mut self) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next())
        }
    }

    fn one_cell(kind: CellKind, v: &[Vec3], values: MeshValues) -> UnstructuredVolume {
        UnstructuredVolume::new(
            MeshInput {
                positions: v.to_vec(),
                index: (0..v.len() as u32).collect(),
                cell_index: vec![0],
                cell_type: vec![u32::from(kind.vtk())],
            },
            values,
        )
        .unwrap_or_else(|e| panic!("{e}"))
    }

    fn jiggled(corners: &[Vec3], rng: &mut Numbers) -> Vec<Vec3> {
        corners
            .iter()
            .map(|&c| c * 2.0 + (rng.point() - 0.5) * 0.3 + Vec3::new(1.0, -2.0, 0.5))
            .collect()
    }

    #[test]
    fn a_linear_field_on_a_tetrahedron_is_reproduced_everywhere_inside() {
        let f = |p: Vec3| 0.3 + 1.5 * p.x - 0.7 * p.y + 0.25 * p.z;
        let mut rng = Numbers(7);
        let v = jiggled(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z], &mut rng);
        let mesh = one_cell(
            CellKind::Tetrahedron,
            &v,
            MeshValues::PerVertex(v.iter().map(|&p| f(p)).collect()),
        );
        for _ in 0..1000 {
            // Random barycentric weights.
            let (a, b, c) = (rng.next(), rng.next(), rng.next());
            let (a, b, c) = if a + b + c > 1.0 {
                (a / 3.0, b / 3.0, c / 3.0)
            } else {
                (a, b, c)
            };
            let p = v[0] * (1.0 - a - b - c) + v[1] * a + v[2] * b + v[3] * c;
            let got = mesh.sample(p);
            assert!((got - f(p)).abs() < 1e-5, "{p}: {got} vs {}", f(p));
        }
        assert!(mesh.sample(v[0] - Vec3::splat(0.5)).is_nan());
    }

    /// Each kind's corners in its parametric space (VTK's order).
    fn corners(kind: CellKind) -> Vec<Vec3> {
        let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        match kind {
            CellKind::Tetrahedron => {
                vec![c(0., 0., 0.), c(1., 0., 0.), c(0., 1., 0.), c(0., 0., 1.)]
            }
            CellKind::Hexahedron => vec![
                c(0., 0., 0.),
                c(1., 0., 0.),
                c(1., 1., 0.),
                c(0., 1., 0.),
                c(0., 0., 1.),
                c(1., 0., 1.),
                c(1., 1., 1.),
                c(0., 1., 1.),
            ],
            CellKind::Wedge => vec![
                c(0., 0., 0.),
                c(1., 0., 0.),
                c(0., 1., 0.),
                c(0., 0., 1.),
                c(1., 0., 1.),
                c(0., 1., 1.),
            ],
            CellKind::Pyramid => vec![
                c(0., 0., 0.),
                c(1., 0., 0.),
                c(1., 1., 0.),
                c(0., 1., 0.),
                c(0.5, 0.5, 1.),
            ],
        }
    }

    #[test]
    fn shape_functions_interpolate_the_corners_and_sum_to_one() {
        for kind in CellKind::ALL {
            let n = kind.vertices();
            let param = match kind {
                CellKind::Pyramid => {
                    let mut c = corners(kind);
                    c[4] = Vec3::new(0.3, 0.8, 1.0); // any r, s at the apex
                    c
                }
                _ => corners(kind),
            };
            for (i, r) in param.iter().enumerate() {
                let (w, _) = kind.shape(*r);
                for (j, &wj) in w.iter().enumerate().take(n) {
                    let expect = if i == j { 1.0 } else { 0.0 };
                    assert!(
                        (wj - expect).abs() < 1e-6,
                        "{kind:?} corner {i} weight {j}: {wj}"
                    );
                }
            }
            let mut rng = Numbers(3);
            for _ in 0..50 {
                let r = rng.point();
                let (w, d) = kind.shape(r);
                assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
                let ds: Vec3 = d.iter().copied().sum();
                assert!(ds.length() < 1e-6, "{kind:?}: derivatives sum to {ds}");
                // Derivatives against finite differences.
                for axis in 0..3 {
                    let h = 1e-3;
                    let mut up = r;
                    up[axis] += h;
                    let mut down = r;
                    down[axis] -= h;
                    let (wu, _) = kind.shape(up);
                    let (wd, _) = kind.shape(down);
                    for i in 0..n {
                        let fd = (wu[i] - wd[i]) / (2.0 * h);
                        assert!((fd - d[i][axis]).abs() < 1e-3, "{kind:?} d{axis} w{i}");
                    }
                }
            }
        }
    }

    #[test]
    fn every_kind_reproduces_its_shape_functions_at_random_points() {
        let mut rng = Numbers(11);
        for kind in CellKind::ALL {
            let v = jiggled(&corners(kind), &mut rng);
            let values: Vec<f32> = (0..v.len())
                .map(|i| 1.0 + i as f32 * 0.5 + rng.next())
                .collect();
            let mesh = one_cell(kind, &v, MeshValues::PerVertex(values.clone()));
            let mut tried = 0;
            while tried < 300 {
                let r = rng.point();
                if !kind.holds(r, 0.0) {
                    continue;
                }
                tried += 1;
                let (w, _) = kind.shape(r);
                let p: Vec3 = (0..v.len()).map(|i| w[i] * v[i]).sum();
                let expect: f32 = (0..v.len()).map(|i| w[i] * values[i]).sum();
                let got = mesh.sample(p);
                assert!(
                    (got - expect).abs() < 1e-5,
                    "{kind:?} at {r}: {got} vs {expect}"
                );
            }
            // Cell data: constant.
            let mesh = one_cell(kind, &v, MeshValues::PerCell(vec![4.5]));
            let centre: Vec3 = v.iter().copied().sum::<Vec3>() / v.len() as f32;
            assert_eq!(mesh.sample(centre), 4.5);
            assert!(mesh.sample(centre + Vec3::splat(10.0)).is_nan());
        }
    }

    #[test]
    fn bad_meshes_are_refused_with_the_array_the_element_and_the_reason() {
        let tet = || MeshInput {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE],
            index: vec![0, 1, 2, 3],
            cell_index: vec![0],
            cell_type: vec![10],
        };
        let data = || MeshValues::PerVertex(vec![0.0; 4]);
        let err = |input: MeshInput, values: MeshValues| {
            UnstructuredVolume::new(input, values)
                .unwrap_err()
                .to_string()
        };
        let mut m = tet();
        m.index[2] = 9;
        assert_eq!(
            err(m, data()),
            "index[2] = 9 is past the 5 vertex positions"
        );
        let mut m = tet();
        m.cell_type[0] = 7;
        assert_eq!(
            err(m, data()),
            "cell.type[0] = 7 is not a VTK tetrahedron (10), hexahedron (12), wedge (13) or pyramid (14)"
        );
        let mut m = tet();
        m.cell_type[0] = 12;
        assert_eq!(
            err(m, data()),
            "cell 0 (hexahedron) has 4 indices; a hexahedron has 8"
        );
        let mut m = tet();
        m.cell_index = vec![0, 0];
        m.cell_type = vec![10, 10];
        assert_eq!(
            err(m, data()),
            "cell.index[1] = 0 does not increase on cell.index[0] = 0"
        );
        let mut m = tet();
        m.cell_index = vec![4];
        assert_eq!(
            err(m, data()),
            "cell.index[0] = 4 is past the end of index (4 entries)"
        );
        let mut m = tet();
        m.positions[1].y = f32::NAN;
        assert_eq!(
            err(m, data()),
            "vertex.position[1] = (1, NaN, 0) is not finite"
        );
        assert_eq!(
            err(tet(), MeshValues::PerVertex(vec![0.0; 3])),
            "vertex.data has 3 values; the cells use vertices up to 3, so it needs at least 4"
        );
        assert_eq!(
            err(tet(), MeshValues::PerVertex(vec![0.0; 6])),
            "vertex.data has 6 values; there are 5 vertex positions"
        );
        assert_eq!(
            err(tet(), MeshValues::PerCell(vec![0.0; 2])),
            "cell.data has 2 values; there are 1 cells, one value each"
        );
        assert_eq!(
            err(tet(), MeshValues::PerCell(vec![f32::INFINITY])),
            "cell.data[0] = inf is not a finite number"
        );
        let mut m = tet();
        m.cell_type.push(10);
        assert_eq!(
            err(m, data()),
            "cell.type has 2 entries for 1 cells (cell.index has 1)"
        );
        assert_eq!(
            check_counts(1 << 29, 0, 0).unwrap_err().to_string(),
            "vertex.position has 536870912 entries; caveray takes up to 268435456"
        );
        // Padding past the used positions is fine (OpenCOVER sends it).
        assert!(UnstructuredVolume::new(tet(), MeshValues::PerVertex(vec![0.0; 5])).is_ok());
    }

    #[test]
    fn the_bvh_stays_within_the_traversal_stack_and_holds_every_cell_once() {
        // The boxes of a 30^3 grid's cells, six tetrahedra's worth each:
        // enough for the top levels to be built on two threads.
        let mut boxes = Vec::new();
        for i in 0..30 * 30 * 30 {
            let lo = Vec3::new((i % 30) as f32, (i / 30 % 30) as f32, (i / 900) as f32);
            boxes.extend(std::iter::repeat_n((lo, lo + Vec3::ONE), 6));
        }
        assert!(boxes.len() > 2 * PARALLEL_CELLS);
        let (nodes, order) = build_bvh(&boxes).unwrap();
        let mut seen = order.clone();
        seen.sort_unstable();
        assert!(
            seen.iter().copied().eq(0..boxes.len() as u32),
            "every cell once"
        );
        let holds = |n: &MeshNode, (lo, hi): (Vec3, Vec3)| {
            Vec3::from(n.lo).cmple(lo).all() && Vec3::from(n.hi).cmpge(hi).all()
        };
        // Depth, and the boxes of children and cells within their node's;
        // every node reached once.
        fn walk(
            nodes: &[MeshNode],
            i: usize,
            reached: &mut Vec<bool>,
            check: &dyn Fn(&MeshNode, usize) -> bool,
        ) -> usize {
            assert!(!reached[i], "node {i} reached twice");
            reached[i] = true;
            let n = nodes[i];
            if n.count > 0 {
                assert!(check(&n, i), "leaf {i} does not hold its cells");
                return 1;
            }
            let (a, b) = (n.first as usize, n.first as usize + 1);
            for c in [a, b] {
                let child = (Vec3::from(nodes[c].lo), Vec3::from(nodes[c].hi));
                assert!(
                    Vec3::from(n.lo).cmple(child.0).all() && Vec3::from(n.hi).cmpge(child.1).all(),
                    "node {i} does not hold child {c}"
                );
            }
            1 + walk(nodes, a, reached, check).max(walk(nodes, b, reached, check))
        }
        let check = |n: &MeshNode, _: usize| {
            (n.first..n.first + n.count).all(|k| holds(n, boxes[order[k as usize] as usize]))
        };
        let mut reached = vec![false; nodes.len()];
        let d = walk(&nodes, 0, &mut reached, &check);
        assert!(reached.iter().all(|&r| r), "every node reached");
        // Median splits: at most log2(cells / leaf) + 2 levels.
        let bound = ((boxes.len() as f32 / LEAF_CELLS as f32).log2().ceil() as usize) + 2;
        assert!(d <= bound, "depth {d} > {bound}");
        // The stack holds a path's pending siblings: one per level.
        assert!(((MAX_MESH_CELLS as f32).log2() as usize) + 2 <= MESH_STACK);
    }
}
