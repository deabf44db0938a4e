//! Unstructured meshes made from structured grids: each cell of a grid as
//! a hexahedron, or cut into six tetrahedra around its main diagonal
//! (Kuhn's subdivision, which neighbouring cells share faces under), with
//! the grid's values at the vertices. A hexahedral mesh samples exactly
//! as its grid does; tetrahedra linearly. The procedural `tets:N` volume
//! is the Marschner-Lobb signal on an N^3 lattice cut so.

use glam::{UVec3, Vec3};

use super::procedural::marschner_lobb;
use crate::scene::{
    check_counts, MeshInput, MeshValues, StructuredVolume, UnstructuredError, UnstructuredVolume,
};

/// How a grid's cells become mesh cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cut {
    Hexahedra,
    Tetrahedra,
}

/// The six tetrahedra of a hexahedron (VTK's vertex order): the paths
/// from vertex 0 to vertex 6 along one edge of each axis.
pub const KUHN: [[usize; 4]; 6] = [
    [0, 1, 2, 6],
    [0, 1, 5, 6],
    [0, 3, 2, 6],
    [0, 3, 7, 6],
    [0, 4, 5, 6],
    [0, 4, 7, 6],
];

/// The vertices of cell (x, y, z) of a grid of `dims` vertices, x
/// fastest, in VTK's hexahedron order: counter-clockwise at the low z,
/// then the same above.
pub fn cell_corners(dims: UVec3, x: u32, y: u32, z: u32) -> [u32; 8] {
    let id = |x: u32, y: u32, z: u32| x + dims.x * (y + dims.y * z);
    [
        id(x, y, z),
        id(x + 1, y, z),
        id(x + 1, y + 1, z),
        id(x, y + 1, z),
        id(x, y, z + 1),
        id(x + 1, y, z + 1),
        id(x + 1, y + 1, z + 1),
        id(x, y + 1, z + 1),
    ]
}

/// `grid`'s cells as a mesh, in the grid's place, with its values (its
/// scaling applied) at the vertices.
pub fn grid_cells(
    grid: &StructuredVolume,
    cut: Cut,
) -> Result<UnstructuredVolume, UnstructuredError> {
    let d = grid.dims();
    let cells = (d - UVec3::ONE)
        .max(UVec3::ZERO)
        .as_u64vec3()
        .element_product();
    let (per_cell, corners) = match cut {
        Cut::Hexahedra => (1, 8),
        Cut::Tetrahedra => (6, 4),
    };
    let vertices = d.as_u64vec3().element_product();
    check_counts(vertices, cells * per_cell * corners, cells * per_cell)?;
    let id = |x: u32, y: u32, z: u32| x + d.x * (y + d.y * z);
    let mut input = MeshInput {
        positions: Vec::with_capacity(vertices as usize),
        index: Vec::with_capacity((cells * per_cell * corners) as usize),
        cell_index: Vec::with_capacity((cells * per_cell) as usize),
        cell_type: Vec::with_capacity((cells * per_cell) as usize),
    };
    let mut values = Vec::with_capacity(vertices as usize);
    for z in 0..d.z {
        for y in 0..d.y {
            for x in 0..d.x {
                input
                    .positions
                    .push(grid.origin() + Vec3::new(x as f32, y as f32, z as f32) * grid.spacing());
                values.push(grid.value(id(x, y, z) as usize));
            }
        }
    }
    for z in 0..d.z.saturating_sub(1) {
        for y in 0..d.y.saturating_sub(1) {
            for x in 0..d.x.saturating_sub(1) {
                let h = cell_corners(d, x, y, z);
                match cut {
                    Cut::Hexahedra => {
                        input.cell_index.push(input.index.len() as u32);
                        input.cell_type.push(12);
                        input.index.extend(h);
                    }
                    Cut::Tetrahedra => {
                        for tet in KUHN {
                            input.cell_index.push(input.index.len() as u32);
                            input.cell_type.push(10);
                            input.index.extend(tet.map(|k| h[k]));
                        }
                    }
                }
            }
        }
    }
    UnstructuredVolume::new(input, MeshValues::PerVertex(values))
}

/// The procedural `tets:N`: the Marschner-Lobb signal at N^3 vertices on
/// [-1, 1]^3, each cell cut in six tetrahedra (6 (N - 1)^3 of them).
pub fn tetrahedra(n: u32) -> Result<UnstructuredVolume, UnstructuredError> {
    grid_cells(&marschner_lobb(n.max(2)), Cut::Tetrahedra)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::shepp_logan;
    use crate::scene::{NearCells, RayCells, Voxels};

    /// A grid of n^3 unit cells from the origin holding `f` at its vertices.
    fn unit_grid(n: u32, f: impl Fn(Vec3) -> f32) -> StructuredVolume {
        let m = n + 1;
        let values = (0..m * m * m)
            .map(|i| {
                f(Vec3::new(
                    (i % m) as f32,
                    (i / m % m) as f32,
                    (i / (m * m)) as f32,
                ))
            })
            .collect::<Vec<f32>>();
        StructuredVolume::new(
            UVec3::splat(m),
            Voxels::F32(values.into()),
            Vec3::ZERO,
            Vec3::ONE,
        )
        .unwrap()
    }

    #[test]
    fn a_trilinear_field_on_hexahedra_and_a_linear_one_on_tetrahedra_hold_in_every_cell() {
        let tri = |p: Vec3| 0.5 + p.x * p.y - 0.3 * p.y * p.z + 0.1 * p.x * p.y * p.z + p.z;
        let hexes = grid_cells(&unit_grid(5, tri), Cut::Hexahedra).unwrap();
        let lin = |p: Vec3| 0.5 + 0.2 * p.x - 0.4 * p.y + 0.3 * p.z;
        let tets = grid_cells(&unit_grid(5, lin), Cut::Tetrahedra).unwrap();
        assert_eq!(tets.cell_count(), 6 * 125);
        assert_eq!(hexes.lattice(), (UVec3::splat(6), Vec3::ONE));
        assert_eq!(hexes.edge(), 1.0);
        for k in 0..2000u32 {
            // A low-discrepancy walk through the cube.
            let t = k as f32 + 0.5;
            let p = Vec3::new(
                (t * 0.618_034).fract(),
                (t * 0.754_878).fract(),
                (t * 0.569_840).fract(),
            ) * 5.0;
            assert!((hexes.sample(p) - tri(p)).abs() < 1e-5, "hex {p}");
            assert!((tets.sample(p) - lin(p)).abs() < 1e-5, "tet {p}");
        }
        assert!(hexes.sample(Vec3::splat(5.2)).is_nan());
    }

    #[test]
    fn hexahedra_sample_as_their_grid_and_tetrahedra_hold_its_vertices() {
        let grid = shepp_logan(9);
        let hexes = grid_cells(&grid, Cut::Hexahedra).unwrap();
        let tets = grid_cells(&grid, Cut::Tetrahedra).unwrap();
        assert_eq!(hexes.cell_count(), 512);
        assert_eq!(tets.cell_count(), 6 * 512);
        assert_eq!(hexes.lattice(), (grid.dims(), grid.spacing()));
        assert_eq!(tets.lattice(), (grid.dims(), grid.spacing()));
        // Trilinear inside each hexahedron is the grid's own trilinear.
        let trilinear = |p: Vec3| {
            let g = (p - grid.origin()) / grid.spacing();
            let i = g.floor().as_uvec3().min(grid.dims() - 2);
            let f = g - i.as_vec3();
            let at = |x: u32, y: u32, z: u32| {
                let d = grid.dims();
                grid.value((x + d.x * (y + d.y * z)) as usize)
            };
            let mut sum = 0.0;
            for c in 0..8u32 {
                let (bx, by, bz) = (c & 1, (c >> 1) & 1, (c >> 2) & 1);
                let w = (if bx == 1 { f.x } else { 1.0 - f.x })
                    * (if by == 1 { f.y } else { 1.0 - f.y })
                    * (if bz == 1 { f.z } else { 1.0 - f.z });
                sum += w * at(i.x + bx, i.y + by, i.z + bz);
            }
            sum
        };
        for k in 0..500 {
            let t = k as f32 / 500.0;
            let p = Vec3::new((t * 7.3).fract(), (t * 3.1).fract(), t) * 1.98 - 0.99;
            assert!((hexes.sample(p) - trilinear(p)).abs() < 1e-5, "{p}");
        }
        // Tetrahedra agree with the grid at its vertices.
        let d = grid.dims();
        for (x, y, z) in [(0, 0, 0), (3, 5, 2), (8, 8, 8)] {
            let q = grid.origin() + UVec3::new(x, y, z).as_vec3() * grid.spacing();
            let value = grid.value((x + d.x * (y + d.y * z)) as usize);
            assert!((tets.sample(q) - value).abs() < 1e-5);
        }
        assert_eq!(tetrahedra(5).unwrap().cell_count(), 6 * 64);
    }

    #[test]
    fn walking_from_the_last_cell_finds_what_the_bvh_finds() {
        let lin = |p: Vec3| 0.5 + 0.2 * p.x - 0.4 * p.y + 0.3 * p.z;
        let tets = grid_cells(&unit_grid(6, lin), Cut::Tetrahedra).unwrap();
        let cube = shepp_logan(7);
        let cells = grid_cells(&cube, Cut::Tetrahedra).unwrap();
        let mut near = NearCells::default();
        let (mut walked, mut outside) = (0, 0);
        // Rays in several directions, a step of a sixth of a cell, some
        // starting and ending outside the mesh.
        for r in 0..40u32 {
            let t = r as f32 + 0.5;
            let start = Vec3::new((t * 0.618).fract(), (t * 0.754).fract(), -0.2) * 6.0;
            let dir = Vec3::new(0.4 * (t * 0.3).sin(), 0.4 * (t * 0.7).cos(), 1.0).normalize();
            for k in 0..40 {
                let p = start + dir * (k as f32 / 6.0);
                let (got, want) = (tets.sample_near(p, &mut near), tets.sample(p));
                if want.is_nan() {
                    assert!(got.is_nan(), "{p}: {got} outside every cell");
                    outside += 1;
                } else {
                    assert!((got - want).abs() < 1e-5, "{p}: {got} vs {want}");
                    assert!((got - lin(p)).abs() < 1e-5, "{p}: {got} vs {}", lin(p));
                    walked += 1;
                }
            }
        }
        assert!(
            walked > 800 && outside > 100,
            "{walked} inside, {outside} out"
        );
        // Any start is valid, even one past the cells.
        let mut far = NearCells {
            last: u32::MAX - 1,
            entry: 12_345_678,
        };
        let p = Vec3::new(0.1, 0.2, 0.3);
        assert!((cells.sample_near(p, &mut far) - cells.sample(p)).abs() < 1e-6);
    }

    #[test]
    fn following_a_ray_through_tetrahedra_finds_what_the_bvh_finds() {
        let lin = |p: Vec3| 0.5 + 0.2 * p.x - 0.4 * p.y + 0.3 * p.z;
        let tets = grid_cells(&unit_grid(6, lin), Cut::Tetrahedra).unwrap();
        let mut near = NearCells::default();
        let (mut with_cell, mut samples, mut outside) = (0, 0, 0);
        // Samples a sixth of a cell apart that could be found by following:
        // inside, and after the ray's first sample inside.
        let (mut followable, mut followed) = (0, 0);
        // Oblique rays; rays along an axis, along the cells' edges, faces
        // and main diagonals, where exits tie; steps of a sixth of a cell
        // and leaps of three cells; some rays starting and ending outside.
        let mut rays: Vec<(Vec3, Vec3)> = (0..30u32)
            .map(|r| {
                let t = r as f32 + 0.5;
                let start = Vec3::new((t * 0.618).fract(), (t * 0.754).fract(), -0.2) * 6.0;
                let dir = Vec3::new(0.4 * (t * 0.3).sin(), 0.4 * (t * 0.7).cos(), 1.0);
                (start, dir.normalize())
            })
            .collect();
        rays.push((Vec3::new(2.0, 3.0, -1.0), Vec3::Z));
        rays.push((Vec3::new(2.5, 3.5, -1.0), Vec3::Z));
        rays.push((Vec3::new(-1.0, 2.0, 2.0), Vec3::X));
        rays.push((Vec3::splat(-1.0), Vec3::ONE.normalize()));
        rays.push((
            Vec3::new(-1.0, -1.0, 2.5),
            Vec3::new(1.0, 1.0, 0.0).normalize(),
        ));
        for (r, &(start, dir)) in rays.iter().enumerate() {
            let mut ray = RayCells::new(start, dir);
            let mut t = 0.0;
            let mut inside_before = false;
            while t < 9.0 {
                let p = start + dir * t;
                let (got, want) = (tets.sample_along(&mut ray, t, &mut near), tets.sample(p));
                if want.is_nan() {
                    assert!(got.is_nan(), "ray {r} at {p}: {got} outside every cell");
                    outside += 1;
                } else {
                    assert!((got - want).abs() < 1e-5, "ray {r} at {p}: {got} vs {want}");
                    samples += 1;
                    with_cell += usize::from(ray.cell().is_some());
                    followable += usize::from(inside_before && r % 3 != 0);
                }
                inside_before = !want.is_nan();
                t += if r % 3 == 0 { 3.0 } else { 1.0 / 6.0 };
            }
            if r % 3 != 0 {
                followed += ray.followed() as usize;
            }
        }
        assert!(
            samples > 500 && outside > 100 && with_cell == samples,
            "{samples} inside ({with_cell} with a cell), {outside} out"
        );
        assert!(
            followed >= followable * 95 / 100,
            "{followed} of {followable} samples found by following the ray"
        );
    }

    #[test]
    fn a_box_of_a_mesh_keeps_the_cells_that_reach_it_and_their_values() {
        let lin = |p: Vec3| 0.5 + 0.2 * p.x - 0.4 * p.y + 0.3 * p.z;
        let tets = grid_cells(&unit_grid(6, lin), Cut::Tetrahedra).unwrap();
        let part = tets
            .cells_within(Vec3::ZERO, Vec3::new(2.0, 6.0, 6.0))
            .unwrap();
        // The cells of columns x = 0, 1 and the ones touching x = 2.
        assert_eq!(part.cell_count(), 6 * 3 * 36);
        assert_eq!(part.vertex_count(), 4 * 49);
        for k in 0..500u32 {
            let t = k as f32 + 0.5;
            let p = Vec3::new(
                (t * 0.618_034).fract() * 2.0,
                (t * 0.754_878).fract() * 6.0,
                (t * 0.569_840).fract() * 6.0,
            );
            assert!((part.sample(p) - lin(p)).abs() < 1e-5, "{p}");
        }
        assert!(part.sample(Vec3::new(4.0, 3.0, 3.0)).is_nan());
        assert!(tets
            .cells_within(Vec3::splat(7.0), Vec3::splat(8.0))
            .is_err());
    }
}
