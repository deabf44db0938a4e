//! Scalar fields for the isosurface tests: a field sampled on [-1, 1]^3
//! and placed, and the two touching balls several tests look at.

use std::sync::Arc;

use anari_library_caveray::data::preset;
use anari_library_caveray::scene::{ObjectIds, PlacedVolume, StructuredVolume, Voxels};
use glam::{Mat4, UVec3, Vec3};

/// `f` sampled at `n`^3 vertices on [-1, 1]^3, placed by `transform`.
pub fn field(n: u32, transform: Mat4, f: impl Fn(Vec3) -> f32) -> PlacedVolume {
    let h = 2.0 / (n - 1) as f32;
    let mut v = Vec::with_capacity((n * n * n) as usize);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                v.push(f(Vec3::new(x as f32, y as f32, z as f32) * h - Vec3::ONE));
            }
        }
    }
    let volume = StructuredVolume::new(
        UVec3::splat(n),
        Voxels::F32(v.into()),
        Vec3::splat(-1.0),
        Vec3::splat(h),
    )
    .unwrap();
    PlacedVolume {
        volume: Arc::new(volume.into()),
        transfer_function: Arc::new(preset("grey").unwrap()),
        transform,
        ids: ObjectIds::NONE,
    }
}

/// A ball of radius 0.5 (where the field is 0.5, high inside) with a
/// smaller one stuck to it, so that neighbouring eyes see different
/// surfaces near the seam.
pub fn two_balls(n: u32, transform: Mat4) -> PlacedVolume {
    field(n, transform, |p| {
        let big = 1.0 - p.length();
        let small = 1.0 - 2.0 * (p - Vec3::new(0.45, 0.3, 0.4)).length();
        big.max(small)
    })
}

/// The display's panel as the renderer takes it: each view's rays over
/// its pixels and each subpixel's view.
pub fn panel(
    d: &anari_library_caveray::cave::MultiViewDisplay,
) -> anari_library_caveray::render::iso::Panel {
    anari_library_caveray::render::iso::Panel::new(
        d.resolution,
        Default::default(),
        d.view_rays().unwrap(),
        |x, y, c| d.view_of(x, y, c),
    )
    .unwrap()
}
