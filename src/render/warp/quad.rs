//! The quad warp: the source image taken as a flat picture standing in
//! the scene's centre, parallel to the source's image plane, seen from the
//! target. For a head-mounted view that plane faces the old eye; for a
//! CAVE wall it is parallel to the wall, whatever the eye did.

use glam::Vec4;

use super::project::Projector;
use super::{Source, WarpSettings};
use crate::geometry::RayGen;

/// Target pixel (x, y): premultiplied color and depth.
pub(super) fn pixel(
    source: &Source,
    from: &Projector,
    target: &RayGen,
    x: u32,
    y: u32,
    settings: &WarpSettings,
) -> (Vec4, f32) {
    let (o, d) = target.pixel_ray(x, y);
    let n = from.image_normal();
    let facing = d.dot(n);
    if facing.abs() < 1e-12 {
        return (Vec4::ZERO, f32::INFINITY);
    }
    let t = (settings.focus() - o).dot(n) / facing;
    if !(t > target.t_near && t < target.t_far) {
        return (Vec4::ZERO, f32::INFINITY);
    }
    let p = o + d * t;
    let Some(seen) = from.locate(p) else {
        return (Vec4::ZERO, f32::INFINITY);
    };
    let c = source.color_at(seen.at);
    let depth = if c.w >= settings.depth_threshold {
        target.depth_at(p, t)
    } else {
        f32::INFINITY
    };
    (c, depth)
}
