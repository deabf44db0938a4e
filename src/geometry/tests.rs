//! Degenerate input gives an error that says what is wrong, never NaN.

use crate::geometry::{
    frustum, pinhole_from_matrices, GeometryError, ImageRegion, MatrixCamera, OffAxisCamera,
    OffAxisProjection, PinholeCamera, Screen,
};
use glam::{DMat4, DVec2, DVec3};

fn wall() -> Screen {
    Screen::new(
        DVec3::new(-1.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(1.0, 1.5, 0.0),
    )
    .unwrap()
}

fn good_matrices() -> (DMat4, DMat4) {
    let m = OffAxisProjection::new(&wall(), DVec3::new(0.2, 0.8, 1.3), 0.05, 100.0).unwrap();
    (m.view, m.proj)
}

#[test]
fn eye_on_or_behind_the_wall_is_an_error_for_every_camera() {
    let s = wall();
    for (eye, d) in [
        (DVec3::new(0.0, 0.5, 0.0), 0.0),
        (DVec3::new(0.3, 0.5, -2.0), -2.0),
    ] {
        let expected = GeometryError::EyeBehindWall { d };
        assert_eq!(OffAxisCamera::new(s, eye).unwrap_err(), expected);
        assert_eq!(PinholeCamera::from_screen(&s, eye).unwrap_err(), expected);
        assert_eq!(
            OffAxisProjection::new(&s, eye, 0.1, 10.0).unwrap_err(),
            expected
        );
        assert!(
            expected.to_string().contains("on or behind the wall"),
            "{expected}"
        );
    }
}

#[test]
fn degenerate_walls_are_rejected_with_the_reason() {
    let (a, b) = (DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0));
    let err = Screen::new(a, a, DVec3::Y).unwrap_err();
    assert!(
        matches!(err, GeometryError::ZeroAreaWall { width, .. } if width == 0.0),
        "{err}"
    );
    assert!(err.to_string().contains("zero area"));
    let err = Screen::new(a, b, b).unwrap_err();
    assert!(
        matches!(err, GeometryError::ZeroAreaWall { height, .. } if height == 0.0),
        "{err}"
    );

    let err = Screen::new(a, b, DVec3::new(2.5, 1.0, 0.0)).unwrap_err();
    let GeometryError::NotRectangular { angle_deg } = err else {
        panic!("{err}")
    };
    assert!((angle_deg - 63.4349).abs() < 1e-3, "{angle_deg}");
    assert!(err.to_string().contains("not a rectangle"));

    let ur = DVec3::new(2.0, 1.0, 0.0);
    let err = Screen::with_upper_left(a, b, ur, DVec3::new(0.0, 1.0, 0.25)).unwrap_err();
    assert_eq!(err, GeometryError::NotPlanar { distance: 0.25 });
    assert!(err.to_string().contains("not a planar rectangle"));
    assert!(Screen::with_upper_left(a, b, ur, DVec3::new(0.0, 1.0, 0.0)).is_ok());

    let err = Screen::new(DVec3::new(f64::NAN, 0.0, 0.0), b, ur).unwrap_err();
    assert_eq!(
        err,
        GeometryError::NonFinite {
            what: "wall corner"
        }
    );
    let err = OffAxisCamera::new(wall(), DVec3::new(0.0, f64::INFINITY, 1.0)).unwrap_err();
    assert_eq!(
        err,
        GeometryError::NonFinite {
            what: "eye position"
        }
    );
}

#[test]
fn clip_planes_must_be_ordered() {
    let eye = DVec3::new(0.0, 0.5, 1.0);
    for (near, far) in [(0.0, 1.0), (-1.0, 1.0), (2.0, 1.0), (1.0, 1.0)] {
        let err = OffAxisProjection::new(&wall(), eye, near, far).unwrap_err();
        assert_eq!(err, GeometryError::NearFar { near, far });
        assert!(err.to_string().contains("0 < near < far"));
    }
}

#[test]
fn singular_and_non_finite_matrices_are_rejected() {
    let (view, proj) = good_matrices();
    let err = MatrixCamera::new(view, DMat4::ZERO).unwrap_err();
    assert!(matches!(err, GeometryError::SingularMatrix { .. }), "{err}");
    assert!(err.to_string().contains("singular"));
    let mut flat = proj;
    flat.y_axis = flat.x_axis; // two equal columns
    assert!(matches!(
        MatrixCamera::new(view, flat).unwrap_err(),
        GeometryError::SingularMatrix { .. }
    ));
    let mut nan = view;
    nan.w_axis.x = f64::NAN;
    assert_eq!(
        MatrixCamera::new(nan, proj).unwrap_err(),
        GeometryError::NonFinite {
            what: "view matrix"
        }
    );
    assert!(matches!(
        pinhole_from_matrices(view, DMat4::ZERO).unwrap_err(),
        GeometryError::SingularMatrix { .. }
    ));
}

#[test]
fn non_perspective_matrices_are_rejected() {
    let (view, proj) = good_matrices();
    // Projective skew: clip w depends on x, so depth varies across the image.
    let mut skew = proj;
    skew.x_axis.w = 0.3;
    let err = MatrixCamera::new(view, skew).unwrap_err();
    assert!(matches!(err, GeometryError::NonPerspective { .. }), "{err}");
    assert!(
        err.to_string().contains("not a perspective frustum"),
        "{err}"
    );
    assert!(pinhole_from_matrices(view, skew).is_err());

    // Orthographic: a valid strategy-1 camera, but it has no eye to recover.
    let ortho = DMat4::from_cols_array(&[
        1.0, 0.0, 0.0, 0.0, //
        0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -0.2, 0.0, 0.0, 0.0, -1.0, 1.0,
    ]);
    let cam = MatrixCamera::new(view, ortho).unwrap();
    let r = crate::geometry::PrimaryRays::ray_through(&cam, DVec2::splat(0.5));
    assert!(r.direction.is_finite() && r.origin.is_finite());
    let err = pinhole_from_matrices(view, ortho).unwrap_err();
    assert_eq!(
        err,
        GeometryError::ParallelPlanes {
            which: "left and right"
        }
    );
    assert!(err.to_string().contains("parallel"));

    // A frustum whose far plane maps behind the eye.
    let inverted = frustum(-0.1, 0.1, -0.1, 0.1, 1.0, -1.0);
    assert!(MatrixCamera::new(view, inverted).is_err());
}

#[test]
fn invalid_pinholes_are_rejected() {
    let (p, d, u) = (DVec3::ZERO, DVec3::NEG_Z, DVec3::Y);
    let full = ImageRegion::FULL;
    let reason = |r: Result<PinholeCamera, GeometryError>| match r {
        Err(GeometryError::InvalidPinhole { reason }) => reason,
        other => panic!("expected InvalidPinhole, got {other:?}"),
    };
    for fovy in [0.0, -0.5, std::f64::consts::PI, 4.0] {
        assert!(reason(PinholeCamera::new(p, d, u, fovy, 1.0, full)).contains("fovy"));
    }
    assert!(reason(PinholeCamera::new(p, d, u, 1.0, 0.0, full)).contains("aspect"));
    assert!(reason(PinholeCamera::new(p, d, d, 1.0, 1.0, full)).contains("parallel"));
    assert!(reason(PinholeCamera::new(p, DVec3::ZERO, u, 1.0, 1.0, full)).contains("zero"));
    let empty = ImageRegion {
        min: DVec2::splat(0.5),
        max: DVec2::new(0.5, 1.0),
    };
    assert!(reason(PinholeCamera::new(p, d, u, 1.0, 1.0, empty)).contains("empty"));
    assert_eq!(
        PinholeCamera::new(p, d, u, f64::NAN, 1.0, full).unwrap_err(),
        GeometryError::NonFinite {
            what: "fovy, aspect or image region"
        }
    );
}

#[test]
fn orientation_does_not_matter_to_the_pinhole_basis() {
    // up need not be orthogonal to direction; the camera orthonormalises it.
    let tilted = PinholeCamera::new(
        DVec3::ZERO,
        DVec3::NEG_Z,
        DVec3::new(0.0, 1.0, 0.7),
        1.0,
        1.5,
        ImageRegion::FULL,
    )
    .unwrap();
    let straight = PinholeCamera::new(
        DVec3::ZERO,
        DVec3::NEG_Z,
        DVec3::Y,
        1.0,
        1.5,
        ImageRegion::FULL,
    )
    .unwrap();
    use crate::geometry::PrimaryRays;
    for s in [DVec2::ZERO, DVec2::ONE, DVec2::new(0.2, 0.9)] {
        let (a, b) = (
            tilted.ray_through(s).direction,
            straight.ray_through(s).direction,
        );
        assert!((a - b).length() < 1e-15, "{a} {b}");
    }
}
