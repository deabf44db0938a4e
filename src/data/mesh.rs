//! A volume's isosurface as a triangle mesh, as a host that extracts one
//! (VTK's contour filter, a segmentation exported as a mesh) would send
//! it beside the volume: marching tetrahedra over the grid's cells (each
//! cell split into six tetrahedra around its main diagonal, so no case
//! table is needed and the surface has no holes), vertices shared between
//! the triangles that meet at them, normals from the field's gradient.

use std::collections::HashMap;

use glam::{UVec3, Vec3};
use thiserror::Error;

use crate::scene::StructuredVolume;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    #[error("the isosurface has more than {max} triangles; extract it with a larger stride")]
    TooMany { max: usize },
    #[error("stride {0} must be at least 1")]
    Stride(u32),
    #[error("isovalue {0} is not finite")]
    Value(f32),
}

/// An indexed triangle mesh in the volume's object space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Per vertex, unit length (towards lower values).
    pub normals: Vec<Vec3>,
}

/// The six tetrahedra of a cell around its diagonal from corner 0 to 7
/// (corner bits: 1 x, 2 y, 4 z).
const TETRAHEDRA: [[usize; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 3, 2, 7],
    [0, 2, 6, 7],
    [0, 6, 4, 7],
    [0, 4, 5, 7],
    [0, 5, 1, 7],
];

struct Grid<'a> {
    volume: &'a StructuredVolume,
    dims: UVec3,
}

impl Grid<'_> {
    fn value(&self, p: UVec3) -> f32 {
        self.volume.value(self.index(p) as usize)
    }

    fn index(&self, p: UVec3) -> u64 {
        let d = self.dims.as_u64vec3();
        let p = p.as_u64vec3();
        p.x + d.x * (p.y + d.y * p.z)
    }

    fn position(&self, p: Vec3) -> Vec3 {
        self.volume.origin() + p * self.volume.spacing()
    }

    /// The field's gradient at grid point `p`, central differences
    /// (one-sided at the edges), per world unit.
    fn gradient(&self, p: UVec3) -> Vec3 {
        let mut g = Vec3::ZERO;
        for k in 0..3 {
            let mut lo = p;
            let mut hi = p;
            lo[k] = lo[k].saturating_sub(1);
            hi[k] = (hi[k] + 1).min(self.dims[k] - 1);
            let run = (hi[k] - lo[k]) as f32 * self.volume.spacing()[k];
            if run > 0.0 {
                g[k] = (self.value(hi) - self.value(lo)) / run;
            }
        }
        g
    }
}

/// The isosurface of `volume` at `value` (as the voxels read, fixed
/// point in [0, 1]) over cells `stride` voxels wide, or an error past
/// `max_triangles`.
pub fn isosurface_mesh(
    volume: &StructuredVolume,
    value: f32,
    stride: u32,
    max_triangles: usize,
) -> Result<Mesh, MeshError> {
    if stride == 0 {
        return Err(MeshError::Stride(stride));
    }
    if !value.is_finite() {
        return Err(MeshError::Value(value));
    }
    let grid = Grid {
        volume,
        dims: volume.dims(),
    };
    let cells = (grid.dims - UVec3::ONE) / stride;
    let mut mesh = Mesh::default();
    // The vertex on each lattice edge, by its two ends.
    let mut shared: HashMap<(u64, u64), u32> = HashMap::new();
    let mut vertex = |mesh: &mut Mesh, a: UVec3, b: UVec3| -> u32 {
        let (ia, ib) = (grid.index(a), grid.index(b));
        let key = (ia.min(ib), ia.max(ib));
        *shared.entry(key).or_insert_with(|| {
            let (va, vb) = (grid.value(a), grid.value(b));
            let t = ((value - va) / (vb - va)).clamp(0.0, 1.0);
            let p = a.as_vec3().lerp(b.as_vec3(), t);
            let g = grid.gradient(a).lerp(grid.gradient(b), t);
            mesh.positions.push(grid.position(p));
            mesh.normals.push((-g).normalize_or(Vec3::Z));
            (mesh.positions.len() - 1) as u32
        })
    };
    for z in 0..cells.z {
        for y in 0..cells.y {
            for x in 0..cells.x {
                let base = UVec3::new(x, y, z) * stride;
                let corner = |c: usize| {
                    base + UVec3::new(c as u32 & 1, (c as u32 >> 1) & 1, (c as u32 >> 2) & 1)
                        * stride
                };
                let points: [UVec3; 8] = std::array::from_fn(corner);
                let values: [f32; 8] = points.map(|p| grid.value(p));
                if values.iter().all(|&v| v >= value) || values.iter().all(|&v| v < value) {
                    continue;
                }
                for tet in TETRAHEDRA {
                    // The corners on each side of the value, without
                    // allocating: this runs for every crossed cell.
                    let (mut inside, mut outside) = ([0usize; 4], [0usize; 4]);
                    let (mut ni, mut no) = (0, 0);
                    for c in tet {
                        if values[c] >= value {
                            inside[ni] = c;
                            ni += 1;
                        } else {
                            outside[no] = c;
                            no += 1;
                        }
                    }
                    let mut edge =
                        |mesh: &mut Mesh, a: usize, b: usize| vertex(mesh, points[a], points[b]);
                    match (&inside[..ni], &outside[..no]) {
                        ([a], [b, c, d]) | ([b, c, d], [a]) => {
                            let t = [
                                edge(&mut mesh, *a, *b),
                                edge(&mut mesh, *a, *c),
                                edge(&mut mesh, *a, *d),
                            ];
                            mesh.triangles.push(t);
                        }
                        ([a, b], [c, d]) => {
                            let ac = edge(&mut mesh, *a, *c);
                            let ad = edge(&mut mesh, *a, *d);
                            let bc = edge(&mut mesh, *b, *c);
                            let bd = edge(&mut mesh, *b, *d);
                            mesh.triangles.push([ac, ad, bd]);
                            mesh.triangles.push([ac, bd, bc]);
                        }
                        _ => {}
                    }
                }
                if mesh.triangles.len() > max_triangles {
                    return Err(MeshError::TooMany { max: max_triangles });
                }
            }
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Voxels;

    /// 1 - |p| on [-1, 1]^3 at n^3.
    fn ball(n: u32) -> StructuredVolume {
        let mut v = Vec::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let p = UVec3::new(x, y, z).as_vec3() / (n - 1) as f32 * 2.0 - 1.0;
                    v.push(1.0 - p.length());
                }
            }
        }
        StructuredVolume::new(
            UVec3::splat(n),
            Voxels::F32(v.into()),
            Vec3::splat(-1.0),
            Vec3::splat(2.0 / (n - 1) as f32),
        )
        .unwrap()
    }

    #[test]
    fn a_ball_s_isosurface_is_a_closed_sphere_of_the_right_radius() {
        let mesh = isosurface_mesh(&ball(24), 0.5, 1, 1 << 20).unwrap();
        assert!(mesh.triangles.len() > 1000);
        // Every vertex near the sphere of radius 0.5: interpolating the
        // field linearly along an edge is off by a fraction of a cell.
        for p in &mesh.positions {
            assert!((p.length() - 0.5).abs() < 0.02, "{p}");
        }
        // Normals point towards lower values: outwards, for 1 - |p|.
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!(n.dot(p.normalize()) > 0.95, "{p} {n}");
        }
        // Closed: every edge is shared by exactly two triangles.
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let open = edges.values().filter(|&&c| c != 2).count();
        assert_eq!(open, 0, "{open} edges not shared by two triangles");
        // A stride of 2 makes about a quarter of the triangles.
        let coarse = isosurface_mesh(&ball(24), 0.5, 2, 1 << 20).unwrap();
        let ratio = mesh.triangles.len() as f64 / coarse.triangles.len() as f64;
        assert!((3.0..5.5).contains(&ratio), "{ratio}");
    }

    #[test]
    fn limits_and_bad_input_are_errors() {
        assert_eq!(
            isosurface_mesh(&ball(24), 0.5, 1, 100),
            Err(MeshError::TooMany { max: 100 })
        );
        assert_eq!(
            isosurface_mesh(&ball(8), 0.5, 0, 100),
            Err(MeshError::Stride(0))
        );
        assert!(matches!(
            isosurface_mesh(&ball(8), f32::NAN, 1, 100),
            Err(MeshError::Value(_))
        ));
        // Nothing crosses a value above the field.
        assert!(isosurface_mesh(&ball(8), 2.0, 1, 100)
            .unwrap()
            .triangles
            .is_empty());
    }
}
