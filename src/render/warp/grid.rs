//! The grid warp: a mesh over the source image, every vertex raised to
//! the first-hit depth of its pixel (or, where nothing was hit, to the
//! quad warp's plane), projected into the target and rasterised there
//! with a depth test; each covered pixel reads the source where its
//! triangle came from.

use glam::{UVec2, Vec2, Vec3, Vec4};

use super::project::Projector;
use super::{Source, WarpSettings, Warped};
use crate::geometry::Ray;
use crate::render::frame::filled;
use crate::render::RenderError;

/// A mesh vertex: where it lands in the target, how far along the target's
/// ray, and where it came from in the source (pixels).
#[derive(Clone, Copy)]
struct Vertex {
    at: Vec2,
    z: f32,
    from: Vec2,
}

pub(super) fn warp(
    source: &Source,
    from: &Projector,
    to: &Projector,
    size: UVec2,
    settings: &WarpSettings,
    late: &dyn Fn() -> bool,
) -> Result<Warped, RenderError> {
    let g = settings.grid_spacing;
    let (sw, sh) = (source.size.x, source.size.y);
    let nodes = UVec2::new((sw - 1).div_ceil(g) + 1, (sh - 1).div_ceil(g) + 1);
    let normal = from.image_normal().as_dvec3();
    let focus = settings.focus().as_dvec3();
    let mut mesh = Vec::with_capacity((nodes.x * nodes.y) as usize);
    for j in 0..nodes.y {
        for i in 0..nodes.x {
            let (x, y) = ((i * g).min(sw - 1), (j * g).min(sh - 1));
            let depth = source.depth[source.index(UVec2::new(x, y))];
            let p = if depth.is_finite() {
                Some(source.rays.point_at_depth(x, y, depth))
            } else {
                let (o, d) = source.rays.pixel_ray(x, y);
                let ray = Ray {
                    origin: o.as_dvec3(),
                    direction: d.as_dvec3(),
                };
                ray.hit_plane(focus, normal)
                    .filter(|h| (*h - ray.origin).dot(ray.direction) > 0.0)
                    .map(|h| h.as_vec3())
            };
            mesh.push(p.and_then(|p| {
                let seen = to.locate(p)?;
                Some(Vertex {
                    at: seen.at,
                    z: seen.along,
                    from: Vec2::new(x as f32 + 0.5, y as f32 + 0.5),
                })
            }));
        }
    }
    let n = size.x as usize * size.y as usize;
    let mut z = filled(n, f32::INFINITY, "the grid warp's depth buffer")?;
    let mut uv = filled(n, Vec2::NAN, "the grid warp's source positions")?;
    let node = |i: u32, j: u32| mesh[(j * nodes.x + i) as usize];
    for j in 0..nodes.y - 1 {
        if late() {
            return Err(RenderError::Stopped);
        }
        for i in 0..nodes.x - 1 {
            let (a, b, c, d) = (
                node(i, j),
                node(i + 1, j),
                node(i + 1, j + 1),
                node(i, j + 1),
            );
            for tri in [[a, b, c], [a, c, d]] {
                if let [Some(p), Some(q), Some(r)] = tri {
                    raster([p, q, r], size, &mut z, &mut uv);
                }
            }
        }
    }
    let target = to.rays();
    let mut color = filled(n, Vec4::ZERO, "the warped color")?;
    let mut depth = filled(n, f32::INFINITY, "the warped depth")?;
    for (k, (s, t)) in uv.iter().zip(&z).enumerate() {
        if s.is_nan() {
            continue;
        }
        color[k] = source.color_at(*s);
        if color[k].w >= settings.depth_threshold {
            let (x, y) = ((k % size.x as usize) as u32, (k / size.x as usize) as u32);
            let (o, d) = target.pixel_ray(x, y);
            depth[k] = target.depth_at(o + d * *t, *t);
        }
    }
    Ok(Warped { size, color, depth })
}

/// Draws one triangle into the target's depth buffer `z`, keeping the
/// source position of the nearest surface at each pixel centre it covers.
fn raster(v: [Vertex; 3], size: UVec2, z: &mut [f32], uv: &mut [Vec2]) {
    let edge = |a: Vec2, b: Vec2, p: Vec2| (b - a).perp_dot(p - a);
    let area = edge(v[0].at, v[1].at, v[2].at);
    if area.abs() < 1e-12 || !area.is_finite() {
        return;
    }
    let lo = v[0].at.min(v[1].at).min(v[2].at);
    let hi = v[0].at.max(v[1].at).max(v[2].at);
    // Pixel centres x + 0.5 within [lo, hi], clamped to the image.
    let first = (lo - Vec2::splat(0.5)).ceil().max(Vec2::ZERO);
    let last = (hi - Vec2::splat(0.5))
        .floor()
        .min(size.as_vec2() - Vec2::ONE);
    if first.x > last.x || first.y > last.y {
        return;
    }
    let w = size.x as usize;
    for y in first.y as u32..=last.y as u32 {
        for x in first.x as u32..=last.x as u32 {
            let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let b = Vec3::new(
                edge(v[1].at, v[2].at, p),
                edge(v[2].at, v[0].at, p),
                edge(v[0].at, v[1].at, p),
            ) / area;
            if b.min_element() < -1e-6 {
                continue;
            }
            let depth = b.x * v[0].z + b.y * v[1].z + b.z * v[2].z;
            let k = y as usize * w + x as usize;
            if depth > 0.0 && depth < z[k] {
                z[k] = depth;
                uv[k] = b.x * v[0].from + b.y * v[1].from + b.z * v[2].from;
            }
        }
    }
}
