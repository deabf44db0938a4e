//! Procedural test volumes on [-1, 1]^3, so every tool and test runs
//! without data files.

use glam::{UVec3, Vec3};

use crate::scene::{StructuredVolume, Voxels};

/// Ellipsoids of the 3D Shepp-Logan head phantom (Kak & Slaney), with the
/// higher-contrast intensities of Toft's modified version:
/// (intensity, semi-axes a b c, centre x y z, rotation about z in degrees).
const SHEPP_LOGAN: [(f32, [f32; 3], [f32; 3], f32); 10] = [
    (1.0, [0.69, 0.92, 0.81], [0.0, 0.0, 0.0], 0.0),
    (-0.8, [0.6624, 0.874, 0.78], [0.0, -0.0184, 0.0], 0.0),
    (-0.2, [0.11, 0.31, 0.22], [0.22, 0.0, 0.0], -18.0),
    (-0.2, [0.16, 0.41, 0.28], [-0.22, 0.0, 0.0], 18.0),
    (0.1, [0.21, 0.25, 0.41], [0.0, 0.35, -0.15], 0.0),
    (0.1, [0.046, 0.046, 0.05], [0.0, 0.1, 0.25], 0.0),
    (0.1, [0.046, 0.046, 0.05], [0.0, -0.1, 0.25], 0.0),
    (0.1, [0.046, 0.023, 0.05], [-0.08, -0.605, 0.0], 0.0),
    (0.1, [0.023, 0.023, 0.02], [0.0, -0.606, 0.0], 0.0),
    (0.1, [0.023, 0.046, 0.02], [0.06, -0.605, 0.0], 0.0),
];

/// A grid of `n`^3 samples over [-1, 1]^3 filled by `f`.
fn sampled(n: u32, f: impl Fn(Vec3) -> f32) -> StructuredVolume {
    let n = n.max(2);
    let spacing = 2.0 / (n - 1) as f32;
    let mut values = Vec::with_capacity((n * n * n) as usize);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = Vec3::new(x as f32, y as f32, z as f32) * spacing - Vec3::ONE;
                values.push(f(p));
            }
        }
    }
    StructuredVolume::new(
        UVec3::splat(n),
        Voxels::F32(values.into()),
        Vec3::splat(-1.0),
        Vec3::splat(spacing),
    )
    .expect("procedural volumes are valid by construction")
}

/// The 3D Shepp-Logan phantom: values in [0, 1], the default scene.
pub fn shepp_logan(n: u32) -> StructuredVolume {
    sampled(n, |p| {
        let sum: f32 = SHEPP_LOGAN
            .iter()
            .filter(|(_, axes, centre, degrees)| {
                let (s, c) = degrees.to_radians().sin_cos();
                let d = p - Vec3::from_array(*centre);
                let local = Vec3::new(c * d.x + s * d.y, -s * d.x + c * d.y, d.z);
                (local / Vec3::from_array(*axes)).length_squared() <= 1.0
            })
            .map(|(intensity, ..)| intensity)
            .sum();
        sum.clamp(0.0, 1.0)
    })
}

/// The Marschner-Lobb test signal (f_M = 6, alpha = 0.25), values in [0, 1].
pub fn marschner_lobb(n: u32) -> StructuredVolume {
    const F_M: f32 = 6.0;
    const ALPHA: f32 = 0.25;
    use std::f32::consts::PI;
    sampled(n, |p| {
        let r = (p.x * p.x + p.y * p.y).sqrt();
        let rho_r = (2.0 * PI * F_M * (PI * r / 2.0).cos()).cos();
        (1.0 - (PI * p.z / 2.0).sin() + ALPHA * (1.0 + rho_r)) / (2.0 * (1.0 + ALPHA))
    })
}

/// A volume filled with 1.0 everywhere: a solid box, whose
/// transmittance is known in closed form.
pub fn solid_box(n: u32) -> StructuredVolume {
    sampled(n, |_| 1.0)
}

/// Radii of the concentric shells' centre surfaces, and their half-width.
const SHELL_RADII: [f32; 4] = [0.3, 0.5, 0.7, 0.9];
const SHELL_HALF_WIDTH: f32 = 0.05;

/// Four concentric spherical shells, each a tent of values peaking at 1.0
/// on its centre surface, with air (0.0) between them and around them:
/// the empty-space benchmark, where most of every ray crosses nothing.
pub fn concentric_shells(n: u32) -> StructuredVolume {
    sampled(n, |p| {
        let r = p.length();
        SHELL_RADII
            .iter()
            .map(|&c| (1.0 - (r - c).abs() / SHELL_HALF_WIDTH).max(0.0))
            .fold(0.0, f32::max)
    })
}
