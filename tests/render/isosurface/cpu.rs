//! Isosurface ray casting, the CPU reference: on a ball of
//! known radius the first crossing lies on the sphere, the normals are
//! radial, the principal curvatures are 1/radius from the tricubic
//! B-spline's Hessian, the secant steps put the hit far closer than the
//! march's step, the B-spline reproduces linear fields, curvature coloring
//! tells a convex view from a concave one, rays march only inside the box
//! where the field can cross the iso-value, and bad settings fail.

use crate::common;
use std::sync::atomic::AtomicBool;

use anari_library_caveray::geometry::{ImageRegion, PinholeCamera, PrimaryRays, RayGen};
use anari_library_caveray::render::iso::{
    cast, crossing_box, curvature_color, Coloring, IsoField, IsoFilter, IsoSettings,
};
use anari_library_caveray::render::{ColorFormat, FrameDesc};
use anari_library_caveray::scene::{PlacedVolume, Voxels};
use glam::{DVec3, Mat4, UVec2, Vec3};

const N: u32 = 48;
const SIZE: UVec2 = UVec2::new(40, 40);

/// A field on [-1, 1]^3 of N^3 voxels, unplaced.
fn field(f: impl Fn(Vec3) -> f32) -> PlacedVolume {
    common::iso::field(N, Mat4::IDENTITY, f)
}

/// A ball of radius 0.5 where the field is 0.5 (high inside).
fn ball() -> PlacedVolume {
    field(|p| 1.0 - p.length())
}

fn camera(eye: DVec3) -> RayGen {
    PinholeCamera::new(eye, -eye, DVec3::Y, 0.5, 1.0, ImageRegion::FULL)
        .unwrap()
        .ray_gen(SIZE)
}

#[test]
fn hits_lie_on_the_sphere_with_radial_normals_and_its_curvature() {
    let ball = ball();
    let rays = camera(DVec3::new(0.3, 0.2, 3.0));
    for filter in [IsoFilter::Trilinear, IsoFilter::TricubicBSpline] {
        let settings = IsoSettings {
            filter,
            ..IsoSettings::new(0.5)
        };
        let (_, hits) = cast(&ball, &rays, &FrameDesc::new(SIZE), &settings).unwrap();
        let hits: Vec<_> = hits.iter().flatten().collect();
        assert!(
            hits.len() > 200,
            "{}: only {} hits",
            filter.name(),
            hits.len()
        );
        for h in &hits {
            let r = h.position.length();
            assert!(
                (r - 0.5).abs() < 4e-3,
                "{}: hit at radius {r}",
                filter.name()
            );
            let radial = h.position.normalize();
            assert!(
                h.normal.dot(radial) > 0.999,
                "{}: normal {} at {}",
                filter.name(),
                h.normal,
                h.position
            );
        }
        if filter == IsoFilter::TricubicBSpline {
            // Away from the silhouette, where the B-spline is well inside
            // its support: both curvatures 1/0.5.
            let facing: Vec<_> = hits.iter().filter(|h| h.normal.z > 0.6).collect();
            assert!(facing.len() > 50);
            for h in facing {
                let (k1, k2) = h.curvatures;
                assert!(
                    (k1 - 2.0).abs() < 0.1 && (k2 - 2.0).abs() < 0.1,
                    "curvatures {k1}, {k2}"
                );
            }
        }
    }
}

#[test]
fn secant_steps_put_the_hit_far_closer_than_the_march_step() {
    let ball = ball();
    let rays = camera(DVec3::new(0.0, 0.0, 3.0));
    let error = |secant_steps| {
        let settings = IsoSettings {
            filter: IsoFilter::Trilinear,
            steps_per_cell: 0.5,
            secant_steps,
            ..IsoSettings::new(0.5)
        };
        let (_, hits) = cast(&ball, &rays, &FrameDesc::new(SIZE), &settings).unwrap();
        hits.iter()
            .flatten()
            .map(|h| (h.position.length() - 0.5).abs())
            .fold(0.0f32, f32::max)
    };
    let (coarse, refined) = (error(0), error(6));
    // A step here is two cells (0.085); one secant step already lands
    // within the cell, six within a fraction of a percent of it.
    assert!(refined < 3e-3, "refined error {refined}");
    assert!(
        refined < coarse / 4.0,
        "refined {refined} vs one secant {coarse}"
    );
}

#[test]
fn the_bspline_reproduces_linear_fields_and_their_gradient() {
    let linear = field(|p| 0.3 * p.x - 0.2 * p.y + 0.7 * p.z + 0.1);
    let voxels = match linear.volume.structured().unwrap().voxels() {
        Voxels::F32(v) => v.clone(),
        _ => unreachable!(),
    };
    let f = IsoField::new(&linear, &voxels, IsoFilter::TricubicBSpline);
    for p in [
        Vec3::new(0.1, -0.3, 0.25),
        Vec3::new(-0.6, 0.55, 0.0),
        Vec3::ZERO,
    ] {
        let s = f.sample(f.grid(p));
        let want = 0.3 * p.x - 0.2 * p.y + 0.7 * p.z + 0.1;
        assert!((s.value - want).abs() < 1e-5, "{p}: {} vs {want}", s.value);
        assert!(
            (s.gradient - Vec3::new(0.3, -0.2, 0.7)).length() < 1e-4,
            "{}",
            s.gradient
        );
        assert!(s.hessian.to_cols_array().iter().all(|x| x.abs() < 1e-3));
    }
}

#[test]
fn curvature_coloring_tells_convex_from_concave() {
    let ball = ball();
    let settings = IsoSettings {
        coloring: Coloring::Curvature { radius: 0.5 },
        ambient: 1.0,
        diffuse: 0.0,
        specular: 0.0,
        ..IsoSettings::new(0.5)
    };
    let desc = FrameDesc::new(SIZE).with_color(ColorFormat::Rgba32F);
    // From outside the ball bulges towards the eye; from inside, the same
    // surface curves away (the normal faces the eye, so its curvature flips).
    let outside = cast(&ball, &camera(DVec3::new(0.0, 0.0, 3.0)), &desc, &settings).unwrap();
    let inside = cast(&ball, &camera(DVec3::new(0.0, 0.0, 0.1)), &desc, &settings).unwrap();
    let centre = |f: &anari_library_caveray::render::Frame| f.pixel(SIZE.x / 2, SIZE.y / 2);
    let (o, i) = (centre(&outside.0), centre(&inside.0));
    assert!(o.x > o.z + 0.3, "convex is orange, got {o}");
    assert!(i.z > i.x + 0.3, "concave is blue, got {i}");
    assert_eq!(curvature_color(0.0, 1.0), Vec3::splat(0.95));
}

#[test]
fn rays_that_miss_show_the_background_and_bad_settings_fail() {
    let ball = ball();
    let rays = camera(DVec3::new(0.0, 0.0, 3.0));
    let desc = FrameDesc::new(SIZE).with_depth();
    // Above every value: nothing to hit.
    let (frame, hits) = cast(&ball, &rays, &desc, &IsoSettings::new(5.0)).unwrap();
    assert!(hits.iter().all(Option::is_none));
    assert!(frame.depth.unwrap().iter().all(|d| d.is_infinite()));
    for (settings, want) in [
        (IsoSettings::new(f32::NAN), "iso-value must be finite"),
        (
            IsoSettings {
                steps_per_cell: 0.0,
                ..IsoSettings::new(0.5)
            },
            "steps per cell",
        ),
        (
            IsoSettings {
                secant_steps: 100,
                ..IsoSettings::new(0.5)
            },
            "at most 64 secant steps",
        ),
        (
            IsoSettings {
                light: Some(Vec3::ZERO),
                ..IsoSettings::new(0.5)
            },
            "light direction",
        ),
        (
            IsoSettings {
                coloring: Coloring::Curvature { radius: -1.0 },
                ..IsoSettings::new(0.5)
            },
            "curvature radius",
        ),
    ] {
        let e = cast(&ball, &rays, &desc, &settings).unwrap_err();
        assert!(e.to_string().contains(want), "{e}");
    }
}

#[test]
fn the_crossing_box_holds_the_surface_and_nothing_far_from_it() {
    let placed = ball();
    let v = placed.volume.structured().unwrap();
    let value = |i| v.value(i);
    // The ball of radius 0.5 is 0.5 * 47 / 2 = 11.75 cells around the
    // grid's centre, 23.5: from 11.75 to 35.25 on each axis.
    for (filter, reach) in [
        (IsoFilter::Trilinear, 1.0),
        (IsoFilter::TricubicBSpline, 2.0),
    ] {
        let (lo, hi) = crossing_box(v.dims(), value, 0.5, filter);
        for axis in 0..3 {
            assert!(
                lo[axis] <= 11.75 && hi[axis] >= 35.25,
                "{filter:?}: {lo} {hi}"
            );
            assert!(
                lo[axis] >= 11.0 - reach && hi[axis] <= 36.0 + reach,
                "{filter:?}: {lo} {hi} is wider than the ball and the filter's reach"
            );
        }
    }
    // A value the field never takes: no box, and every ray misses.
    let (lo, hi) = crossing_box(v.dims(), value, 2.0, IsoFilter::Trilinear);
    assert!(lo.cmpgt(hi).any(), "{lo} {hi}");
    let (_, hits) = cast(
        &placed,
        &camera(DVec3::new(0.0, 0.0, 3.0)),
        &FrameDesc::new(SIZE),
        &IsoSettings::new(2.0),
    )
    .unwrap();
    assert!(hits.iter().all(Option::is_none));
}

#[test]
fn the_cpu_renderer_keeps_a_fields_values_and_boxes_and_draws_as_the_caster() {
    use anari_library_caveray::render::iso::IsoSurface;
    use anari_library_caveray::render::{Backend, Renderer};
    let mut r = Renderer::new(Backend::Cpu).unwrap();
    let rays = camera(DVec3::new(0.3, 0.2, 3.0));
    let desc = FrameDesc::new(SIZE).with_depth();
    let (ball, other) = (
        ball(),
        field(|p| 1.0 - (p - Vec3::new(0.2, 0.0, 0.0)).length()),
    );
    // Iso-values and volumes change and come back: each frame is the
    // caster's own, not a kept box or field of another.
    for (placed, isovalue) in [(&ball, 0.5), (&ball, 0.3), (&other, 0.5), (&ball, 0.5)] {
        let settings = IsoSettings::new(isovalue);
        let surface = IsoSurface {
            placed: placed.clone(),
            settings,
        };
        let kept = r
            .cast_surfaces(&[surface], &rays, &desc, &AtomicBool::new(false))
            .unwrap();
        let (fresh, _) = cast(placed, &rays, &desc, &settings).unwrap();
        assert_eq!(kept.color, fresh.color, "iso-value {isovalue}");
        assert_eq!(kept.depth, fresh.depth, "iso-value {isovalue}");
    }
}
