//! The invariants of docs/off_axis.md, on every wall and eye of every
//! shipped rig, for 200 random tracked head poses each (fixed seed).
//! Tolerances: f64 results to 1e-9 (lengths relative to the rig's size,
//! unit directions and image coordinates absolute); single-precision
//! paths (f32 matrices from a GL host, the f32 RayGen) to 1e-5.

use crate::common;

use anari_library_caveray::cave::{Eye, Rig, View};
use anari_library_caveray::geometry::{
    pinhole_from_matrices, MatrixCamera, PrimaryRays, Ray, Screen,
};
use common::{random_head, rig_scale, shipped_rigs, Rng};
use glam::{DVec2, DVec3, UVec2};

const POSES: usize = 200;
const F64_TOL: f64 = 1e-9;
const F32_TOL: f64 = 1e-5;

/// Pixels checked per view: a 9 x 9 grid including the image's edges.
fn sample_pixels(size: UVec2) -> Vec<UVec2> {
    let pick = |i: u32, len: u32| (u64::from(i) * u64::from(len - 1) / 8) as u32;
    (0..9)
        .flat_map(|j| (0..9).map(move |i| UVec2::new(pick(i, size.x), pick(j, size.y))))
        .collect()
}

/// Two rays describe the same line (direction and position).
fn assert_same_line(a: &Ray, b: &Ray, dir_tol: f64, len_tol: f64, what: &str) {
    let (da, db) = (a.direction.normalize(), b.direction.normalize());
    assert!(
        (da - db).length() <= dir_tol,
        "{what}: directions {da} vs {db}"
    );
    let off = a.distance_to_point(b.origin);
    assert!(
        off <= len_tol,
        "{what}: lines are {off} apart (tolerance {len_tol})"
    );
}

fn check_view(rig: &Rig, view: &View, context: &str) {
    let scale = rig_scale(rig);
    let len_tol = F64_TOL * scale;
    let screen = view.camera.screen();
    let matrix = view
        .matrix_camera()
        .unwrap_or_else(|e| panic!("{context}: {e}"));
    let pinhole = view.pinhole().unwrap_or_else(|e| panic!("{context}: {e}"));
    let recovered = view
        .pinhole_from_matrices()
        .unwrap_or_else(|e| panic!("{context}: {e}"));
    let cams: [(&str, &dyn PrimaryRays); 4] = [
        ("offAxis", &view.camera),
        ("matrix", &matrix),
        ("pinhole", &pinhole),
        ("from-matrices", &recovered.camera),
    ];

    // Corner rays pass through the wall's corners.
    let image_corners = [DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    for (name, cam) in cams {
        for (s, corner) in image_corners.iter().zip(screen.corners()) {
            let d = cam.ray_through(*s).distance_to_point(corner);
            assert!(
                d <= len_tol,
                "{context}: {name} corner ray {s} misses {corner} by {d}"
            );
        }
    }

    // Every generator gives the same ray line per pixel; strategy-1 rays
    // pass through the eye.
    for p in sample_pixels(view.resolution) {
        let reference = view.camera.pixel_ray(p.x, p.y, view.resolution);
        for (name, cam) in &cams[1..] {
            let r = cam.pixel_ray(p.x, p.y, view.resolution);
            assert_same_line(
                &reference,
                &r,
                F64_TOL,
                len_tol,
                &format!("{context} pixel {p} {name}"),
            );
        }
        let m = matrix.pixel_ray(p.x, p.y, view.resolution);
        let miss = m.distance_to_point(view.eye_position);
        assert!(
            miss <= len_tol,
            "{context}: matrix ray of {p} misses the eye by {miss}"
        );
    }

    // Strategy 3 recovers the eye, and its far-plane corners are the wall's
    // corners seen from the eye.
    let err = (recovered.eye - view.eye_position).length();
    assert!(err <= len_tol, "{context}: recovered eye off by {err}");
    for (far, corner) in recovered.corners.iter().zip(screen.corners()) {
        let towards = Ray {
            origin: view.eye_position,
            direction: corner - view.eye_position,
        };
        let off = towards.distance_to_point(*far) / (*far - view.eye_position).length();
        assert!(
            off <= F64_TOL,
            "{context}: far corner {far} is {off} off the eye-corner line"
        );
        assert!((*far - view.eye_position).length() > (corner - view.eye_position).length());
    }

    // The image region is inside [0,1]^2 and touches an edge on each axis.
    for (name, cam) in [("pinhole", &pinhole), ("from-matrices", &recovered.camera)] {
        let r = cam.image_region();
        let [x0, y0, x1, y1] = r.to_array();
        for v in [x0, y0, x1, y1] {
            assert!(
                (-F64_TOL..=1.0 + F64_TOL).contains(&v),
                "{context}: {name} region {r:?}"
            );
        }
        assert!(
            x0 < x1 && y0 < y1,
            "{context}: {name} region {r:?} is empty"
        );
        let touches = |lo: f64, hi: f64| lo.abs() <= F64_TOL || (hi - 1.0).abs() <= F64_TOL;
        assert!(
            touches(x0, x1) && touches(y0, y1),
            "{context}: {name} region {r:?} touches no edge"
        );
        assert!(cam.fovy() > 0.0 && cam.fovy() < std::f64::consts::PI && cam.aspect() > 0.0);
    }

    // Single precision: f32 matrices as a GL host hands them over, and the
    // f32 RayGen every renderer consumes.
    let from_f32 = MatrixCamera::from_f32(
        view.projection.view.as_mat4(),
        view.projection.proj.as_mat4(),
    )
    .unwrap_or_else(|e| panic!("{context}: f32 matrices: {e}"));
    let recovered_f32 = pinhole_from_matrices(from_f32.view(), from_f32.proj())
        .unwrap_or_else(|e| panic!("{context}: f32 strategy 3: {e}"));
    let eye_err = (recovered_f32.eye - view.eye_position).length();
    assert!(
        eye_err <= F32_TOL * scale,
        "{context}: f32 recovered eye off by {eye_err}"
    );
    for p in sample_pixels(view.resolution) {
        let reference = view.camera.pixel_ray(p.x, p.y, view.resolution);
        let r = from_f32.pixel_ray(p.x, p.y, view.resolution);
        assert_same_line(
            &reference,
            &r,
            F32_TOL,
            F32_TOL * scale,
            &format!("{context} f32 matrices {p}"),
        );
        for (name, cam) in cams {
            let (o, d) = cam.ray_gen(view.resolution).pixel_ray(p.x, p.y);
            let r = Ray {
                origin: o.as_dvec3(),
                direction: d.as_dvec3(),
            };
            assert_same_line(
                &reference,
                &r,
                F32_TOL,
                F32_TOL * scale,
                &format!("{context} {name} RayGen {p}"),
            );
        }
    }
}

#[test]
fn every_strategy_agrees_on_every_wall_of_every_rig() {
    let rigs = shipped_rigs();
    let stems: Vec<&str> = rigs.iter().map(|(s, _)| s.as_str()).collect();
    for expected in [
        "cave_4wall_3m",
        "cologne_5wall",
        "fishtank_desktop",
        "powerwall",
    ] {
        assert!(stems.contains(&expected), "missing rig {expected}");
    }
    let mut rng = Rng::new(0x00CA_7E5A);
    for (stem, rig) in &rigs {
        let mut checked = 0;
        for pose in 0..POSES {
            let head = random_head(rig, &mut rng);
            for (wall, eye, view) in rig.views(&head) {
                let context = format!("{stem} pose {pose} {} {eye}", wall.name);
                let view = view.unwrap_or_else(|e| panic!("{context}: {e}"));
                check_view(rig, &view, &context);
                checked += 1;
            }
        }
        let per_pose: usize = rig.walls.iter().map(|w| w.eyes.len()).sum();
        assert_eq!(checked, POSES * per_pose, "{stem}");
    }
}

#[test]
fn a_point_on_the_wall_lands_on_the_same_pixel_for_both_eyes() {
    let mut rng = Rng::new(7);
    for (stem, rig) in shipped_rigs() {
        for _ in 0..POSES {
            let head = random_head(&rig, &mut rng);
            for wall in &rig.walls {
                let left = rig.view(wall, Eye::Left, &head).unwrap();
                let right = rig.view(wall, Eye::Right, &head).unwrap();
                let s = DVec2::new(rng.uniform(0.0, 1.0), rng.uniform(0.0, 1.0));
                let p = wall.screen.point(s);
                for view in [&left, &right] {
                    let ndc = MatrixCamera::new(view.projection.view, view.projection.proj)
                        .unwrap()
                        .project(p);
                    let got = 0.5 * (ndc.truncate() + DVec2::ONE);
                    assert!(
                        (got - s).length() <= F64_TOL,
                        "{stem} {}: {s} -> {got}",
                        wall.name
                    );
                }
            }
        }
    }
}

/// gluPerspective, written out independently of the library.
fn glu_perspective(fovy: f64, aspect: f64, near: f64, far: f64) -> [f64; 16] {
    let f = 1.0 / (fovy / 2.0).tan();
    [
        f / aspect,
        0.0,
        0.0,
        0.0,
        0.0,
        f,
        0.0,
        0.0,
        0.0,
        0.0,
        (far + near) / (near - far),
        -1.0,
        0.0,
        0.0,
        2.0 * far * near / (near - far),
        0.0,
    ]
}

/// gluLookAt, written out independently of the library.
fn glu_look_at(eye: DVec3, centre: DVec3, up: DVec3) -> [f64; 16] {
    let f = (centre - eye).normalize();
    let s = f.cross(up).normalize();
    let u = s.cross(f);
    [
        s.x,
        u.x,
        -f.x,
        0.0,
        s.y,
        u.y,
        -f.y,
        0.0,
        s.z,
        u.z,
        -f.z,
        0.0,
        -s.dot(eye),
        -u.dot(eye),
        f.dot(eye),
        1.0,
    ]
}

fn assert_close(a: &[f64; 16], b: &[f64; 16], tol: f64, what: &str) {
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= tol * x.abs().max(y.abs()).max(1.0),
            "{what}[{i}]: {x} vs {y}"
        );
    }
}

#[test]
fn an_eye_on_the_centre_normal_is_a_plain_symmetric_perspective() {
    for (stem, rig) in shipped_rigs() {
        for wall in &rig.walls {
            let s = &wall.screen;
            let eye = s.centre() + 0.4 * s.width() * s.normal();
            let cam = anari_library_caveray::geometry::OffAxisCamera::new(*s, eye).unwrap();
            let pinhole =
                anari_library_caveray::geometry::PinholeCamera::from_screen(s, eye).unwrap();
            let region = pinhole.image_region().to_array();
            for (got, want) in region.iter().zip([0.0, 0.0, 1.0, 1.0]) {
                assert!(
                    (got - want).abs() <= 1e-12,
                    "{stem} {}: region {region:?}",
                    wall.name
                );
            }
            let aspect = s.width() / s.height();
            assert!((pinhole.aspect() - aspect).abs() <= 1e-12);
            let fovy = 2.0 * (0.5 * s.height() / (0.4 * s.width())).atan();
            assert!((pinhole.fovy() - fovy).abs() <= 1e-12);
            let m = cam.projection(rig.near, rig.far).unwrap();
            let what = format!("{stem} {}", wall.name);
            assert_close(
                &m.proj.to_cols_array(),
                &glu_perspective(fovy, aspect, rig.near, rig.far),
                F64_TOL,
                &what,
            );
            let look = glu_look_at(eye, eye - s.normal(), s.y_axis());
            assert_close(&m.view.to_cols_array(), &look, F64_TOL, &what);
        }
    }
}

/// The view matrix built from *columns* X, Y, Z and translation -E, found
/// in public sample code. It is only right for axis-aligned walls.
fn column_form_view(s: &Screen, eye: DVec3) -> glam::DMat4 {
    glam::DMat4::from_cols(
        s.x_axis().extend(0.0),
        s.y_axis().extend(0.0),
        s.normal().extend(0.0),
        (-eye).extend(1.0),
    )
}

fn corner_rays_hit_corners(view: glam::DMat4, proj: glam::DMat4, s: &Screen, tol: f64) -> bool {
    let Ok(cam) = MatrixCamera::new(view, proj) else {
        return false;
    };
    [DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y]
        .iter()
        .zip(s.corners())
        .all(|(st, c)| cam.ray_through(*st).distance_to_point(c) <= tol)
}

#[test]
fn the_column_form_view_matrix_is_caught_on_side_walls() {
    for stem in ["cologne_5wall", "cave_4wall_3m"] {
        let rig = common::rig(stem);
        let head = rig.head_pose(None, None);
        let tol = F64_TOL * rig_scale(&rig);
        for wall in &rig.walls {
            let view = rig.view(wall, Eye::Left, &head).unwrap();
            let proj = view.projection.proj;
            assert!(corner_rays_hit_corners(
                view.projection.view,
                proj,
                &wall.screen,
                tol
            ));
            let wrong = column_form_view(&wall.screen, view.eye_position);
            let axis_aligned = wrong == view.projection.view;
            if matches!(wall.name.as_str(), "left" | "right") {
                assert!(
                    !axis_aligned,
                    "{stem} {} must not be axis-aligned",
                    wall.name
                );
            }
            // The invariant tells the wrong matrix apart wherever it differs.
            assert_eq!(
                corner_rays_hit_corners(wrong, proj, &wall.screen, tol),
                axis_aligned,
                "{stem} {}",
                wall.name
            );
        }
    }
}

#[test]
fn eyes_outside_the_walls_extent_still_work() {
    let rig = common::rig("powerwall");
    let wall = &rig.walls[0];
    let tol = F64_TOL * rig_scale(&rig);
    // Far left of the wall, below its lower edge, and above its upper edge.
    for head in [
        DVec3::new(-5.0, 1.7, 1.0),
        DVec3::new(3.0, 0.1, 0.5),
        DVec3::new(0.5, 4.0, 2.0),
    ] {
        let pose = rig.head_pose(Some(head), None);
        let extents = wall
            .screen
            .extents(rig.eye_position(&pose, Eye::Left))
            .unwrap();
        assert!(
            extents.left < 0.0 || extents.right < 0.0 || extents.bottom < 0.0 || extents.top < 0.0
        );
        for eye in [Eye::Left, Eye::Right] {
            let view = rig.view(wall, eye, &pose).unwrap();
            check_view(&rig, &view, &format!("powerwall head {head} {eye}"));
            let pinhole = view.pinhole().unwrap();
            assert!(corner_rays_hit_corners(
                view.projection.view,
                view.projection.proj,
                &wall.screen,
                tol
            ));
            assert!(pinhole.image_region().to_array() != [0.0, 0.0, 1.0, 1.0]);
        }
    }
}

#[test]
fn zero_ipd_gives_identical_eyes() {
    let mut rig = common::rig("cologne_5wall");
    rig.viewer.ipd = 0.0;
    let mut rng = Rng::new(3);
    for _ in 0..20 {
        let head = random_head(&rig, &mut rng);
        for wall in &rig.walls {
            let l = rig.view(wall, Eye::Left, &head).unwrap();
            let r = rig.view(wall, Eye::Right, &head).unwrap();
            assert_eq!(l.eye_position, r.eye_position);
            assert_eq!(l.projection, r.projection);
        }
    }
}
