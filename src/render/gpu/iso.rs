//! Isosurface ray casting on the GPU (shaders/iso.wgsl, and
//! iso_panel.wgsl for multi-view panels), held to the CPU reference in
//! src/render/iso/: the pipelines are made on the first cast, the volume
//! shares the renderer's uploaded textures.

use bytemuck::Zeroable;
use glam::Vec3;
use wgpu::TextureViewDimension as Dim;

use super::bindings::{binding_table, Kind};
use super::context::{unprepared, Context, Pass};
use super::raycast::RaycastPass;
use super::resources::{color_data, floats, OutputBuffers};
use super::shaders::compute_pipeline;
use super::uniforms::Iso;
use super::volume_texture::VolumeTexture;
use crate::geometry::RayGen;
use crate::render::iso::{
    crossing_box, Coloring, IsoFilter, IsoSettings, MultiViewMethod, UNSTRUCTURED_ISO,
};
use crate::render::{Frame, FrameDesc, RenderError, Watch};
use crate::scene::{PlacedVolume, Scaling};

binding_table! {
    /// Group 0 of every isosurface pass.
    IsoResources / IsoLayout = "iso_bindings" imports ["iso_uniforms"] (filterable: bool) {
        iso: Kind::storage("Iso"),
        volume: Kind::texture(Dim::D3, filterable),
        color_out: Kind::storage_rw("array<u32>"),
        depth_out: Kind::storage_rw("array<f32>"),
    }
}

binding_table! {
    /// Group 1 of the multi-view panel passes.
    PanelResources / PanelLayout = "iso_panel_bindings" imports [] () {
        /// Each view's rays (seven vec4s: origin, its steps, direction,
        /// its steps, eye).
        view_rays: Kind::storage("array<vec4f>"),
        /// Each pixel's red, green and blue views (a byte each).
        pixel_views: Kind::storage("array<u32>"),
        /// The geometric pass's green t per pixel (negative: missed).
        green_t: Kind::storage_rw("array<f32>"),
    }
}

/// A panel's buffers for one display image, and how it is made.
pub(super) struct PanelBuffers<'a> {
    rays: &'a wgpu::Buffer,
    views: &'a wgpu::Buffer,
    /// The geometric pass's green t per pixel.
    green: &'a wgpu::Buffer,
    method: MultiViewMethod,
}

pub(super) struct IsoPass {
    layout: IsoLayout,
    pipeline: wgpu::ComputePipeline,
    /// A multi-view panel's rays and per-pixel views (group 1).
    panel_layout: PanelLayout,
    per_subpixel: wgpu::ComputePipeline,
    geometric: wgpu::ComputePipeline,
    spectral: wgpu::ComputePipeline,
    /// The spectral pass shading green's hit for red and blue.
    green_geometry: wgpu::ComputePipeline,
    uniform: wgpu::Buffer,
    target: Option<OutputBuffers>,
    /// The last panel's buffers (put back after each cast).
    panel: Option<PanelCache>,
    /// The last crossing box, and the volume, iso-value and filter it is
    /// of: a pass over every voxel, kept while they stay.
    crossing: Option<(Crossing, (Vec3, Vec3))>,
}

/// A panel's buffers and what was last written to them.
struct PanelCache {
    ray_data: Vec<[f32; 4]>,
    packed: Vec<u32>,
    rays: wgpu::Buffer,
    views: wgpu::Buffer,
    green: wgpu::Buffer,
}

/// What a crossing box depends on.
struct Crossing {
    volume: std::sync::Arc<crate::scene::SpatialField>,
    isovalue: f32,
    filter: IsoFilter,
}

impl Crossing {
    fn matches(&self, placed: &PlacedVolume, s: &IsoSettings) -> bool {
        std::sync::Arc::ptr_eq(&self.volume, &placed.volume)
            && self.isovalue.to_bits() == s.isovalue.to_bits()
            && self.filter == s.filter
    }
}

impl IsoPass {
    /// Cast in `raycast`'s bands of rows (its band group last), so that a
    /// discard stops a cast between bands.
    pub fn new(ctx: &Context, raycast: &RaycastPass) -> Result<Self, RenderError> {
        let device = &ctx.device;
        let layout = IsoLayout::new(device, ctx.filterable);
        let bands = raycast.band_layout.group();
        let pipeline =
            compute_pipeline(device, "iso", "iso", "main", &[layout.group(), bands], &[])?;
        let panel_layout = PanelLayout::new(device);
        let panel_pipeline = |entry: &str, constants: &[(&str, f64)]| {
            compute_pipeline(
                device,
                "iso panel",
                "iso_panel",
                entry,
                &[layout.group(), panel_layout.group(), bands],
                constants,
            )
        };
        let per_subpixel = panel_pipeline("per_subpixel", &[])?;
        let geometric = panel_pipeline("geometric", &[])?;
        let spectral = panel_pipeline("spectral", &[])?;
        let green_geometry = panel_pipeline("spectral", &[("GREEN_GEOMETRY", 1.0)])?;
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("iso"),
            size: size_of::<Iso>() as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self {
            layout,
            pipeline,
            panel_layout,
            per_subpixel,
            geometric,
            spectral,
            green_geometry,
            uniform,
            target: None,
            panel: None,
            crossing: None,
        })
    }

    /// A multi-view panel's image from its views' rays (`rays`, seven
    /// vec4s a view, `first` the first view) and each pixel's three views
    /// (`packed`): one ray a subpixel (`PerSubpixel`) or the geometric and
    /// spectral passes (`GeometricSpectral`, `GreenGeometry`). Returns the frame and the passes' milliseconds.
    #[allow(clippy::too_many_arguments)]
    pub fn cast_display(
        &mut self,
        ctx: &Context,
        volume: &VolumeTexture,
        placed: &PlacedVolume,
        first: &RayGen,
        rays: Vec<[f32; 4]>,
        packed: Vec<u32>,
        desc: &FrameDesc,
        settings: &IsoSettings,
        method: MultiViewMethod,
        (raycast, watch): (&RaycastPass, Watch),
    ) -> Result<(Frame, f64), RenderError> {
        // A display's rays and pattern stay from frame to frame: its
        // buffers are kept, and written again only when they change.
        let fits = self
            .panel
            .as_ref()
            .is_some_and(|k| k.ray_data.len() == rays.len() && k.packed.len() == packed.len());
        let cache = match self.panel.take() {
            Some(mut k) if fits => {
                if k.ray_data != rays {
                    ctx.queue
                        .write_buffer(&k.rays, 0, bytemuck::cast_slice(&rays));
                    k.ray_data = rays;
                }
                if k.packed != packed {
                    ctx.queue
                        .write_buffer(&k.views, 0, bytemuck::cast_slice(&packed));
                    k.packed = packed;
                }
                k
            }
            _ => {
                let buffer = |label, bytes: &[u8]| {
                    let b = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(label),
                        size: bytes.len().max(16) as u64,
                        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    });
                    ctx.queue.write_buffer(&b, 0, bytes);
                    b
                };
                PanelCache {
                    rays: buffer("iso panel rays", bytemuck::cast_slice(&rays)),
                    views: buffer("iso panel views", bytemuck::cast_slice(&packed)),
                    green: buffer("iso green t", &vec![0u8; 4 * packed.len()]),
                    ray_data: rays,
                    packed,
                }
            }
        };
        let buffers = PanelBuffers {
            rays: &cache.rays,
            views: &cache.views,
            green: &cache.green,
            method,
        };
        let frame = self.cast(
            ctx,
            volume,
            placed,
            first,
            desc,
            settings,
            Some(buffers),
            (raycast, watch),
        );
        self.panel = Some(cache);
        frame
    }

    /// The iso shader over `rays` (`main`), or over a panel: `per_subpixel`,
    /// or `geometric` then `spectral`; `volume` is `placed`'s texture.
    /// Returns the frame and the passes' milliseconds, or
    /// `RenderError::Stopped` once the stop flag is set between bands.
    /// Counts every pass's bands.
    #[allow(clippy::too_many_arguments)]
    pub fn cast(
        &mut self,
        ctx: &Context,
        volume: &VolumeTexture,
        placed: &PlacedVolume,
        rays: &RayGen,
        desc: &FrameDesc,
        settings: &IsoSettings,
        panel: Option<PanelBuffers>,
        (raycast, watch): (&RaycastPass, Watch),
    ) -> Result<(Frame, f64), RenderError> {
        if !matches!(&self.target, Some(t) if t.size == desc.size && t.format == desc.color) {
            self.target = Some(OutputBuffers::new(ctx, desc.size, desc.color, false));
        }
        let bounds = match &self.crossing {
            Some((key, bounds)) if key.matches(placed, settings) => *bounds,
            _ => {
                let Some(v) = placed.volume.structured() else {
                    return Err(RenderError::Settings(UNSTRUCTURED_ISO.into()));
                };
                let bounds =
                    crossing_box(v.dims(), |i| v.value(i), settings.isovalue, settings.filter);
                let key = Crossing {
                    volume: std::sync::Arc::clone(&placed.volume),
                    isovalue: settings.isovalue,
                    filter: settings.filter,
                };
                self.crossing = Some((key, bounds));
                bounds
            }
        };
        let target = self.target.as_ref().ok_or_else(unprepared)?;
        let uniform = uniform(placed, volume.to_value, rays, desc, settings, bounds);
        ctx.queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        let group = IsoResources {
            iso: self.uniform.as_entire_binding(),
            volume: wgpu::BindingResource::TextureView(&volume.view),
            color_out: target.color.as_entire_binding(),
            depth_out: target.depth.as_entire_binding(),
        }
        .bind(&ctx.device, &self.layout);
        let bands = raycast.write_bands(ctx, desc.size);
        let passes = match &panel {
            // Naive panels are cast a view at a time, never here.
            Some(p) => p.method.passes(1) as u64,
            None => 1,
        };
        watch.expect(passes * bands.len() as u64);
        let banded = |pipeline, groups| Pass {
            pipeline,
            groups,
            band: Some(&raycast.band_group),
        };
        let ms = match panel {
            None => ctx.dispatch_bands(&banded(&self.pipeline, &[&group]), &bands, watch)?,
            Some(p) => {
                let panel_group = PanelResources {
                    view_rays: p.rays.as_entire_binding(),
                    pixel_views: p.views.as_entire_binding(),
                    green_t: p.green.as_entire_binding(),
                }
                .bind(&ctx.device, &self.panel_layout);
                let groups = [&group, &panel_group];
                match p.method {
                    // Every band's green first: the spectral pass reads
                    // it about each pixel, across band edges.
                    MultiViewMethod::GeometricSpectral | MultiViewMethod::GreenGeometry => {
                        let second = match p.method {
                            MultiViewMethod::GreenGeometry => &self.green_geometry,
                            _ => &self.spectral,
                        };
                        ctx.dispatch_bands(&banded(&self.geometric, &groups), &bands, watch)?
                            + ctx.dispatch_bands(&banded(second, &groups), &bands, watch)?
                    }
                    _ => ctx.dispatch_bands(&banded(&self.per_subpixel, &groups), &bands, watch)?,
                }
            }
        };
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&target.color, 0, &target.color_read, 0, None);
        encoder.copy_buffer_to_buffer(&target.depth, 0, &target.depth_read, 0, None);
        ctx.queue.submit([encoder.finish()]);
        let color = ctx.read(&target.color_read, target.color_bytes())?;
        let depth = desc
            .depth
            .then(|| {
                ctx.read(&target.depth_read, target.scalar_bytes())
                    .map(|b| floats(&b))
            })
            .transpose()?;
        ctx.check()?;
        let frame = Frame {
            size: desc.size,
            color: color_data(desc.color, color),
            depth,
            hits: None,
            samples: 0,
        };
        Ok((frame, ms))
    }
}

fn uniform(
    placed: &PlacedVolume,
    to_value: Scaling,
    rays: &RayGen,
    desc: &FrameDesc,
    s: &IsoSettings,
    (lo, hi): (Vec3, Vec3),
) -> Iso {
    let v = |x: glam::Vec3| x.extend(0.0).to_array();
    let m = placed.world_to_grid().as_mat4();
    let (color, curvature, radius) = match s.coloring {
        Coloring::Flat(c) => (c, 0, 1.0),
        Coloring::Curvature { radius } => (glam::Vec3::ONE, 1, radius),
    };
    Iso {
        ray_origin: v(rays.origin),
        ray_origin_dx: v(rays.origin_dx),
        ray_origin_dy: v(rays.origin_dy),
        ray_dir: v(rays.direction),
        ray_dir_dx: v(rays.direction_dx),
        ray_dir_dy: v(rays.direction_dy),
        eye: rays.eye.map_or([0.0; 4], |e| e.extend(1.0).to_array()),
        to_grid_x: m.row(0).to_array(),
        to_grid_y: m.row(1).to_array(),
        to_grid_z: m.row(2).to_array(),
        color: v(color),
        light: s.light.map_or([0.0; 4], |l| l.extend(1.0).to_array()),
        shading: [s.ambient, s.diffuse, s.specular, s.shininess],
        background: s.background.to_array(),
        dims: placed.volume.dims().extend(0).to_array(),
        box_lo: v(lo),
        box_hi: v(hi),
        isovalue: s.isovalue,
        step: placed.smallest_cell() / s.steps_per_cell,
        near: rays.t_near,
        far: rays.t_far,
        width: desc.size.x,
        height: desc.size.y,
        secant_steps: s.secant_steps,
        filtering: u32::from(s.filter == IsoFilter::TricubicBSpline),
        curvature,
        radius,
        color_format: desc.color.code(),
        texel_scale: to_value.slope,
        texel_offset: to_value.intercept,
        ..Iso::zeroed()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu::bindings::assert_declared;
    use crate::render::gpu::raycast::BandLayout;
    use crate::render::gpu::shaders::compose;

    #[test]
    fn the_iso_shaders_declare_their_tables() {
        for filterable in [false, true] {
            let bands = BandLayout::table();
            let groups = [&IsoLayout::table(filterable), &bands];
            assert_declared(&compose("iso", &groups).unwrap(), &groups);
            let groups = [&IsoLayout::table(filterable), &PanelLayout::table(), &bands];
            assert_declared(&compose("iso_panel", &groups).unwrap(), &groups);
        }
    }
}
