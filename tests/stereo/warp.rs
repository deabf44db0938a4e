//! Image warping and rendering in cells (docs/warping.md): cameras run
//! backwards land on their own pixels; cells pasted together are the whole
//! image; every warp shows an unchanged view unchanged; moved eyes are
//! shown better by every warp than by the stale image, and a sideways step
//! best by the layers; the display timeline reports what it showed; bad
//! settings fail with their reasons.

use crate::common;

use std::sync::atomic::AtomicBool;

use anari_library_caveray::cave::Rig;
use anari_library_caveray::cave::{pose_along, Eye};
use anari_library_caveray::data::{grid_cells, preset, shepp_logan, Cut};
use anari_library_caveray::geometry::{
    ImageRegion, OrthographicCamera, PinholeCamera, PrimaryRays, RayGen,
};
use anari_library_caveray::render::cells::{CellGrid, CellRun, Predictor};
use anari_library_caveray::render::warp::{
    warp, Projector, Source, Timeline, WarpMode, WarpSettings,
};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    dssim, ColorFormat, CpuRenderer, Frame, FrameDesc, RenderError, RenderSettings, Renderer,
};
use anari_library_caveray::scene::Scene;
use common::render::{four_cameras, off_axis_wall, phantom};
use glam::{DVec3, UVec2};

const SIZE: UVec2 = UVec2::new(48, 40);

fn capture(scene: &Scene, rays: &RayGen, layers: usize) -> Source {
    CpuRenderer::new()
        .capture(
            scene,
            rays,
            &RenderSettings::default(),
            SIZE,
            layers,
            &AtomicBool::new(false),
        )
        .unwrap()
}

fn ideal(scene: &Scene, rays: &RayGen) -> Frame {
    CpuRenderer::new()
        .render(
            scene,
            rays,
            &RenderSettings::default(),
            &FrameDesc::new(SIZE).with_color(ColorFormat::Rgba32F),
        )
        .unwrap()
}

fn shown(source: &Source, target: &RayGen, mode: WarpMode, scene: &Scene) -> Frame {
    warp(
        source,
        target,
        SIZE,
        &WarpSettings::new(mode, scene.bounds()),
    )
    .unwrap()
    .frame(
        &FrameDesc::new(SIZE).with_color(ColorFormat::Rgba32F),
        RenderSettings::default().background,
    )
    .unwrap()
}

/// The phantom where `rig` puts volumes, its opacity kept at that size
/// (as the tool places it).
fn placed_phantom(n: u32, rig: &Rig) -> Scene {
    let size = rig.scene.size as f32;
    let tf = preset("phantom").unwrap();
    let tf = tf
        .clone()
        .with_unit_distance(tf.unit_distance() * size / 2.0)
        .unwrap();
    Scene::new(shepp_logan(n).placed(rig.scene.centre.as_vec3(), size), tf)
}

/// A pinhole on the +z axis looking at the origin from `eye`.
fn pinhole(eye: DVec3, look: DVec3) -> RayGen {
    PinholeCamera::new(
        eye,
        look - eye,
        DVec3::Y,
        50f64.to_radians(),
        f64::from(SIZE.x) / f64::from(SIZE.y),
        ImageRegion::FULL,
    )
    .unwrap()
    .ray_gen(SIZE)
}

#[test]
fn every_camera_run_backwards_lands_on_its_own_pixel() {
    let (screen, eye) = off_axis_wall();
    let mut cameras = four_cameras(&screen, eye, SIZE);
    let ortho = OrthographicCamera::new(
        DVec3::new(0.2, 0.1, 4.0),
        DVec3::new(0.1, 0.0, -1.0),
        DVec3::Y,
        2.5,
        1.2,
        ImageRegion::FULL,
    )
    .unwrap();
    cameras.push(("orthographic", ortho.ray_gen(SIZE)));
    for (name, rays) in cameras {
        let projector = Projector::new(&rays).unwrap();
        for (x, y) in [(0, 0), (47, 0), (13, 29), (47, 39)] {
            let (o, d) = rays.pixel_ray(x, y);
            for t in [0.5f32, 3.0, 7.0] {
                let seen = projector.locate(o + d * t).unwrap();
                let (at, along) = (seen.at, seen.along);
                let want = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                assert!(
                    (at - want).length() < 2e-3,
                    "{name}: pixel ({x}, {y}) at t = {t} located at {at}"
                );
                assert!(
                    (along - t).abs() < 1e-4 * t.max(1.0),
                    "{name}: t {t} came back as {along}"
                );
            }
        }
    }
    // Behind a pinhole's eye there is no pixel.
    let rays = pinhole(DVec3::new(0.0, 0.0, 4.0), DVec3::ZERO);
    let p = Projector::new(&rays).unwrap();
    assert!(p.locate(glam::Vec3::new(0.0, 0.0, 5.0)).is_none());
}

#[test]
fn rays_that_neither_meet_nor_run_parallel_have_no_projector() {
    let mut rays = pinhole(DVec3::new(0.0, 0.0, 4.0), DVec3::ZERO);
    rays.origin_dx = glam::Vec3::new(0.01, 0.0, 0.0);
    let e = Projector::new(&rays).unwrap_err();
    assert!(
        e.contains("neither meet in one eye nor run parallel"),
        "{e}"
    );
}

#[test]
fn cells_tile_the_image_and_pasted_together_are_the_whole_capture() {
    let grid = CellGrid::new(SIZE, UVec2::new(5, 3)).unwrap();
    let mut covered = vec![0u8; (SIZE.x * SIZE.y) as usize];
    for i in 0..grid.count() {
        let (lo, size) = grid.rect(i);
        for y in lo.y..lo.y + size.y {
            for x in lo.x..lo.x + size.x {
                covered[(y * SIZE.x + x) as usize] += 1;
            }
        }
    }
    assert!(
        covered.iter().all(|&c| c == 1),
        "cells overlap or leave gaps"
    );
    assert_eq!(
        CellGrid::new(UVec2::new(3, 2), UVec2::new(8, 8))
            .unwrap()
            .cells,
        UVec2::new(3, 2),
        "at most one cell per pixel"
    );

    let scene = phantom(24);
    let (screen, eye) = off_axis_wall();
    let rays = four_cameras(&screen, eye, SIZE)[0].1;
    let whole = capture(&scene, &rays, 3);
    let mut pasted = Source::empty(SIZE, rays, 3).unwrap();
    for i in 0..grid.count() {
        let (lo, size) = grid.rect(i);
        let part = CpuRenderer::new()
            .capture(
                &scene,
                &rays.shifted(lo.as_vec2()),
                &RenderSettings::default(),
                size,
                3,
                &AtomicBool::new(false),
            )
            .unwrap();
        pasted.paste(lo, &part).unwrap();
    }
    let close = whole
        .color
        .iter()
        .zip(&pasted.color)
        .all(|(a, b)| (*a - *b).abs().max_element() < 1e-4);
    assert!(close, "cells differ from the whole image");
    assert_eq!(whole.samples, pasted.samples);
    let wrong = Source::empty(UVec2::new(4, 4), rays, 3).unwrap();
    let e = pasted.paste(UVec2::new(46, 0), &wrong).unwrap_err();
    assert!(e.to_string().contains("does not fit"), "{e}");
}

#[test]
fn predictions_take_the_neighbourhood_maximum_times_the_bias() {
    let grid = CellGrid::new(UVec2::new(40, 40), UVec2::new(4, 4)).unwrap();
    let mut p = Predictor::new(grid, 1.5);
    assert_eq!(p.predict(5), 0.0, "nothing known: render and learn");
    p.record(0, 2.0);
    assert_eq!(p.predict(15), 3.0, "no neighbour known: the largest time");
    p.record(15, 1.0);
    p.record(10, 4.0);
    assert_eq!(p.predict(5), 6.0, "cell 10 neighbours cell 5");
    assert_eq!(p.predict(0), 3.0, "cell 10 is not cell 0's neighbour");
    assert_eq!(Predictor::new(grid, 0.5).bias(), 1.0, "bias is at least 1");

    let mut run = CellRun::new(grid, 1.0);
    run.done(0, 5.0);
    assert_eq!(
        run.next_cell(4.0, false),
        None,
        "cell 1 is predicted at 5 ms"
    );
    assert_eq!(
        run.next_cell(4.0, true),
        Some(1),
        "the first cell of a frame always runs"
    );
    assert_eq!(run.next_cell(5.0, false), Some(1));
}

#[test]
fn every_warp_shows_an_unchanged_view_unchanged() {
    let scene = phantom(32);
    let rays = pinhole(DVec3::new(0.3, 0.2, 3.5), DVec3::ZERO);
    let source = capture(&scene, &rays, 4);
    let truth = ideal(&scene, &rays);
    for mode in WarpMode::ALL {
        let d = dssim(&shown(&source, &rays, mode, &scene), &truth).unwrap();
        assert!(d < 2e-3, "{}: DSSIM {d} for the same view", mode.name());
    }
}

#[test]
fn moved_eyes_are_shown_better_by_every_warp_and_a_step_best_by_the_layers() {
    let scene = phantom(32);
    let from = pinhole(DVec3::new(0.0, 0.0, 3.5), DVec3::ZERO);
    warps_beat_none_and_layers_the_step(&scene, &capture(&scene, &from, 4));
}

/// `source`, captured from (0, 0, 3.5) looking at the origin, shown after
/// a step sideways, looking ahead (the step path), and after a turn of the
/// head (the view direction swings): every warp beats the stale image,
/// and the layers are best on the step.
fn warps_beat_none_and_layers_the_step(scene: &Scene, source: &Source) {
    let step = pinhole(DVec3::new(0.35, 0.0, 3.5), DVec3::new(0.35, 0.0, 0.0));
    let turn = pinhole(DVec3::new(0.0, 0.0, 3.5), DVec3::new(0.5, 0.0, 0.0));
    for (name, target) in [("step", step), ("turn", turn)] {
        let truth = ideal(scene, &target);
        let d: Vec<f64> = WarpMode::ALL
            .iter()
            .map(|&m| dssim(&shown(source, &target, m, scene), &truth).unwrap())
            .collect();
        for (m, v) in WarpMode::ALL.iter().zip(&d).skip(1) {
            assert!(
                v < &d[0],
                "{name}: {} ({v}) is no better than none ({})",
                m.name(),
                d[0]
            );
        }
        if name == "step" {
            assert!(d[3] < d[1] && d[3] < d[2], "{name}: layers not best: {d:?}");
        }
    }
}

/// An unstructured field (the phantom's cells cut into tetrahedra) is
/// captured and warped as a grid is.
#[test]
fn a_mesh_is_warped_by_every_mode_and_a_step_best_by_the_layers() {
    let mesh = grid_cells(&shepp_logan(24), Cut::Tetrahedra).unwrap();
    let scene = Scene::new(mesh, preset("phantom").unwrap());
    let from = pinhole(DVec3::new(0.0, 0.0, 3.5), DVec3::ZERO);
    let source = capture(&scene, &from, 4);
    for mode in WarpMode::ALL {
        let d = dssim(&shown(&source, &from, mode, &scene), &ideal(&scene, &from)).unwrap();
        assert!(d < 2e-3, "{}: DSSIM {d} for the same view", mode.name());
    }
    warps_beat_none_and_layers_the_step(&scene, &source);
}

/// An AMR field of three levels is captured and warped as a grid is.
#[test]
fn an_amr_field_is_warped_by_every_mode_and_a_step_best_by_the_layers() {
    use anari_library_caveray::data::{refined, smooth_waves};
    let scene = Scene::new(
        refined(32, 3, smooth_waves).unwrap(),
        preset("phantom").unwrap(),
    );
    let from = pinhole(DVec3::new(0.0, 0.0, 3.5), DVec3::ZERO);
    let source = capture(&scene, &from, 4);
    for mode in WarpMode::ALL {
        let d = dssim(&shown(&source, &from, mode, &scene), &ideal(&scene, &from)).unwrap();
        assert!(d < 2e-3, "{}: DSSIM {d} for the same view", mode.name());
    }
    warps_beat_none_and_layers_the_step(&scene, &source);
}

/// A NanoVDB grid (the library's fog sphere) is captured and warped as a
/// grid is.
#[test]
fn a_nanovdb_grid_is_warped_by_every_mode_and_a_step_best_by_the_layers() {
    use anari_library_caveray::scene::Filter;
    let Some(written) = common::nanovdb::grids() else {
        return;
    };
    let grid = written.grid("fog", Filter::Linear);
    let scene = common::nanovdb::scene(grid, preset("shells").unwrap());
    let from = pinhole(DVec3::new(0.0, 0.0, 3.5), DVec3::ZERO);
    let source = capture(&scene, &from, 4);
    for mode in WarpMode::ALL {
        let d = dssim(&shown(&source, &from, mode, &scene), &ideal(&scene, &from)).unwrap();
        assert!(d < 2e-3, "{}: DSSIM {d} for the same view", mode.name());
    }
    warps_beat_none_and_layers_the_step(&scene, &source);
}

#[test]
fn surfaces_in_the_volume_are_warped_by_every_mode_and_a_step_best_by_the_layers() {
    use anari_library_caveray::scene::{AlphaMode, ColorSource, OpacitySource, SurfaceMaterial};
    use glam::Vec3;
    // An opaque ball in front of the phantom's middle and a translucent
    // one inside it: the layers hold each as a layer of its own, so a
    // step sideways moves them against the volume behind.
    let material = |color: Vec3, opacity: f32, alpha: AlphaMode| SurfaceMaterial {
        color: ColorSource::Constant(color),
        opacity: OpacitySource::Constant(opacity),
        alpha,
        pbr: None,
    };
    let scene = phantom(32)
        .with_shapes(vec![
            common::render::balls(
                vec![Vec3::new(-0.3, 0.25, 0.6)],
                0.25,
                material(Vec3::new(0.9, 0.5, 0.2), 1.0, AlphaMode::Opaque),
            ),
            common::render::balls(
                vec![Vec3::new(0.25, -0.2, 0.0)],
                0.4,
                material(Vec3::new(0.2, 0.6, 0.9), 0.4, AlphaMode::Blend),
            ),
        ])
        .unwrap();
    let look = DVec3::ZERO;
    let from = pinhole(DVec3::new(0.0, 0.0, 3.5), look);
    let source = capture(&scene, &from, 4);
    let same = dssim(
        &shown(&source, &from, WarpMode::Layers, &scene),
        &ideal(&scene, &from),
    )
    .unwrap();
    assert!(same < 2e-3, "layers: DSSIM {same} for the same view");
    warps_beat_none_and_layers_the_step(&scene, &source);
}

#[test]
fn a_wall_warp_follows_the_eye_across_the_fixed_wall() {
    // On a wall only the eye moves: the quad warp's plane stays parallel
    // to the wall, and the stale image is worse than every warp.
    let rig = common::rig("cologne_5wall").with_neck_model();
    let wall = rig.wall("front").unwrap();
    let scene = placed_phantom(32, &rig);
    let keys = rig
        .load_head_path(&common::config_dir().join("head_paths/step_1s.toml"))
        .unwrap();
    let at = |t: f64| {
        let head = pose_along(&keys, t).unwrap();
        rig.view(wall, Eye::Mono, &head)
            .unwrap()
            .camera
            .ray_gen(SIZE)
    };
    let (from, to) = (at(0.3), at(0.5));
    let source = capture(&scene, &from, 4);
    let truth = ideal(&scene, &to);
    let d: Vec<f64> = WarpMode::ALL
        .iter()
        .map(|&m| dssim(&shown(&source, &to, m, &scene), &truth).unwrap())
        .collect();
    for v in &d[1..] {
        assert!(
            *v < d[0],
            "a warp is no better than none on the wall: {d:?}"
        );
    }
    let n = Projector::new(&from).unwrap().image_normal();
    let wall_normal = wall.screen.normal().as_vec3();
    assert!(
        n.dot(-wall_normal) > 1.0 - 1e-4,
        "image plane {n} is not the wall {wall_normal}"
    );
}

#[test]
fn the_timeline_shows_a_still_head_exactly_and_ages_a_moving_one() {
    let scene = phantom(24);
    let still = pinhole(DVec3::new(0.0, 0.0, 3.5), DVec3::ZERO);
    let timeline = Timeline {
        hz: 60.0,
        duration: 0.2,
        size: SIZE,
        cells: UVec2::new(4, 4),
        bias: 1.2,
        layers: 4,
        render_ms: Some(40.0),
        warp_ms: 2.0,
        modes: WarpMode::ALL.to_vec(),
        warp: WarpSettings::new(WarpMode::None, scene.bounds()),
    };
    let mut renderer = Renderer::Cpu(CpuRenderer::new());
    let settings = RenderSettings::default();
    let mut seen = 0;
    let out = timeline
        .run(&mut renderer, &scene, &settings, &|_| Ok(still), &mut |r| {
            seen += 1;
            assert_eq!(r.shown.len(), 4);
        })
        .unwrap();
    assert_eq!((out.len(), seen), (12, 12), "0.2 s at 60 Hz");
    for r in &out {
        assert!(r.dssim.iter().all(|&d| d < 2e-3), "still head: {r:?}");
        assert!(
            r.age_ms >= 1e3 / 60.0 - 1e-9,
            "nothing is shown before it was rendered"
        );
    }
    // With a 40 ms image and 14.7 ms a refresh, an image takes at least
    // three refreshes: ages grow between swaps.
    let images = out.windows(2).filter(|w| w[1].age_ms < w[0].age_ms).count();
    assert!((1..=4).contains(&images), "{images} images in 0.2 s");

    let moving = |t: f64| {
        Ok(pinhole(
            DVec3::new(2.0 * t, 0.0, 3.5),
            DVec3::new(2.0 * t, 0.0, 0.0),
        ))
    };
    let out = timeline
        .run(&mut renderer, &scene, &settings, &moving, &mut |_| {})
        .unwrap();
    let mean = |i: usize| out.iter().map(|r| r.dssim[i]).sum::<f64>() / out.len() as f64;
    assert!(mean(3) < mean(0), "layers {} vs none {}", mean(3), mean(0));
}

#[test]
fn bad_warp_and_timeline_settings_fail_with_their_reasons() {
    let scene = phantom(16);
    let rays = pinhole(DVec3::new(0.0, 0.0, 3.5), DVec3::ZERO);
    let plain = capture(&scene, &rays, 0);
    let settings = |mode| WarpSettings::new(mode, scene.bounds());
    let message = |r: Result<_, RenderError>| {
        r.map(|_: anari_library_caveray::render::warp::Warped| ())
            .unwrap_err()
            .to_string()
    };
    assert!(
        message(warp(&plain, &rays, SIZE, &settings(WarpMode::Layers)))
            .contains("needs a source rendered with layers")
    );
    assert!(message(warp(
        &plain,
        &rays,
        UVec2::new(8, 8),
        &settings(WarpMode::None)
    ))
    .contains("cannot fill 8x8"));
    let mut s = settings(WarpMode::Grid);
    s.grid_spacing = 0;
    assert!(message(warp(&plain, &rays, SIZE, &s)).contains("grid spacing must be 1 to 256"));
    let mut s = settings(WarpMode::Quad);
    s.layer_steps = 100_000;
    assert!(message(warp(&plain, &rays, SIZE, &s)).contains("layer steps must be 1 to 4096"));
    assert!(message(warp(
        &plain,
        &rays,
        UVec2::new(0, 3),
        &settings(WarpMode::Quad)
    ))
    .contains("at least 1x1"));
    let e = CpuRenderer::new()
        .capture(
            &scene,
            &rays,
            &RenderSettings::default(),
            SIZE,
            9,
            &AtomicBool::new(false),
        )
        .unwrap_err();
    assert!(e.to_string().contains("at most 8 layers"), "{e}");

    let base = Timeline {
        hz: 90.0,
        duration: 0.1,
        size: SIZE,
        cells: UVec2::new(2, 2),
        bias: 1.0,
        layers: 2,
        render_ms: None,
        warp_ms: 1.0,
        modes: vec![WarpMode::Quad],
        warp: settings(WarpMode::None),
    };
    let fails = |t: Timeline, want: &str| {
        let e = t
            .run(
                &mut Renderer::Cpu(CpuRenderer::new()),
                &scene,
                &RenderSettings::default(),
                &|_| Ok(rays),
                &mut |_| {},
            )
            .unwrap_err()
            .to_string();
        assert!(e.contains(want), "{e}");
    };
    fails(
        Timeline {
            hz: 0.0,
            ..base.clone()
        },
        "display rate must be 1 to 1000 Hz",
    );
    fails(
        Timeline {
            duration: f64::NAN,
            ..base.clone()
        },
        "must last more than 0 s",
    );
    fails(
        Timeline {
            render_ms: Some(-1.0),
            ..base.clone()
        },
        "simulated render time",
    );
    fails(
        Timeline {
            warp_ms: 20.0,
            ..base.clone()
        },
        "less than a refresh",
    );
    fails(
        Timeline {
            cells: UVec2::ZERO,
            ..base.clone()
        },
        "at least 1x1 cells",
    );
    let behind = |_: f64| Err("the eye is behind the wall".to_string());
    let e = base
        .run(
            &mut Renderer::Cpu(CpuRenderer::new()),
            &scene,
            &RenderSettings::default(),
            &behind,
            &mut |_| {},
        )
        .unwrap_err();
    assert!(e.to_string().contains("behind the wall"), "{e}");
}
