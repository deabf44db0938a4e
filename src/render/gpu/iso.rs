//! Isosurface ray casting on the GPU (shaders/iso.wgsl), held to the CPU
//! reference in src/render/iso/: the pipeline is made on the first cast,
//! the volume shares the renderer's uploaded textures.

use bytemuck::Zeroable;
use glam::Vec3;

use super::resources::OutputBuffers;
use super::uniforms::{Iso, WORKGROUP};
use super::{
    bind_group, buffer_type, color_data, compute_pipeline, floats, layout_entry, shaders,
    unprepared, GpuRenderer,
};
use crate::geometry::RayGen;
use crate::render::iso::{crossing_box, Coloring, IsoFilter, IsoSettings, MultiViewMethod, Panel};
use crate::render::{Frame, FrameDesc, RenderError};
use crate::scene::{PlacedVolume, Scene};

/// A panel's buffers for one display image, and how it is made.
struct PanelBuffers<'a> {
    rays: &'a wgpu::Buffer,
    views: &'a wgpu::Buffer,
    /// The geometric pass's green t per pixel.
    green: &'a wgpu::Buffer,
    method: MultiViewMethod,
}

pub(super) struct IsoGpu {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    /// A multi-view panel's rays and per-pixel views (group 1).
    panel_layout: wgpu::BindGroupLayout,
    per_subpixel: wgpu::ComputePipeline,
    geometric: wgpu::ComputePipeline,
    spectral: wgpu::ComputePipeline,
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
    volume: std::sync::Arc<crate::scene::StructuredVolume>,
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

impl GpuRenderer {
    /// `placed`'s isosurface seen through `rays`, as
    /// [`crate::render::iso::cast`] renders it, on the GPU.
    pub fn cast_iso(
        &mut self,
        placed: &PlacedVolume,
        rays: &RayGen,
        desc: &FrameDesc,
        settings: &IsoSettings,
    ) -> Result<Frame, RenderError> {
        self.run_iso(placed, rays, desc, settings, None)
    }

    /// A multi-view panel's image, every subpixel from its own view, as
    /// [`crate::render::iso::render_display`] makes it: one ray a subpixel
    /// (`PerSubpixel`) or the geometric and spectral passes. The naive way
    /// is the CPU's (or `cast_iso` per view).
    pub fn cast_display(
        &mut self,
        placed: &PlacedVolume,
        panel: &Panel,
        settings: &IsoSettings,
        method: MultiViewMethod,
    ) -> Result<Frame, RenderError> {
        if method == MultiViewMethod::Naive {
            return Err(RenderError::Settings(
                "the GPU makes a panel's image per subpixel or by passes; naive is cast_iso per view".into(),
            ));
        }
        let views = panel.views.len();
        if views == 0 || views > 256 {
            return Err(RenderError::Settings(format!(
                "a panel on the GPU has 1 to 256 views, not {views}"
            )));
        }
        let desc = FrameDesc::new(panel.size).with_color(panel.color);
        desc.validate()?;
        let v = |x: glam::Vec3| x.extend(0.0).to_array();
        let rays: Vec<[f32; 4]> = panel
            .views
            .iter()
            .flat_map(|r| {
                [
                    v(r.origin),
                    v(r.origin_dx),
                    v(r.origin_dy),
                    v(r.direction),
                    v(r.direction_dx),
                    v(r.direction_dy),
                    r.eye.map_or([0.0; 4], |e| e.extend(1.0).to_array()),
                ]
            })
            .collect();
        // Each pixel's three views, a byte each (at most 256 views).
        let packed: Vec<u32> = panel
            .checked_table()?
            .iter()
            .map(|v| v[0] | v[1] << 8 | v[2] << 16)
            .collect();
        // A display's rays and pattern stay from frame to frame: its
        // buffers are kept, and written again only when they change.
        let mut kept = self.iso.as_mut().and_then(|iso| iso.panel.take());
        let fits = kept
            .as_ref()
            .is_some_and(|k| k.ray_data.len() == rays.len() && k.packed.len() == packed.len());
        let cache = match kept.take() {
            Some(mut k) if fits => {
                if k.ray_data != rays {
                    self.ctx
                        .queue
                        .write_buffer(&k.rays, 0, bytemuck::cast_slice(&rays));
                    k.ray_data = rays;
                }
                if k.packed != packed {
                    self.ctx
                        .queue
                        .write_buffer(&k.views, 0, bytemuck::cast_slice(&packed));
                    k.packed = packed;
                }
                k
            }
            _ => {
                let device = &self.ctx.device;
                let buffer = |label, bytes: &[u8]| {
                    let b = device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(label),
                        size: bytes.len().max(16) as u64,
                        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    });
                    self.ctx.queue.write_buffer(&b, 0, bytes);
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
        let frame = self.run_iso(placed, &panel.views[0], &desc, settings, Some(buffers));
        if let Some(iso) = self.iso.as_mut() {
            iso.panel = Some(cache);
        }
        frame
    }

    /// The iso shader over `rays` (`main`), or over a panel: `per_subpixel`,
    /// or `geometric` then `spectral`.
    fn run_iso(
        &mut self,
        placed: &PlacedVolume,
        rays: &RayGen,
        desc: &FrameDesc,
        settings: &IsoSettings,
        panel: Option<PanelBuffers>,
    ) -> Result<Frame, RenderError> {
        desc.validate()?;
        settings.validate()?;
        let scene = Scene::placed(vec![placed.clone()])
            .map_err(|e| RenderError::Settings(e.to_string()))?;
        self.check_limits(&scene, desc)?;
        self.upload_scene(&scene);
        if self.iso.is_none() {
            self.iso = Some(IsoGpu::new(self));
        }
        let ctx = &self.ctx;
        let view = self
            .volumes
            .first()
            .map(|(_, v)| v)
            .ok_or_else(unprepared)?;
        let iso = self.iso.as_mut().ok_or_else(unprepared)?;
        if !matches!(&iso.target, Some(t) if t.size == desc.size && t.format == desc.color) {
            iso.target = Some(OutputBuffers::new(ctx, desc.size, desc.color));
        }
        let bounds = match &iso.crossing {
            Some((key, bounds)) if key.matches(placed, settings) => *bounds,
            _ => {
                let v = &placed.volume;
                let bounds = crossing_box(
                    v.dims(),
                    |i| v.voxels().value(i),
                    settings.isovalue,
                    settings.filter,
                );
                let key = Crossing {
                    volume: std::sync::Arc::clone(v),
                    isovalue: settings.isovalue,
                    filter: settings.filter,
                };
                iso.crossing = Some((key, bounds));
                bounds
            }
        };
        let target = iso.target.as_ref().ok_or_else(unprepared)?;
        let uniform = uniform(placed, rays, desc, settings, bounds);
        ctx.queue
            .write_buffer(&iso.uniform, 0, bytemuck::bytes_of(&uniform));
        let group = bind_group(
            &ctx.device,
            "iso",
            &iso.layout,
            [
                iso.uniform.as_entire_binding(),
                wgpu::BindingResource::TextureView(view),
                target.color.as_entire_binding(),
                target.depth.as_entire_binding(),
            ],
        );
        let workgroups = [
            desc.size.x.div_ceil(WORKGROUP),
            desc.size.y.div_ceil(WORKGROUP),
            1,
        ];
        self.last_pass_ms = match panel {
            None => ctx.dispatch(&iso.pipeline, &[&group], workgroups)?,
            Some(p) => {
                let panel_group = bind_group(
                    &ctx.device,
                    "iso panel",
                    &iso.panel_layout,
                    [
                        p.rays.as_entire_binding(),
                        p.views.as_entire_binding(),
                        p.green.as_entire_binding(),
                    ],
                );
                let groups = [&group, &panel_group];
                match p.method {
                    MultiViewMethod::GeometricSpectral => {
                        ctx.dispatch(&iso.geometric, &groups, workgroups)?
                            + ctx.dispatch(&iso.spectral, &groups, workgroups)?
                    }
                    _ => ctx.dispatch(&iso.per_subpixel, &groups, workgroups)?,
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
        Ok(Frame {
            size: desc.size,
            color: color_data(desc.color, color),
            depth,
            samples: 0,
        })
    }
}

impl IsoGpu {
    fn new(gpu: &GpuRenderer) -> Self {
        let device = &gpu.ctx.device;
        let storage = buffer_type(wgpu::BufferBindingType::Storage { read_only: false });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("iso"),
            entries: &[
                layout_entry(0, buffer_type(wgpu::BufferBindingType::Uniform)),
                layout_entry(
                    1,
                    wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float {
                            filterable: gpu.ctx.filterable,
                        },
                        view_dimension: wgpu::TextureViewDimension::D3,
                        multisampled: false,
                    },
                ),
                layout_entry(2, storage),
                layout_entry(3, storage),
            ],
        });
        let source = shaders::iso();
        let pipeline = compute_pipeline(device, "iso", &source, &[&layout], "main");
        let read = buffer_type(wgpu::BufferBindingType::Storage { read_only: true });
        let panel_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("iso panel"),
            entries: &[
                layout_entry(0, read),
                layout_entry(1, read),
                layout_entry(2, storage),
            ],
        });
        let panel_pipeline = |entry: &str| {
            compute_pipeline(
                device,
                "iso panel",
                &source,
                &[&layout, &panel_layout],
                entry,
            )
        };
        let per_subpixel = panel_pipeline("per_subpixel");
        let geometric = panel_pipeline("geometric");
        let spectral = panel_pipeline("spectral");
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("iso"),
            size: size_of::<Iso>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            layout,
            pipeline,
            panel_layout,
            per_subpixel,
            geometric,
            spectral,
            uniform,
            target: None,
            panel: None,
            crossing: None,
        }
    }
}

fn uniform(
    placed: &PlacedVolume,
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
        ..Iso::zeroed()
    }
}
