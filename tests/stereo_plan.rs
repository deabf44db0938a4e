//! The re-projection planner against numbers worked out by hand from the
//! paper's equations (Buchacher & Erdt 2017; docs/reprojection_stereo.md), the
//! layer assignment against a CPU model, and the CAVE-wall planner against
//! real rig geometry.

mod common;

use anari_library_caveray::cave::Eye;
use anari_library_caveray::render::stereo::{
    layer_memory, layers_for, minimal_focal_length, pixel_scale, plan_views, span_to_sphere,
    Bounds, HmdStereo, LayerCountError, LayerFormat, NotEpipolar, StereoError,
};
use glam::{DVec3, UVec2};

const MIB: f64 = 1024.0 * 1024.0;

#[test]
fn paper_numbers() {
    // w = 768, 2a = 110 deg, e = 0.065 m, r = 1 m, d_p = 32:
    // tan 55 deg = 1.428148; e r w / (d_p tan a) = 49.92 / 45.70074 = 1.092323;
    // h = -1 + sqrt(1 + 1.092323) = 0.446486 m.
    let a = 55f64.to_radians();
    let h = minimal_focal_length(1.0, 0.065, 768.0, 32.0, a);
    assert!((h - 0.446486).abs() < 1e-6, "h = {h}");
    // The paper reports h = 0.435 m, which d_p = 33 reproduces.
    let h33 = minimal_focal_length(1.0, 0.065, 768.0, 33.0, a);
    assert!((h33 - 0.435).abs() < 5e-4, "h(33) = {h33}");
    // Back again: s = 768 / (2 h tan a) = 768 / 1.275293 = 602.21 px per metre,
    // d_r = e - e h / (h + 2r) = 0.065 * 2 / 2.446486 = 0.0531373 m, 32.000 px.
    let s = pixel_scale(768.0, h, a);
    assert!((s - 602.21).abs() < 0.01, "s = {s}");
    let d_r = span_to_sphere(0.065, h, 1.0);
    assert!((d_r - 0.0531373).abs() < 1e-6, "d_r = {d_r}");
    assert!((d_r * s - 32.0).abs() < 1e-9);
    // Memory: 768^2 x 32 x RGBA16F = 144 MiB; 1080^2: 284.77 MiB; 1512^2: 558.14 MiB.
    // M = w^2 L bytes channels, RGBA16F: 2 bytes times 4 channels a texel.
    let m = |w: u32| layer_memory(UVec2::splat(w), 32, LayerFormat::Rgba16F) as f64 / MIB;
    assert_eq!(LayerFormat::Rgba16F.bytes_per_texel(), 2 * 4);
    assert_eq!(m(768), 144.0);
    assert!((m(1080) - 284.77).abs() < 0.005);
    assert!((m(1512) - 558.14).abs() < 0.005);
}

#[test]
fn layers_cover_the_longest_span() {
    // Samples land in the pixel they fall in, so a 31 px span can reach
    // into 32 pixels and a 31.5 px span into 33.
    let plan = HmdStereo::paper(31.0).plan().unwrap();
    assert!((plan.span_px - 31.0).abs() < 1e-9);
    assert_eq!(plan.layers, 32);
    assert_eq!(
        plan.memory,
        layer_memory(UVec2::splat(768), 32, LayerFormat::Rgba16F)
    );
    assert_eq!(HmdStereo::paper(31.5).plan().unwrap().layers, 33);
    assert_eq!(HmdStereo::paper_for_layers(32), HmdStereo::paper(31.0));
    // The paper's d_p = 32 with 32 layers would let two rays share texels
    // at the sphere's extremes; the planner asks for 33.
    let setup = HmdStereo::paper(32.0);
    match setup.plan_with(32) {
        Err(StereoError::Layers(LayerCountError::TooFewLayers {
            layers: 32,
            needed: 33,
            ..
        })) => {}
        other => panic!("{other:?}"),
    }
    // Rays to infinity span e, more than the sphere's d_r.
    let unbounded = HmdStereo {
        radius: None,
        ..setup
    }
    .plan()
    .unwrap();
    assert!(unbounded.span_px > 32.0);
}

#[test]
fn zero_eye_distance_needs_one_layer_and_bad_input_is_refused() {
    let mono = HmdStereo {
        eye_distance: 0.0,
        ..HmdStereo::paper(32.0)
    };
    assert_eq!(mono.plan().unwrap().layers, 1);
    let paper = HmdStereo::paper(32.0);
    assert_eq!(
        paper.plan_with(0),
        Err(StereoError::Layers(LayerCountError::NoLayers))
    );
    assert_eq!(
        HmdStereo {
            eye_distance: -0.065,
            ..paper
        }
        .plan(),
        Err(StereoError::NegativeEyeDistance(-0.065))
    );
    assert!(matches!(
        HmdStereo {
            focal: 0.0,
            ..paper
        }
        .plan(),
        Err(StereoError::NotPositive {
            what: "focal length",
            ..
        })
    ));
    assert!(matches!(
        HmdStereo { fov: 3.5, ..paper }.plan(),
        Err(StereoError::FieldOfView(_))
    ));
    let message = paper.plan_with(8).unwrap_err().to_string();
    assert!(
        message.contains("8 layers are too few") && message.contains("at least 33"),
        "{message}"
    );
}

/// Which layer texels the left rays of one image row write: ray x writes
/// every right pixel its segment crosses, in layer L - (x mod L) - 1.
fn collisions(width: i64, layers: i64, offset: impl Fn(f64) -> f64, depths: (f64, f64)) -> usize {
    let mut written = std::collections::HashSet::new();
    let mut collisions = 0;
    for x in 0..width {
        let k = layers - x.rem_euclid(layers) - 1;
        let first = (x as f64 + offset(depths.0)).round() as i64;
        let last = (x as f64 + offset(depths.1)).round() as i64;
        for p in first.min(last)..=first.max(last) {
            if !written.insert((k, p)) {
                collisions += 1;
            }
        }
    }
    collisions
}

#[test]
fn planned_layers_never_share_a_texel() {
    for span in [7.3, 16.0, 31.0, 31.5, 40.9] {
        let setup = HmdStereo::paper(span);
        let plan = setup.plan().unwrap();
        let (e, h, r) = (setup.eye_distance, setup.focal, setup.radius.unwrap());
        let s = pixel_scale(768.0, h, 0.5 * setup.fov);
        // Right-image x minus left-image x of a point at depth z, from the
        // image plane (z = h) to the sphere's far side (z = h + 2r).
        let offset = |z: f64| -e * h * s / z;
        let depths = (h, h + 2.0 * r);
        // With whole-pixel rays every ray's segment covers the same number
        // of pixels; the plan must cover it, and that many layers must be
        // exactly enough.
        let exact = (offset(depths.1).round() - offset(depths.0).round()) as i64 + 1;
        assert!(
            i64::from(plan.layers) >= exact,
            "span {span}: {plan:?} < {exact}"
        );
        assert_eq!(
            collisions(768 + 64, i64::from(plan.layers), offset, depths),
            0,
            "span {span}"
        );
        assert_eq!(
            collisions(768 + 64, exact, offset, depths),
            0,
            "span {span}"
        );
        // One layer fewer must collide, or the check proves nothing.
        assert!(
            collisions(768 + 64, exact - 1, offset, depths) > 0,
            "span {span}"
        );
    }
}

#[test]
fn front_wall_with_a_level_head_plans_and_a_side_wall_falls_back() {
    let rig = common::rig("cologne_5wall");
    let head = rig.head_pose(None, Some(DVec3::ZERO));
    let (centre, radius) = (rig.scene.centre, 0.5 * rig.scene.size * 3f64.sqrt());
    let cameras = |wall: &str| {
        let w = rig.wall(wall).unwrap();
        let l = rig.view(w, Eye::Left, &head).unwrap();
        let r = rig.view(w, Eye::Right, &head).unwrap();
        (l.matrix_camera().unwrap(), r.matrix_camera().unwrap(), l, r)
    };

    let (l, r, lv, rv) = cameras("front");
    let plan = plan_views(&l, &r, 400, 400, Bounds::Sphere { centre, radius }).unwrap();
    // On a shared wall the shift is e (1 - d / z) in wall units, zero on
    // the wall itself and growing with depth.
    let wall = rig.wall("front").unwrap();
    let e = (rv.eye_position - lv.eye_position).length();
    let d = wall.screen.extents(lv.eye_position).unwrap().distance;
    let s = 400.0 / wall.screen.width();
    let z_far = (centre - lv.eye_position).dot(-wall.screen.normal()) + radius;
    let expected_far = e * (1.0 - d / z_far) * s;
    assert!(
        (plan.far_offset - expected_far).abs() < 0.01,
        "{plan:?} vs {expected_far}"
    );
    assert!(plan.near_offset < plan.far_offset);
    assert_eq!(plan.near_px, plan.near_offset.round() as i32);
    assert_eq!(plan.far_px, plan.far_offset.round() as i32);
    assert_eq!(plan.layers as i32, plan.far_px - plan.near_px + 1);
    assert!(plan.layers <= layers_for(plan.far_offset - plan.near_offset));

    // The volume's box lies inside its sphere, which here reaches behind
    // the eyes: the box needs far fewer layers.
    let half = DVec3::splat(0.5 * rig.scene.size);
    let boxed = plan_views(
        &l,
        &r,
        400,
        400,
        Bounds::Box {
            lo: centre - half,
            hi: centre + half,
        },
    )
    .unwrap();
    assert!(boxed.layers < plan.layers, "{boxed:?} vs {plan:?}");
    assert!(boxed.near_offset > plan.near_offset && boxed.far_offset <= plan.far_offset);

    // Facing the front wall, the baseline points into the side walls.
    let (l, r, _, _) = cameras("left");
    let why = plan_views(&l, &r, 400, 400, Bounds::Sphere { centre, radius }).unwrap_err();
    assert!(
        matches!(
            why,
            NotEpipolar::VerticalDisparity(_) | NotEpipolar::UnevenShift(_)
        ),
        "{why}"
    );
}
