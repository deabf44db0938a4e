//! The scene of the C mesh benchmark (examples/c/mesh_bench.c), built in
//! Rust so that `bench surfaces` times caveray's own renderers on the
//! scene it is compared with other ANARI devices on: a closed bumpy UV
//! sphere of 1 001 112 triangles coloured by its normal, 1 024 small
//! spheres on a shell around it, seen from (0, 0, 3.5) with a 60 degree
//! field of view.

use std::f64::consts::{PI, TAU};
use std::sync::Arc;

use anari_library_caveray::geometry::{ImageRegion, PinholeCamera, PrimaryRays, RayGen};
use anari_library_caveray::scene::{
    Attribute, ColorSource, Kept, PlacedShape, Shape, ShapeInput, SurfaceMaterial,
};
use glam::{DVec3, Mat4, UVec2, Vec3, Vec4};

use crate::Failure;

/// Quads around the sphere in each direction (mesh_bench.c's N_THETA and
/// N_PHI).
const QUADS: u32 = 708;
/// Small spheres per side of their grid on the shell.
const SPHERES: u32 = 32;
const SPHERE_RADIUS: f32 = 0.04;
const SHELL: f64 = 1.35;
/// The camera's distance from the centre and its vertical field of view.
pub const DISTANCE: f64 = 3.5;
const FOVY_DEG: f64 = 60.0;

/// The bumpy sphere's point and outward unit normal at polar angle `th`
/// and azimuth `ph`: radius 1 + 0.1 sin(8 th) sin(8 ph).
fn bumpy(th: f64, ph: f64) -> (DVec3, DVec3) {
    let (st, ct, sp, cp) = (th.sin(), th.cos(), ph.sin(), ph.cos());
    let r = 1.0 + 0.1 * (8.0 * th).sin() * (8.0 * ph).sin();
    let r_t = 0.8 * (8.0 * th).cos() * (8.0 * ph).sin();
    let r_p = 0.8 * (8.0 * th).sin() * (8.0 * ph).cos();
    let s = DVec3::new(st * cp, ct, st * sp);
    let s_t = DVec3::new(ct * cp, -st, ct * sp);
    let s_p = DVec3::new(-st * sp, 0.0, st * cp);
    let n = (r_t * s + r * s_t).cross(r_p * s + r * s_p);
    let n = if st < 1e-9 || n.length() < 1e-12 {
        s
    } else {
        n.normalize()
    };
    (r * s, if n.dot(s) < 0.0 { -n } else { n })
}

/// The mesh and the spheres, placed where the benchmark's camera sees
/// them.
pub fn shapes() -> Result<Vec<PlacedShape>, Failure> {
    let row = QUADS + 1;
    let mut positions = Vec::with_capacity((row * row) as usize);
    let mut colors = Vec::with_capacity((row * row) as usize);
    for i in 0..=QUADS {
        let th = PI * f64::from(i) / f64::from(QUADS);
        for j in 0..=QUADS {
            // The seam and the poles repeat one vertex bit for bit, so the
            // mesh is closed.
            let j = if j == QUADS || i == 0 || i == QUADS {
                0
            } else {
                j
            };
            let (p, n) = bumpy(th, TAU * f64::from(j) / f64::from(QUADS));
            positions.push(p.as_vec3());
            colors.push((Vec3::splat(0.5) + 0.45 * n.as_vec3()).extend(1.0));
        }
    }
    let mut triangles = Vec::with_capacity((2 * QUADS * QUADS) as usize);
    for i in 0..QUADS {
        for j in 0..QUADS {
            let v00 = i * row + j;
            let (v01, v10) = (v00 + 1, v00 + row);
            let v11 = v10 + 1;
            // Counter-clockwise from outside; at a pole one of each quad's
            // two triangles has no area and is left out.
            if i != 0 {
                triangles.push([v00, v01, v11]);
            }
            if i != QUADS - 1 {
                triangles.push([v00, v11, v10]);
            }
        }
    }
    let mesh_input = ShapeInput {
        vertices: positions.len(),
        primitives: triangles.len(),
        attributes: [Some(Attribute::per_vertex(colors)), None, None, None, None],
        ids: None,
    };
    let n = triangles.len();
    let mesh = Shape::triangles(positions, triangles, Kept::All(n), None, mesh_input)
        .map_err(|e| Failure::Runtime(format!("the bumpy sphere: {e}")))?;

    let centres: Vec<Vec3> = (0..SPHERES * SPHERES)
        .map(|k| {
            let (i, j) = (k / SPHERES, k % SPHERES);
            let th = PI * (f64::from(i) + 0.5) / f64::from(SPHERES);
            let ph = TAU * f64::from(j) / f64::from(SPHERES);
            (SHELL * DVec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin())).as_vec3()
        })
        .collect();
    let count = centres.len();
    let spheres = Shape::spheres(
        centres,
        vec![SPHERE_RADIUS; count],
        (0..count as u32).collect(),
        ShapeInput {
            vertices: count,
            primitives: count,
            attributes: [None, None, None, None, None],
            ids: None,
        },
    )
    .map_err(|e| Failure::Runtime(format!("the spheres: {e}")))?;

    let coloured = SurfaceMaterial {
        color: ColorSource::Attribute(0),
        ..SurfaceMaterial::default()
    };
    let plain = SurfaceMaterial {
        color: ColorSource::Constant(Vec3::new(0.8, 0.7, 0.6)),
        ..SurfaceMaterial::default()
    };
    Ok(vec![
        PlacedShape::new(Arc::new(mesh.shape), coloured, Mat4::IDENTITY),
        PlacedShape::new(Arc::new(spheres.shape), plain, Mat4::IDENTITY),
    ])
}

/// The benchmark's background, a dark grey.
pub const BACKGROUND: Vec4 = Vec4::new(0.1, 0.1, 0.1, 1.0);

/// View `i` of `n`: the benchmark's camera turned by i/n of a turn about
/// the y axis, at the same distance, looking at the centre.
pub fn camera(i: u32, n: u32, image: UVec2) -> Result<RayGen, Failure> {
    let angle = TAU * f64::from(i) / f64::from(n);
    let position = DISTANCE * DVec3::new(angle.sin(), 0.0, angle.cos());
    PinholeCamera::new(
        position,
        -position,
        DVec3::Y,
        FOVY_DEG.to_radians(),
        f64::from(image.x) / f64::from(image.y),
        ImageRegion::FULL,
    )
    .map(|c| c.ray_gen(image))
    .map_err(|e| Failure::Runtime(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The C benchmark's counts: every quad two triangles but one at
    /// each pole, no triangle dropped, and the spheres' grid.
    #[test]
    fn the_scene_has_the_c_benchmarks_counts() {
        let Ok(shapes) = shapes() else {
            panic!("the bumpy scene could not be made")
        };
        assert_eq!(shapes[0].shape.len(), 1_001_112);
        assert_eq!(shapes[0].shape.vertices(), 709 * 709);
        assert_eq!(shapes[1].shape.len(), 1024);
        let (lo, hi) = shapes[0].shape.bounds();
        assert!(lo.cmpge(Vec3::splat(-1.1)).all() && hi.cmple(Vec3::splat(1.1)).all());
        assert!((hi - lo).min_element() > 1.9);
    }
}
