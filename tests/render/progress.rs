//! Progress within a frame: every path counts exactly the units it
//! announces (CPU tiles or rows, GPU bands), announces them all before
//! the first is done, and counts up while it runs, not only at its end.

use crate::common;

use std::sync::atomic::AtomicBool;

use anari_library_caveray::cave::MultiViewDisplay;
use anari_library_caveray::geometry::{OffAxisCamera, PrimaryRays};
use anari_library_caveray::render::iso::{IsoSettings, IsoSurface, MultiViewMethod};
use anari_library_caveray::render::stereo::{Bounds, HmdStereo, LayerFormat, Reprojection};
use anari_library_caveray::render::{
    CpuRenderer, Done, FrameDesc, GpuRenderer, Progress, Render as _, RenderSettings, Renderer,
    Shading, Watch,
};
use common::render::{gpu, off_axis_wall, phantom};
use glam::{Mat4, UVec2, Vec3};

/// Pixels per CPU tile edge (src/render/cpu).
const TILE: u32 = 16;

fn wall_rays(size: UVec2) -> anari_library_caveray::geometry::RayGen {
    let (screen, eye) = off_axis_wall();
    OffAxisCamera::new(screen, eye).unwrap().ray_gen(size)
}

fn tiles(size: UVec2) -> u32 {
    size.x.div_ceil(TILE) * size.y.div_ceil(TILE)
}

fn done(units: u32) -> Done {
    Done {
        done: units,
        total: units,
    }
}

/// The balls in front of the off-axis wall, and a display of 4 views.
fn surface() -> IsoSurface {
    IsoSurface {
        placed: common::iso::two_balls(24, Mat4::from_scale(Vec3::splat(1.6))),
        settings: IsoSettings::new(0.5),
    }
}

/// A frame 512 pixels wide and as few rows high as make two bands on
/// this adapter (software adapters cast smaller bands).
fn two_bands(g: &GpuRenderer) -> UVec2 {
    let mut size = UVec2::new(512, 8);
    while g.band_count(size) < 2 {
        size.y *= 2;
    }
    size
}

fn display(size: UVec2) -> MultiViewDisplay {
    let text = format!(
        "units = \"m\"\nviews = 4\nresolution = [{}, {}]\n\
         ll = [-1.2, -0.8, 2.0]\nlr = [1.2, -0.8, 2.0]\nur = [1.2, 0.8, 2.0]\n\
         viewing_distance = 3.0\nview_spacing = 0.03\n\
         [lens]\npitch = 3.75\nslant = 0.15625\noffset = 0.0\n",
        size.x, size.y
    );
    MultiViewDisplay::from_toml(&text, "progress display").unwrap()
}

#[test]
fn the_cpu_counts_every_tile_and_moves_within_a_frame() {
    let cpu = CpuRenderer::new();
    let scene = phantom(48);
    let size = UVec2::new(160, 128);
    let rays = wall_rays(size);
    let settings = RenderSettings {
        shading: Shading::Shadows,
        ..Default::default()
    };
    let desc = FrameDesc::new(size);
    let total = tiles(size);
    // A loaded machine may finish a frame between two looks: a few tries,
    // each watched from this thread while another renders.
    let mut between = Vec::new();
    for _ in 0..5 {
        let counter = Progress::new();
        let mut seen = vec![counter.get()];
        std::thread::scope(|s| {
            let render = s.spawn(|| {
                cpu.render_until(&scene, &rays, &settings, &desc, &counter)
                    .unwrap()
            });
            while !render.is_finished() {
                let now = counter.get();
                if seen.last() != Some(&now) {
                    seen.push(now);
                }
                std::thread::sleep(std::time::Duration::from_millis(1));
            }
            render.join().unwrap();
        });
        seen.push(counter.get());
        assert_eq!(counter.get(), done(total));
        for pair in seen.windows(2) {
            assert!(pair[0].done <= pair[1].done, "went back: {seen:?}");
            // The total is there before the first tile is done.
            assert!(
                pair[1].total == total || pair[1] == Done::default(),
                "{seen:?}"
            );
        }
        between = seen
            .iter()
            .filter(|d| d.done > 0 && d.done < total)
            .copied()
            .collect();
        if !between.is_empty() {
            break;
        }
    }
    assert!(
        !between.is_empty(),
        "no reading between 0 and {total} tiles in 5 frames"
    );
    println!("readings within the frame: {between:?}");
}

#[test]
fn the_cpu_counts_rows_of_captures_surfaces_and_panels() {
    let mut r = Renderer::Cpu(CpuRenderer::new());
    let never = AtomicBool::new(false);
    let size = UVec2::new(40, 24);
    let rays = wall_rays(size);
    let counter = Progress::new();
    let watch = || Watch::new(&never).counting(&counter);

    r.capture(
        &phantom(16),
        &rays,
        &RenderSettings::default(),
        size,
        2,
        watch(),
    )
    .unwrap();
    assert_eq!(counter.get(), done(size.y));

    // Two surfaces: both casts' rows announced before the first.
    counter.reset();
    let (a, b) = (surface(), surface());
    r.cast_surfaces(&[a, b], &rays, &FrameDesc::new(size), watch())
        .unwrap();
    assert_eq!(counter.get(), done(2 * size.y));

    let d = display(size);
    let panel = common::iso::panel(&d);
    for (method, passes) in [
        (MultiViewMethod::PerSubpixel, 1),
        (MultiViewMethod::GeometricSpectral, 2),
        (MultiViewMethod::Naive, 4),
    ] {
        counter.reset();
        r.cast_display(&surface(), &panel, method, watch()).unwrap();
        assert_eq!(counter.get(), done(passes * size.y), "{}", method.name());
    }
}

#[test]
fn a_stopped_frame_counts_no_unit_it_did_not_finish() {
    let cpu = CpuRenderer::new();
    let stop = AtomicBool::new(true);
    let counter = Progress::new();
    let size = UVec2::new(48, 48);
    let e = cpu
        .render_until(
            &phantom(16),
            &wall_rays(size),
            &RenderSettings::default(),
            &FrameDesc::new(size),
            Watch::new(&stop).counting(&counter),
        )
        .unwrap_err();
    assert_eq!(e, anari_library_caveray::render::RenderError::Stopped);
    assert_eq!(
        counter.get(),
        Done {
            done: 0,
            total: tiles(size)
        }
    );
}

#[test]
fn the_gpu_counts_every_band_it_finishes() {
    let mut g = gpu();
    let scene = phantom(16);
    let size = two_bands(&g);
    let bands = g.band_count(size) as u32;
    let rays = wall_rays(size);
    let counter = Progress::new();
    let settings = RenderSettings {
        shading: Shading::Shadows,
        ..Default::default()
    };
    g.render_until(&scene, &rays, &settings, &FrameDesc::new(size), &counter)
        .unwrap();
    assert_eq!(counter.get(), done(bands));

    counter.reset();
    g.capture(&scene, &rays, &settings, size, 0, &counter)
        .unwrap();
    assert_eq!(counter.get(), done(bands));

    // Re-projected stereo: the left eye's bands and the compositing.
    counter.reset();
    let (left, right) = HmdStereo::protocol(256, 12.0).eyes(0.0).unwrap();
    let square = UVec2::splat(256);
    let plan = Reprojection::new(
        &left,
        &right,
        square,
        Bounds::of(&scene),
        None,
        LayerFormat::Rgba16F,
    )
    .unwrap();
    let march = g.band_count(plan.plan.cast) as u32;
    g.render_reprojected_until(
        &scene,
        &left.ray_gen(square),
        &plan,
        &RenderSettings::default(),
        &FrameDesc::new(square),
        &counter,
    )
    .unwrap();
    assert_eq!(counter.get(), done(march + 1));
}

#[test]
fn the_gpu_counts_every_pass_of_surfaces_and_panels() {
    let g = gpu();
    let size = two_bands(&g);
    let bands = g.band_count(size) as u32;
    let mut r = Renderer::Gpu(Box::new(g));
    let rays = wall_rays(size);
    let counter = Progress::new();

    let (a, b) = (surface(), surface());
    r.cast_surfaces(&[a, b], &rays, &FrameDesc::new(size), &counter)
        .unwrap();
    assert_eq!(counter.get(), done(2 * bands));

    let d = display(size);
    let panel = common::iso::panel(&d);
    for (method, passes) in [
        (MultiViewMethod::PerSubpixel, 1),
        (MultiViewMethod::GeometricSpectral, 2),
        (MultiViewMethod::Naive, 4),
    ] {
        counter.reset();
        r.cast_display(&surface(), &panel, method, &counter)
            .unwrap();
        assert_eq!(counter.get(), done(passes * bands), "{}", method.name());
    }
}
