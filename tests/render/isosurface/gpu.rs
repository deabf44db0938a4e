//! Isosurface ray casting on the GPU (shaders/iso.wgsl) against its CPU
//! reference: two touching balls, placed turned and moved, seen off-axis,
//! trilinear and tricubic (the GPU's B-spline values from 8 trilinear
//! fetches), flat and curvature coloring: SSIM >= 0.99 and the same
//! depths but at a few silhouette pixels.

use crate::common;
use std::sync::atomic::AtomicBool;

use anari_library_caveray::geometry::PrimaryRays;
use anari_library_caveray::render::iso::{cast, Coloring, IsoFilter, IsoSettings};
use anari_library_caveray::render::{ssim, ColorFormat, FrameDesc};
use anari_library_caveray::scene::PlacedVolume;
use common::render::{gpu, off_axis_wall};
use glam::{Mat4, Quat, UVec2, Vec3};

fn balls() -> PlacedVolume {
    common::iso::two_balls(
        32,
        Mat4::from_scale_rotation_translation(
            Vec3::splat(1.6),
            Quat::from_rotation_y(0.6),
            Vec3::new(0.1, -0.05, 0.0),
        ),
    )
}

#[test]
fn the_gpu_casts_the_cpus_isosurface() {
    let mut g = gpu();
    let go = AtomicBool::new(false);
    let placed = balls();
    let (screen, eye) = off_axis_wall();
    let size = UVec2::new(56, 48);
    let rays = anari_library_caveray::geometry::OffAxisCamera::new(screen, eye)
        .unwrap()
        .ray_gen(size);
    let desc = FrameDesc::new(size)
        .with_color(ColorFormat::Rgba32F)
        .with_depth();
    for filter in [IsoFilter::Trilinear, IsoFilter::TricubicBSpline] {
        for coloring in [
            Coloring::Flat(Vec3::new(0.9, 0.8, 0.7)),
            Coloring::Curvature { radius: 0.4 },
        ] {
            let settings = IsoSettings {
                filter,
                coloring,
                light: Some(Vec3::new(0.3, 0.6, 1.0)),
                ..IsoSettings::new(0.5)
            };
            let (cpu, hits) = cast(&placed, &rays, &desc, &settings).unwrap();
            let on_gpu = g.cast_iso(&placed, &rays, &desc, &settings, &go).unwrap();
            let name = format!("{} {coloring:?}", filter.name());
            assert!(hits.iter().flatten().count() > 200, "{name}: too few hits");
            let s = ssim(&cpu, &on_gpu).unwrap();
            println!("{name}: SSIM {s:.5}");
            assert!(s >= 0.99, "{name}: SSIM {s}");
            let (a, b) = (cpu.depth.unwrap(), on_gpu.depth.unwrap());
            let same = a
                .iter()
                .zip(&b)
                .filter(|(x, y)| (x.is_infinite() && y.is_infinite()) || (*x - *y).abs() < 1e-3)
                .count();
            assert!(
                same as f64 >= 0.98 * a.len() as f64,
                "{name}: {same} of {} depths agree",
                a.len()
            );
        }
    }
    // Bad settings fail as on the CPU, and the renderer stays usable.
    let e = g
        .cast_iso(&placed, &rays, &desc, &IsoSettings::new(f32::NAN), &go)
        .unwrap_err();
    assert!(e.to_string().contains("iso-value must be finite"), "{e}");
    g.cast_iso(&placed, &rays, &desc, &IsoSettings::new(0.5), &go)
        .unwrap();
}

#[test]
fn the_gpu_gives_every_subpixel_its_own_eye_as_the_cpu_does() {
    use anari_library_caveray::cave::MultiViewDisplay;
    use anari_library_caveray::render::iso::{
        render_display, subpixels_differing, MultiViewMethod,
    };
    let mut g = gpu();
    let go = AtomicBool::new(false);
    let mut placed = balls();
    placed.transform = Mat4::from_translation(Vec3::new(0.0, 0.0, -1.2)) * placed.transform;
    let display = |offset: f64| {
        let text = format!(
            "units = \"m\"\nviews = 8\nresolution = [48, 32]\n\
             ll = [-1.2, -0.8, 0.0]\nlr = [1.2, -0.8, 0.0]\nur = [1.2, 0.8, 0.0]\n\
             viewing_distance = 3.0\nview_spacing = 0.03\n\
             [lens]\npitch = 3.75\nslant = 0.15625\noffset = {offset:?}\n"
        );
        MultiViewDisplay::from_toml(&text, "test display").unwrap()
    };
    let settings = IsoSettings::new(0.5);
    // A second lens offset, then the first again: the GPU keeps a panel's
    // buffers between casts and must notice the pattern change.
    let mut first = None;
    for offset in [0.0, 1.5, 0.0] {
        let d = display(offset);
        let panel = common::iso::panel(&d);
        for method in [
            MultiViewMethod::PerSubpixel,
            MultiViewMethod::GeometricSpectral,
            MultiViewMethod::GreenGeometry,
        ] {
            let (cpu, _) = render_display(&placed, &panel, &settings, method).unwrap();
            let on_gpu = g
                .cast_display(&placed, &panel, &settings, method, &go)
                .unwrap();
            let differ = subpixels_differing(&cpu, &on_gpu, 2);
            println!(
                "lens offset {offset}, {}, GPU against CPU: {:.3}% of subpixels differ",
                method.name(),
                100.0 * differ
            );
            assert!(
                differ <= 0.005,
                "{}: {differ} of subpixels differ",
                method.name()
            );
            assert!(ssim(&cpu, &on_gpu).unwrap() >= 0.99);
            if method == MultiViewMethod::PerSubpixel {
                match &first {
                    None => first = Some(on_gpu),
                    Some(f) if offset == 0.0 => assert_eq!(f.color, on_gpu.color),
                    Some(f) => assert_ne!(f.color, on_gpu.color, "the pattern moved"),
                }
            }
        }
    }
    let d = display(0.0);
    let panel = common::iso::panel(&d);
    let e = g
        .cast_display(&placed, &panel, &settings, MultiViewMethod::Naive, &go)
        .unwrap_err();
    assert!(e.to_string().contains("naive is cast_iso per view"), "{e}");
}
