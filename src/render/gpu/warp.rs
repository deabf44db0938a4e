//! The warps on the GPU (shaders/warp.wgsl): quad and layers one
//! invocation a target pixel; grid as four passes (mesh vertices, a depth
//! raster with atomics, a pick raster, the color gather). Pipelines are
//! made on the first warp; buffers grow with the largest source and
//! target seen, and a source is uploaded only when it is not the last one.

use glam::{UVec2, Vec3, Vec4};

use super::bindings::{binding_table, Kind};
use super::context::{unprepared, Context, WORKGROUP};
use super::resources::floats;
use super::shaders::compute_pipeline;
use super::uniforms::Warp;
use crate::geometry::RayGen;
use crate::render::frame::filled;
use crate::render::warp::{Projector, Source, WarpMode, WarpSettings, Warped};
use crate::render::{FrameDesc, RenderError};

/// Triangles a grid pass covers per workgroup (shaders/warp.wgsl).
const TRIANGLES_PER_GROUP: u32 = 64;

binding_table! {
    /// The warp passes' only group.
    WarpResources / WarpLayout = "warp_bindings" imports ["warp_uniforms"] () {
        w: Kind::storage("Warp"),
        /// The source: premultiplied color, first-hit depth, and
        /// `w.layers` layers a pixel as two vec4s each (color; start, end,
        /// 1 for a surface's).
        color: Kind::storage("array<vec4f>"),
        depth: Kind::storage("array<f32>"),
        layers: Kind::storage("array<vec4f>"),
        out_color: Kind::storage_rw("array<vec4f>"),
        out_depth: Kind::storage_rw("array<f32>"),
        /// The grid: the nearest surface's distance a target pixel (bits
        /// inverted, so that atomicMax keeps the nearest; 0: none), each
        /// mesh vertex where it landed in the target (x, y, distance, 1 if
        /// it landed), and each target pixel's source position.
        nearest: Kind::storage_rw("array<atomic<u32>>"),
        mesh: Kind::storage_rw("array<vec4f>"),
        from_at: Kind::storage_rw("array<vec2f>"),
    }
}

pub(super) struct WarpPass {
    layout: WarpLayout,
    quad: wgpu::ComputePipeline,
    layers: wgpu::ComputePipeline,
    nodes: wgpu::ComputePipeline,
    depth: wgpu::ComputePipeline,
    pick: wgpu::ComputePipeline,
    gather: wgpu::ComputePipeline,
    uniform: wgpu::Buffer,
    buffers: Option<Buffers>,
    /// The source the buffers hold.
    uploaded: Option<u64>,
}

/// Sizes in elements: source pixels, layers a pixel, target pixels, nodes.
#[derive(Clone, Copy, PartialEq, Eq)]
struct Capacity {
    from: u64,
    k: u64,
    to: u64,
    nodes: u64,
}

struct Buffers {
    capacity: Capacity,
    color: wgpu::Buffer,
    depth: wgpu::Buffer,
    layers: wgpu::Buffer,
    out_color: wgpu::Buffer,
    out_depth: wgpu::Buffer,
    nearest: wgpu::Buffer,
    color_read: wgpu::Buffer,
    depth_read: wgpu::Buffer,
    group: wgpu::BindGroup,
}

impl WarpPass {
    pub fn new(ctx: &Context) -> Result<Self, RenderError> {
        let device = &ctx.device;
        let layout = WarpLayout::new(device);
        let pipeline =
            |entry: &str| compute_pipeline(device, "warp", "warp", entry, &[layout.group()], &[]);
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("warp uniform"),
            size: size_of::<Warp>() as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self {
            quad: pipeline("quad")?,
            layers: pipeline("layer_march")?,
            nodes: pipeline("grid_nodes")?,
            depth: pipeline("grid_depth")?,
            pick: pipeline("grid_pick")?,
            gather: pipeline("grid_color")?,
            layout,
            uniform,
            buffers: None,
            uploaded: None,
        })
    }

    /// `source` shown from `target` (an image of `size`): the warped image
    /// and the passes' milliseconds.
    pub fn warp(
        &mut self,
        ctx: &Context,
        source: &Source,
        target: &RayGen,
        size: UVec2,
        settings: &WarpSettings,
    ) -> Result<(Warped, f64), RenderError> {
        FrameDesc::new(size).validate()?;
        settings.validate()?;
        let bad = |m: String| RenderError::Settings(m);
        if settings.mode == WarpMode::None {
            return crate::render::warp::warp(source, target, size, settings).map(|w| (w, 0.0));
        }
        if settings.mode == WarpMode::Layers && source.k == 0 {
            return Err(bad(
                "warp 'layers' needs a source rendered with layers".into()
            ));
        }
        let from = Projector::new(&source.rays).map_err(bad)?;
        let to = Projector::new(target).map_err(bad)?;
        let g = settings.grid_spacing;
        let nodes = UVec2::new(
            (source.size.x - 1).div_ceil(g) + 1,
            (source.size.y - 1).div_ceil(g) + 1,
        );
        let triangles = 2 * u64::from(nodes.x - 1) * u64::from(nodes.y - 1);
        let groups = triangles.div_ceil(u64::from(TRIANGLES_PER_GROUP));
        if groups > u64::from(ctx.limits.max_compute_workgroups_per_dimension) {
            return Err(bad(format!(
                "a grid of {triangles} triangles is more than one dispatch holds; raise the grid spacing"
            )));
        }
        let pixels = |s: UVec2| u64::from(s.x) * u64::from(s.y);
        let need = Capacity {
            from: pixels(source.size),
            k: source.k.max(1) as u64,
            to: pixels(size),
            nodes: pixels(nodes),
        };
        self.reserve(ctx, need)?;
        let buffers = self.buffers.as_ref().ok_or_else(unprepared)?;
        if self.uploaded != Some(source.generation()) {
            let queue = &ctx.queue;
            queue.write_buffer(
                &buffers.color,
                0,
                bytemuck::cast_slice(&vec4s(&source.color)),
            );
            queue.write_buffer(&buffers.depth, 0, bytemuck::cast_slice(&source.depth));
            if source.k > 0 {
                let packed: Vec<[f32; 4]> = source
                    .layers
                    .iter()
                    .flat_map(|l| {
                        let surface = if l.surface { 1.0 } else { 0.0 };
                        [l.color.to_array(), [l.start, l.end, surface, 0.0]]
                    })
                    .collect();
                queue.write_buffer(&buffers.layers, 0, bytemuck::cast_slice(&packed));
            }
            self.uploaded = Some(source.generation());
        }
        let uniform = uniform(source, &from, &to, size, nodes, settings);
        ctx.queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        let per_pixel = [size.x.div_ceil(WORKGROUP), size.y.div_ceil(WORKGROUP), 1];
        let group = [&buffers.group];
        let ms = match settings.mode {
            WarpMode::Quad => ctx.dispatch(&self.quad, &group, per_pixel)?,
            WarpMode::Layers => ctx.dispatch(&self.layers, &group, per_pixel)?,
            _ => {
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                encoder.clear_buffer(&buffers.nearest, 0, Some(4 * need.to));
                ctx.queue.submit([encoder.finish()]);
                let per_node = [nodes.x.div_ceil(WORKGROUP), nodes.y.div_ceil(WORKGROUP), 1];
                let per_triangle = [groups as u32, 1, 1];
                ctx.dispatch(&self.nodes, &group, per_node)?
                    + ctx.dispatch(&self.depth, &group, per_triangle)?
                    + ctx.dispatch(&self.pick, &group, per_triangle)?
                    + ctx.dispatch(&self.gather, &group, per_pixel)?
            }
        };
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&buffers.out_color, 0, &buffers.color_read, 0, 16 * need.to);
        encoder.copy_buffer_to_buffer(&buffers.out_depth, 0, &buffers.depth_read, 0, 4 * need.to);
        ctx.queue.submit([encoder.finish()]);
        let read = floats(&ctx.read(&buffers.color_read, 16 * need.to)?);
        let depth = floats(&ctx.read(&buffers.depth_read, 4 * need.to)?);
        ctx.check()?;
        let mut color = filled(need.to as usize, Vec4::ZERO, "the warped color")?;
        for (c, f) in color.iter_mut().zip(read.chunks_exact(4)) {
            *c = Vec4::from_slice(f);
        }
        Ok((Warped { size, color, depth }, ms))
    }

    /// Buffers for at least `need`, made anew (and the source with them)
    /// when the ones held are smaller.
    fn reserve(&mut self, ctx: &Context, need: Capacity) -> Result<(), RenderError> {
        if let Some(b) = &self.buffers {
            let c = b.capacity;
            if c.from >= need.from && c.k >= need.k && c.to >= need.to && c.nodes >= need.nodes {
                return Ok(());
            }
        }
        let cap = match &self.buffers {
            Some(b) => Capacity {
                from: b.capacity.from.max(need.from),
                k: b.capacity.k.max(need.k),
                to: b.capacity.to.max(need.to),
                nodes: b.capacity.nodes.max(need.nodes),
            },
            None => need,
        };
        let largest = ctx.limits.max_storage_buffer_binding_size;
        let layer_bytes = cap.from.saturating_mul(cap.k).saturating_mul(32);
        if layer_bytes > largest
            || cap.from.saturating_mul(16) > largest
            || cap.to.saturating_mul(16) > largest
        {
            return Err(RenderError::Settings(format!(
                "a warp of these sizes needs buffers of up to {} bytes; {} allows {largest}",
                layer_bytes.max(16 * cap.from).max(16 * cap.to),
                ctx.info.name
            )));
        }
        let device = &ctx.device;
        let storage = |label, bytes: u64, extra| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(16),
                usage: wgpu::BufferUsages::STORAGE | extra,
                mapped_at_creation: false,
            })
        };
        let readable = |label, bytes: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(16),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let into = wgpu::BufferUsages::COPY_DST;
        let out = wgpu::BufferUsages::COPY_SRC;
        let color = storage("warp source color", 16 * cap.from, into);
        let depth = storage("warp source depth", 4 * cap.from, into);
        let layers = storage("warp source layers", layer_bytes, into);
        let out_color = storage("warped color", 16 * cap.to, out);
        let out_depth = storage("warped depth", 4 * cap.to, out);
        let nearest = storage("grid nearest", 4 * cap.to, into);
        let mesh = storage("grid mesh", 16 * cap.nodes, into);
        let from_at = storage("grid source positions", 8 * cap.to, into);
        let group = WarpResources {
            w: self.uniform.as_entire_binding(),
            color: color.as_entire_binding(),
            depth: depth.as_entire_binding(),
            layers: layers.as_entire_binding(),
            out_color: out_color.as_entire_binding(),
            out_depth: out_depth.as_entire_binding(),
            nearest: nearest.as_entire_binding(),
            mesh: mesh.as_entire_binding(),
            from_at: from_at.as_entire_binding(),
        }
        .bind(device, &self.layout);
        self.buffers = Some(Buffers {
            capacity: cap,
            color_read: readable("warped color read-back", 16 * cap.to),
            depth_read: readable("warped depth read-back", 4 * cap.to),
            color,
            depth,
            layers,
            out_color,
            out_depth,
            nearest,
            // The mesh and the source positions live as long as the group.
            group,
        });
        self.uploaded = None;
        ctx.check()
    }
}

fn vec4s(v: &[Vec4]) -> Vec<[f32; 4]> {
    v.iter().map(|c| c.to_array()).collect()
}

fn uniform(
    source: &Source,
    from: &Projector,
    to: &Projector,
    size: UVec2,
    nodes: UVec2,
    settings: &WarpSettings,
) -> Warp {
    let v = |x: Vec3| x.extend(0.0).to_array();
    let eye = |r: &RayGen| match r.eye {
        Some(e) => e.extend(1.0).to_array(),
        None => [0.0; 4],
    };
    let (s, t) = (&source.rays, to.rays());
    let [fx, fy, fz, fc] = from.packed();
    let [tx, ty, tz, tc] = to.packed();
    let (lo, hi) = settings.bounds;
    Warp {
        to_origin: v(t.origin),
        to_origin_dx: v(t.origin_dx),
        to_origin_dy: v(t.origin_dy),
        to_direction: v(t.direction),
        to_direction_dx: v(t.direction_dx),
        to_direction_dy: v(t.direction_dy),
        to_eye: eye(t),
        from_origin: v(s.origin),
        from_origin_dx: v(s.origin_dx),
        from_origin_dy: v(s.origin_dy),
        from_direction: v(s.direction),
        from_direction_dx: v(s.direction_dx),
        from_direction_dy: v(s.direction_dy),
        from_eye: eye(s),
        from_inverse_x: fx,
        from_inverse_y: fy,
        from_inverse_z: fz,
        from_centre: fc,
        to_inverse_x: tx,
        to_inverse_y: ty,
        to_inverse_z: tz,
        to_centre: tc,
        normal: v(from.image_normal()),
        focus: v(settings.focus()),
        lo: v(lo),
        hi: v(hi),
        from_size: source.size.to_array(),
        to_size: size.to_array(),
        nodes: nodes.to_array(),
        spacing: settings.grid_spacing,
        layers: source.k as u32,
        steps: settings.layer_steps,
        depth_threshold: settings.depth_threshold,
        near: t.t_near,
        far: t.t_far,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu::bindings::assert_declared;
    use crate::render::gpu::shaders::compose;

    #[test]
    fn the_warp_shader_declares_its_table() {
        let groups = [&WarpLayout::table()];
        assert_declared(&compose("warp", &groups).unwrap(), &groups);
    }
}
