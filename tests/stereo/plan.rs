//! The re-projection planner against numbers worked out by hand from the
//! paper's equations (Buchacher & Erdt 2017; docs/reprojection_stereo.md), the
//! layer assignment against a CPU model, and the CAVE-wall planner against
//! real rig geometry.

use crate::common;

use anari_library_caveray::cave::Eye;
use std::collections::HashMap;

use anari_library_caveray::geometry::{MatrixCamera, PrimaryRays};
use anari_library_caveray::render::stereo::{
    layer_memory, minimal_focal_length, pixel_scale, plan_views, span_to_sphere, Axis, Bounds,
    HmdStereo, LayerCountError, LayerFormat, NotEpipolar, StereoError, ViewPlan,
};
use glam::{DMat4, DVec3, IVec2, UVec2};

const MIB: f64 = 1024.0 * 1024.0;

#[test]
fn paper_numbers() {
    // w = 768, 2a = 110 deg, e = 0.065 m, r = 1 m, d_p = 32:
    // tan 55 deg = 1.428148; e r w / (d_p tan a) = 49.92 / 45.70074 = 1.092323;
    // h = -1 + sqrt(1 + 1.092323) = 0.446486 m.
    let a = 55f64.to_radians();
    let h = minimal_focal_length(1.0, 0.065, 768.0, 32.0, a);
    assert!((h - 0.446486).abs() < 1e-6, "h = {h}");
    // Buchacher & Erdt report h = 0.435 m, which d_p = 33 reproduces.
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
    // Buchacher & Erdt's d_p = 32 with 32 layers would let two rays share texels
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

/// The planner's pair for `wall` of the Cologne CAVE, seen by a head at
/// its default place turned by `ypr` degrees, over the volume's box, at
/// `width` pixels.
fn cave_pair(
    wall: &str,
    ypr: DVec3,
    width: u32,
    swapped: bool,
) -> (Result<ViewPlan, NotEpipolar>, MatrixCamera, MatrixCamera) {
    let rig = common::rig("cologne_5wall");
    let head = rig.head_pose(None, Some(ypr));
    let w = rig.wall(wall).unwrap();
    let view = |eye| rig.view(w, eye, &head).unwrap().matrix_camera().unwrap();
    let (mut l, mut r) = (view(Eye::Left), view(Eye::Right));
    if swapped {
        std::mem::swap(&mut l, &mut r);
    }
    let half = DVec3::splat(0.5 * rig.scene.size);
    let bounds = Bounds::Box {
        lo: rig.scene.centre - half,
        hi: rig.scene.centre + half,
    };
    let size = (w.resolution.as_dvec2() * f64::from(width) / f64::from(w.resolution.x))
        .round()
        .as_uvec2();
    (plan_views(&l, &r, size.x, size.y, bounds), l, r)
}

/// The CPU model of the layer writes: every left ray cast writes every
/// texel its planned offsets reach, in its family's layer. Returns the
/// texels written twice, with `layers` per family.
fn model_collisions(plan: &ViewPlan, layers: u32) -> usize {
    let l = i64::from(layers);
    let mut owner = HashMap::new();
    let mut collisions = 0;
    for p in cast_pixels(plan) {
        for (o, axis) in model_writes(plan, p) {
            let (texel, layer) = match axis {
                Axis::Columns => (IVec2::new(p.x + o, p.y), i64::from(p.x).rem_euclid(l)),
                Axis::Rows => (IVec2::new(p.x, p.y + o), l + i64::from(p.y).rem_euclid(l)),
            };
            if owner.insert((texel, layer), p).is_some_and(|q| q != p) {
                collisions += 1;
            }
        }
    }
    collisions
}

fn cast_pixels(plan: &ViewPlan) -> impl Iterator<Item = IVec2> + '_ {
    let (first, cast) = (plan.first, plan.cast.as_ivec2());
    (0..cast.y).flat_map(move |y| (0..cast.x).map(move |x| first + IVec2::new(x, y)))
}

/// The (offset, family) pairs left ray `p` writes inside the image.
fn model_writes(plan: &ViewPlan, p: IVec2) -> Vec<(i32, Axis)> {
    let size = plan.size.as_ivec2();
    let mut out = Vec::new();
    for axis in [Axis::Columns, Axis::Rows] {
        if !plan.writes(p.as_dvec2(), axis) {
            continue;
        }
        let [a, b] = plan.ray_offsets(p.as_dvec2(), axis);
        let i = axis as usize;
        for o in a.min(b)..=a.max(b) {
            if (0..size[i]).contains(&(p[i] + o)) {
                out.push((o, axis));
            }
        }
    }
    out
}

/// Every right pixel finds, at every depth of the range, the left ray
/// whose segment it needs among the rays it reads, and that ray writes
/// the family it reads.
fn model_reads_cover(plan: &ViewPlan) -> Result<(), String> {
    let (size, w) = (plan.size.as_ivec2(), plan.epipole.z);
    for y in 0..size.y {
        for x in 0..size.x {
            let q = IVec2::new(x, y);
            let axis = plan.axis_at(q.as_dvec2());
            let i = axis as usize;
            let [a, b] = plan.read_offsets(q.as_dvec2(), axis);
            let g = plan.g(q.as_dvec2())[i];
            for k in 0..=16 {
                let t = f64::from(k) / 16.0;
                let lambda = plan.lambda[0] + t * (plan.lambda[1] - plan.lambda[0]);
                let o = (lambda * g / (1.0 + lambda * w)).round() as i32;
                if o < a.min(b) || o > a.max(b) {
                    return Err(format!("{q}: offset {o} outside the read range {a}..{b}"));
                }
                for (p, share) in plan.read_pixels(q, o, axis) {
                    if share == 0.0 {
                        continue;
                    }
                    let inside = (p - plan.first).cmpge(IVec2::ZERO).all()
                        && (p - plan.first).cmplt(plan.cast.as_ivec2()).all();
                    if !inside {
                        return Err(format!("{q}: reads {p}, which is not cast"));
                    }
                    if !plan.writes(p.as_dvec2(), axis) {
                        return Err(format!("{q}: reads {p}, which does not write {axis:?}"));
                    }
                }
            }
        }
    }
    Ok(())
}

#[test]
fn front_wall_with_a_level_head_shifts_along_the_rows() {
    let (plan, lv, rv) = cave_pair("front", DVec3::ZERO, 400, false);
    let plan = plan.unwrap();
    // A baseline parallel to the wall: the epipole at infinity along the
    // rows, one family, no rows beyond the image.
    assert_eq!(plan.epipole.z, 0.0);
    assert_eq!(plan.epipole.y, 0.0);
    assert_eq!(plan.families, [true, false]);
    assert_eq!((plan.first.y, plan.cast.y), (0, 400));
    // On a shared wall the shift is e (1 - d / z) in wall units, zero on
    // the wall itself and growing with depth.
    let rig = common::rig("cologne_5wall");
    let wall = rig.wall("front").unwrap();
    let left_eye = lv.eye().unwrap();
    let e = (rv.eye().unwrap() - left_eye).length();
    let d = wall.screen.extents(left_eye).unwrap().distance;
    let s = 400.0 / wall.screen.width();
    let g = plan.g(glam::DVec2::ZERO).x;
    let shift = |z: f64| e * (1.0 - d / z) * s;
    let (near, far) = (plan.lambda[0] * g, plan.lambda[1] * g);
    assert!(near < far, "{plan:?}");
    // The farthest visible point is the box's far face, the nearest the
    // first depth at which the box enters the wall's frustum.
    let half = 0.5 * rig.scene.size;
    let z_far = (rig.scene.centre - left_eye).dot(-wall.screen.normal()) + half;
    assert!(
        (far - shift(z_far)).abs() < 0.01,
        "{far} vs {}",
        shift(z_far)
    );
    let exact = ((far.round() - near.round()) as u32) + 1;
    assert_eq!(plan.layers, exact);
    assert_eq!(model_collisions(&plan, plan.layers), 0);
    assert!(model_collisions(&plan, plan.layers - 1) > 0);
    model_reads_cover(&plan).unwrap();
}

#[test]
fn every_wall_and_head_pose_plans_without_shared_texels() {
    // Level, turned to either side wall, rolled, looking at the floor,
    // and the eyes swapped.
    let poses = [
        (DVec3::ZERO, false),
        (DVec3::new(90.0, 0.0, 0.0), false),
        (DVec3::new(-90.0, 0.0, 0.0), false),
        (DVec3::new(30.0, 0.0, 15.0), false),
        (DVec3::new(0.0, -60.0, -15.0), false),
        (DVec3::new(20.0, 10.0, 5.0), true),
    ];
    let (mut planned, mut two_families) = (0, 0);
    for (ypr, swapped) in poses {
        for wall in ["front", "left", "right", "floor", "ceiling"] {
            let (plan, _, _) = cave_pair(wall, ypr, 64, swapped);
            let plan = match plan {
                Ok(plan) => plan,
                // Walls behind the head see nothing of the volume.
                Err(NotEpipolar::Behind) => continue,
                Err(e) => panic!("{wall} at {ypr}: {e}"),
            };
            planned += 1;
            let what = format!("{wall} at {ypr} (swapped: {swapped}): {plan:?}");
            assert_eq!(model_collisions(&plan, plan.layers), 0, "{what}");
            model_reads_cover(&plan).unwrap_or_else(|e| panic!("{what}: {e}"));
            // The bound is not wasteful: the fewest layers that share no
            // texel are at least half of it.
            let fewest = (1..=plan.layers)
                .find(|&l| model_collisions(&plan, l) == 0)
                .unwrap();
            assert!(plan.layers <= 2 * fewest, "{what}: {fewest} would do");
            if plan.families == [true, true] {
                two_families += 1;
            }
        }
    }
    // Every wall of every pose here sees the volume, and radial lines
    // (both families) are common: the side walls of a level head.
    assert_eq!(planned, 30);
    assert!(two_families >= 10, "{two_families}");
}

#[test]
fn image_planes_that_are_not_parallel_fall_back() {
    let (plan, l, r) = cave_pair("front", DVec3::ZERO, 64, false);
    plan.unwrap();
    // Toe-in: the right eye's view turned by 5 degrees about the vertical.
    let turned = MatrixCamera::new(DMat4::from_rotation_y(0.087) * r.view(), r.proj()).unwrap();
    let rig = common::rig("cologne_5wall");
    let half = DVec3::splat(0.5 * rig.scene.size);
    let bounds = Bounds::Box {
        lo: rig.scene.centre - half,
        hi: rig.scene.centre + half,
    };
    let why = plan_views(&l, &turned, 64, 64, bounds).unwrap_err();
    assert!(
        matches!(why, NotEpipolar::OffLine(_) | NotEpipolar::UnevenShift(_)),
        "{why}"
    );
    assert!(why.to_string().contains("pixels"), "{why}");
}

#[test]
fn a_volume_around_the_eyes_is_refused_with_the_reason() {
    use anari_library_caveray::render::stereo::{LayerFormat, Reprojection, ReprojectionError};
    let rig = common::rig("cologne_5wall");
    let walk = rig
        .load_head_path(&common::config_dir().join("head_paths/cologne_walk.toml"))
        .unwrap();
    // A 2.6 m volume the walk stays inside of.
    let half = DVec3::splat(1300.0);
    let centre = DVec3::new(0.0, 500.0, -300.0);
    let bounds = Bounds::Box {
        lo: centre - half,
        hi: centre + half,
    };
    let mut reasons = std::collections::BTreeSet::new();
    for key in &walk {
        for wall in &rig.walls {
            let view = |eye| {
                rig.view(wall, eye, &key.pose)
                    .unwrap()
                    .matrix_camera()
                    .unwrap()
            };
            let size = UVec2::splat(64);
            match Reprojection::new(
                &view(Eye::Left),
                &view(Eye::Right),
                size,
                bounds,
                None,
                LayerFormat::Rgba16F,
            ) {
                Ok(r) => {
                    // What is accepted casts at most twice the image.
                    assert!(r.plan.cast.x * r.plan.cast.y <= 2 * 64 * 64, "{:?}", r.plan)
                }
                Err(ReprojectionError::Costlier { cast, size: s }) => {
                    assert!(cast.x * cast.y > 2 * s.x * s.y);
                    reasons.insert("costlier");
                }
                Err(ReprojectionError::NotEpipolar(NotEpipolar::BetweenEyes)) => {
                    reasons.insert("between");
                }
                Err(ReprojectionError::NotEpipolar(NotEpipolar::TooClose(scale))) => {
                    assert!(scale > 2.0, "{scale}");
                    reasons.insert("close");
                }
                Err(e) => panic!("{} at t = {}: {e}", wall.name, key.time),
            }
        }
    }
    // Each way of being too close occurs on this walk.
    assert_eq!(
        reasons.into_iter().collect::<Vec<_>>(),
        ["between", "close", "costlier"]
    );
}
