//! Placing things in the world: the affine transforms volumes and
//! surfaces take, the boxes around what they place, and the numbers hosts tell the
//! placed things apart by.

use glam::{Mat4, Vec3, Vec4};

/// Why `transform` cannot place anything, if it cannot: it must be finite,
/// affine and invertible.
pub fn check_affine(transform: Mat4) -> Result<(), &'static str> {
    if !transform.is_finite() {
        return Err("is not finite");
    }
    let bottom = transform.row(3) - Vec4::W;
    if bottom.abs().max_element() > 1e-6 {
        return Err("is projective; a volume's transform must be affine");
    }
    let linear = transform.as_dmat4();
    let scale = [linear.x_axis, linear.y_axis, linear.z_axis]
        .iter()
        .map(|c| c.truncate().length())
        .fold(0.0, f64::max);
    let det = glam::DMat3::from_mat4(linear).determinant();
    if det.abs() <= 1e-9 * scale.powi(3) || scale == 0.0 {
        return Err("is singular: it flattens the volume");
    }
    Ok(())
}

/// The box around box `(lo, hi)`'s corners under affine `transform`.
pub fn transformed_box(transform: Mat4, (lo, hi): (Vec3, Vec3)) -> (Vec3, Vec3) {
    (0..8)
        .map(|i| {
            let pick = |bit: u32, a: f32, b: f32| if i & bit == 0 { a } else { b };
            transform.transform_point3(Vec3::new(
                pick(1, lo.x, hi.x),
                pick(2, lo.y, hi.y),
                pick(4, lo.z, hi.z),
            ))
        })
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), p| {
            (l.min(p), h.max(p))
        })
}

/// The numbers a host gave an object and the instance that placed it,
/// which the frame's objectId and instanceId channels report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ObjectIds {
    pub object: u32,
    pub instance: u32,
}

impl ObjectIds {
    /// What ANARI reports for an object or instance given no `id`, and
    /// where nothing was hit.
    pub const NONE: Self = Self {
        object: u32::MAX,
        instance: u32::MAX,
    };
}
