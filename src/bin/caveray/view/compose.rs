//! What `caveray view` draws with the GPU: the walls' images as textured
//! quads, lines, and egui's controls, into a canvas the window shows and
//! screenshots read. It owns its pipelines, their layouts and the bind
//! groups, made once (a wall's again when its image changes size).

use glam::{Mat4, UVec2, Vec3, Vec4};
use wgpu::util::DeviceExt;

use crate::Failure;

/// The canvas's format: what egui draws into ("gamma space") and what the
/// walls' sRGB-encoded images are copied into unchanged.
pub const CANVAS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const SHADER: &str = include_str!("../../../../shaders/view.wgsl");
/// Lines a frame may draw (wall edges, head, volume box).
const MAX_LINE_VERTICES: usize = 4096;

/// The device and queue the window draws with.
pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter: wgpu::Adapter,
    pub info: wgpu::AdapterInfo,
}

impl Gpu {
    /// A GPU that can draw to `surface` (any, without one).
    pub fn open(
        instance: &wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, Failure> {
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: surface,
            ..Default::default()
        }))
        .map_err(|e| {
            Failure::Runtime(format!(
                "caveray view draws with Vulkan and found no adapter ({e}); on a machine \
                 without a GPU install Mesa's lavapipe (mesa-vulkan-drivers)"
            ))
        })?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("caveray view"),
            ..Default::default()
        }))
        .map_err(|e| Failure::Runtime(format!("cannot open the window's GPU: {e}")))?;
        Ok(Self {
            device,
            queue,
            info: adapter.get_info(),
            adapter,
        })
    }
}

/// A wall to draw this frame.
pub struct WallDraw {
    pub clip: Mat4,
    /// Lower-left, lower-right, upper-right, upper-left.
    pub corners: [Vec3; 4],
    /// 0 left, 1 right, 2 anaglyph, 3 side by side.
    pub stereo: u32,
    /// Texel for pixel (laid flat at 1:1), not filtered.
    pub exact: bool,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct WallUniform {
    clip: [[f32; 4]; 4],
    corners: [[f32; 4]; 4],
    stereo: u32,
    flags: u32,
    pad: [u32; 2],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LineVertex {
    pub position: [f32; 3],
    pub color: [f32; 4],
}

impl LineVertex {
    pub fn new(p: Vec3, color: Vec4) -> Self {
        Self {
            position: p.to_array(),
            color: color.to_array(),
        }
    }
}

/// A frame's 3D part: where on the canvas it goes, its walls and lines.
pub struct Stage {
    /// x, y, width, height in canvas pixels (y down).
    pub viewport: [f32; 4],
    pub walls: Vec<Option<WallDraw>>,
    pub lines: Vec<LineVertex>,
    pub lines_clip: Mat4,
    /// Laid flat: each image's rectangle in the viewport (x, y, width,
    /// height in pixels, y down).
    pub rects: Vec<[f32; 4]>,
}

/// egui's part of a frame.
pub struct Overlay {
    pub primitives: Vec<egui::ClippedPrimitive>,
    pub textures: egui::TexturesDelta,
    pub pixels_per_point: f32,
}

struct WallImages {
    uniform: wgpu::Buffer,
    /// Left and right eye (a mono wall's image is its left).
    images: [Option<(wgpu::Texture, UVec2)>; 2],
    bind: wgpu::BindGroup,
}

pub struct Composer {
    size: UVec2,
    canvas: wgpu::Texture,
    canvas_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    wall_pipeline: wgpu::RenderPipeline,
    wall_layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    /// Bound where a wall has no image for an eye yet.
    blank: wgpu::TextureView,
    walls: Vec<WallImages>,
    line_pipeline: wgpu::RenderPipeline,
    line_uniform: wgpu::Buffer,
    line_bind: wgpu::BindGroup,
    line_vertices: wgpu::Buffer,
    blit: Option<(wgpu::TextureFormat, wgpu::RenderPipeline, wgpu::BindGroup)>,
    blit_layout: wgpu::BindGroupLayout,
    egui: egui_wgpu::Renderer,
    /// egui's controls and overlay, drawn only when they change (egui is
    /// the costliest part of a frame on a CPU's Vulkan) and laid over the
    /// walls every frame.
    ui_layer: wgpu::TextureView,
    ui_bind: wgpu::BindGroup,
    layer_pipeline: wgpu::RenderPipeline,
}

fn texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

fn uniform_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A render pipeline's parts besides its module and layout.
struct Spec<'a> {
    /// Vertex and fragment entry points.
    entries: (&'a str, &'a str),
    buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    topology: wgpu::PrimitiveTopology,
    target: wgpu::TextureFormat,
    blend: Option<wgpu::BlendState>,
    depth: bool,
}

fn pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
    spec: Spec<'_>,
) -> wgpu::RenderPipeline {
    let Spec {
        entries: (vs, fs),
        buffers,
        topology,
        target,
        blend,
        depth,
    } = spec;
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(vs),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(vs),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some(vs),
            buffers,
            compilation_options: Default::default(),
        },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fs),
            targets: &[Some(wgpu::ColorTargetState {
                format: target,
                blend,
                write_mask: wgpu::ColorWrites::ALL,
            })],
            compilation_options: Default::default(),
        }),
        primitive: wgpu::PrimitiveState {
            topology,
            ..Default::default()
        },
        depth_stencil: depth.then_some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::LessEqual),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        multiview_mask: None,
        cache: None,
    })
}

/// The canvas, its depth and egui's layer at `size`.
fn canvas_textures(
    device: &wgpu::Device,
    size: UVec2,
) -> (
    wgpu::Texture,
    wgpu::TextureView,
    wgpu::TextureView,
    wgpu::TextureView,
) {
    let extent = wgpu::Extent3d {
        width: size.x,
        height: size.y,
        depth_or_array_layers: 1,
    };
    let canvas = device.create_texture(&canvas_descriptor(extent));
    let depth = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("view depth"),
        size: extent,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: DEPTH_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let layer = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("view controls"),
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        ..canvas_descriptor(extent)
    });
    let view = canvas.create_view(&Default::default());
    (
        canvas,
        view,
        depth.create_view(&Default::default()),
        layer.create_view(&Default::default()),
    )
}

fn canvas_descriptor(extent: wgpu::Extent3d) -> wgpu::TextureDescriptor<'static> {
    wgpu::TextureDescriptor {
        label: Some("view canvas"),
        size: extent,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: CANVAS_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    }
}

fn layer_bind(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    layer: &wgpu::TextureView,
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("view controls"),
        layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: wgpu::BindingResource::TextureView(layer),
        }],
    })
}

impl Composer {
    pub fn new(gpu: &Gpu, size: UVec2, walls: usize) -> Self {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("view.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let wall_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("view wall"),
            entries: &[
                uniform_entry(0, wgpu::ShaderStages::VERTEX_FRAGMENT),
                texture_entry(1),
                texture_entry(2),
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let line_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("view lines"),
            entries: &[uniform_entry(0, wgpu::ShaderStages::VERTEX)],
        });
        let blit_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("view blit"),
            entries: &[wgpu::BindGroupLayoutEntry {
                visibility: wgpu::ShaderStages::FRAGMENT,
                ..texture_entry(0)
            }],
        });
        let wall_pipeline = pipeline(
            device,
            &module,
            &wall_layout,
            Spec {
                entries: ("wall_vs", "wall_fs"),
                buffers: &[],
                topology: wgpu::PrimitiveTopology::TriangleList,
                target: CANVAS_FORMAT,
                blend: None,
                depth: true,
            },
        );
        let line_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<LineVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4],
        })];
        let line_pipeline = pipeline(
            device,
            &module,
            &line_layout,
            Spec {
                entries: ("line_vs", "line_fs"),
                buffers: &line_buffers,
                topology: wgpu::PrimitiveTopology::LineList,
                target: CANVAS_FORMAT,
                blend: None,
                depth: true,
            },
        );
        // egui's layer over the walls: its colours are premultiplied.
        let layer_pipeline = pipeline(
            device,
            &module,
            &blit_layout,
            Spec {
                entries: ("blit_vs", "blit_fs"),
                buffers: &[],
                topology: wgpu::PrimitiveTopology::TriangleList,
                target: CANVAS_FORMAT,
                blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                depth: false,
            },
        );
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("view walls"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let blank = device
            .create_texture_with_data(
                &gpu.queue,
                &wgpu::TextureDescriptor {
                    label: Some("view blank"),
                    size: wgpu::Extent3d {
                        width: 1,
                        height: 1,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: CANVAS_FORMAT,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                },
                Default::default(),
                &[0, 0, 0, 255],
            )
            .create_view(&Default::default());
        let line_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("view lines"),
            size: 64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let line_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("view lines"),
            layout: &line_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: line_uniform.as_entire_binding(),
            }],
        });
        let line_vertices = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("view line vertices"),
            size: (MAX_LINE_VERTICES * std::mem::size_of::<LineVertex>()) as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let (canvas, canvas_view, depth_view, ui_layer) = canvas_textures(device, size);
        let ui_bind = layer_bind(device, &blit_layout, &ui_layer);
        let egui = egui_wgpu::Renderer::new(
            device,
            CANVAS_FORMAT,
            egui_wgpu::RendererOptions {
                dithering: false,
                ..Default::default()
            },
        );
        let mut composer = Self {
            size,
            canvas,
            canvas_view,
            depth_view,
            wall_pipeline,
            wall_layout,
            sampler,
            blank,
            walls: Vec::new(),
            line_pipeline,
            line_uniform,
            line_bind,
            line_vertices,
            blit: None,
            blit_layout,
            egui,
            ui_layer,
            ui_bind,
            layer_pipeline,
        };
        composer.walls = (0..walls)
            .map(|_| {
                let uniform = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("view wall"),
                    size: std::mem::size_of::<WallUniform>() as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let bind = composer.wall_bind(device, &uniform, [None, None]);
                WallImages {
                    uniform,
                    images: [None, None],
                    bind,
                }
            })
            .collect();
        composer
    }

    pub fn size(&self) -> UVec2 {
        self.size
    }

    fn wall_bind(
        &self,
        device: &wgpu::Device,
        uniform: &wgpu::Buffer,
        images: [Option<&wgpu::Texture>; 2],
    ) -> wgpu::BindGroup {
        let views = images.map(|t| t.map(|t| t.create_view(&Default::default())));
        let view = |i: usize| views[i].as_ref().unwrap_or(&self.blank);
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("view wall"),
            layout: &self.wall_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(view(0)),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(view(1)),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
            ],
        })
    }

    /// The canvas at `size` (the window's), if it changed.
    pub fn resize(&mut self, gpu: &Gpu, size: UVec2) {
        let size = size.max(UVec2::ONE);
        if size == self.size {
            return;
        }
        (
            self.canvas,
            self.canvas_view,
            self.depth_view,
            self.ui_layer,
        ) = canvas_textures(&gpu.device, size);
        self.ui_bind = layer_bind(&gpu.device, &self.blit_layout, &self.ui_layer);
        self.size = size;
        self.blit = None;
    }

    /// A wall's image for one eye (0 left or mono, 1 right), sRGB-encoded
    /// RGBA, top row first; `None` forgets it.
    pub fn set_image(&mut self, gpu: &Gpu, wall: usize, eye: usize, image: Option<(UVec2, &[u8])>) {
        let Some(w) = self.walls.get(wall) else {
            return;
        };
        let same_size = match (&w.images[eye], &image) {
            (Some((_, old)), Some((new, _))) => old == new,
            (None, None) => true,
            _ => false,
        };
        if !same_size {
            let made = image.map(|(size, _)| {
                let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("view wall image"),
                    size: wgpu::Extent3d {
                        width: size.x,
                        height: size.y,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: CANVAS_FORMAT,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                });
                (texture, size)
            });
            let mut images = std::mem::take(&mut self.walls[wall].images);
            images[eye] = made;
            let bind = self.wall_bind(
                &gpu.device,
                &self.walls[wall].uniform,
                [
                    images[0].as_ref().map(|t| &t.0),
                    images[1].as_ref().map(|t| &t.0),
                ],
            );
            let w = &mut self.walls[wall];
            w.images = images;
            w.bind = bind;
        }
        if let (Some((texture, size)), Some((_, pixels))) = (&self.walls[wall].images[eye], image) {
            gpu.queue.write_texture(
                texture.as_image_copy(),
                pixels,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(4 * size.x),
                    rows_per_image: Some(size.y),
                },
                wgpu::Extent3d {
                    width: size.x,
                    height: size.y,
                    depth_or_array_layers: 1,
                },
            );
        }
    }

    /// Draws a frame into the canvas.
    pub fn draw(&mut self, gpu: &Gpu, stage: &Stage) {
        let device = &gpu.device;
        let mut encoder = device.create_command_encoder(&Default::default());
        for (w, draw) in self.walls.iter().zip(&stage.walls) {
            let Some(d) = draw else { continue };
            let corner = |c: Vec3| [c.x, c.y, c.z, 1.0];
            let flags = u32::from(w.images[0].is_some())
                | (u32::from(w.images[1].is_some()) << 1)
                | (u32::from(d.exact) << 2);
            let uniform = WallUniform {
                clip: d.clip.to_cols_array_2d(),
                corners: d.corners.map(corner),
                stereo: d.stereo,
                flags,
                pad: [0; 2],
            };
            gpu.queue
                .write_buffer(&w.uniform, 0, bytemuck::bytes_of(&uniform));
        }
        let lines = &stage.lines[..stage.lines.len().min(MAX_LINE_VERTICES) & !1];
        gpu.queue.write_buffer(
            &self.line_uniform,
            0,
            bytemuck::bytes_of(&stage.lines_clip.to_cols_array()),
        );
        gpu.queue
            .write_buffer(&self.line_vertices, 0, bytemuck::cast_slice(lines));
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("view walls"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.canvas_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: 0.02,
                            g: 0.02,
                            b: 0.03,
                            a: 1.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let [x, y, w, h] = stage.viewport;
            let (cw, ch) = (self.size.x as f32, self.size.y as f32);
            let x0 = x.clamp(0.0, cw - 1.0);
            let y0 = y.clamp(0.0, ch - 1.0);
            pass.set_viewport(
                x0,
                y0,
                w.min(cw - x0).max(1.0),
                h.min(ch - y0).max(1.0),
                0.0,
                1.0,
            );
            pass.set_pipeline(&self.wall_pipeline);
            for (w, draw) in self.walls.iter().zip(&stage.walls) {
                if draw.is_some() {
                    pass.set_bind_group(0, &w.bind, &[]);
                    pass.draw(0..6, 0..1);
                }
            }
            if !lines.is_empty() {
                pass.set_pipeline(&self.line_pipeline);
                pass.set_bind_group(0, &self.line_bind, &[]);
                pass.set_vertex_buffer(0, self.line_vertices.slice(..));
                pass.draw(0..lines.len() as u32, 0..1);
            }
        }
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("view controls over walls"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &self.canvas_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.layer_pipeline);
            pass.set_bind_group(0, &self.ui_bind, &[]);
            pass.draw(0..3, 0..1);
        }
        gpu.queue.submit([encoder.finish()]);
    }

    /// Draws egui's controls and overlay into their layer, which every
    /// frame lays over the walls until the next call.
    pub fn draw_ui(&mut self, gpu: &Gpu, overlay: Overlay) {
        let device = &gpu.device;
        let mut encoder = device.create_command_encoder(&Default::default());
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.size.x, self.size.y],
            pixels_per_point: overlay.pixels_per_point,
        };
        for (id, deltas) in &overlay.textures.set {
            for delta in deltas {
                self.egui.update_texture(device, &gpu.queue, *id, delta);
            }
        }
        let extra = self.egui.update_buffers(
            device,
            &gpu.queue,
            &mut encoder,
            &overlay.primitives,
            &screen,
        );
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("view controls"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &self.ui_layer,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            self.egui.render(&mut pass, &overlay.primitives, &screen);
        }
        gpu.queue
            .submit(extra.into_iter().chain([encoder.finish()]));
        for id in &overlay.textures.free {
            self.egui.free_texture(id);
        }
    }

    /// Copies the canvas to `target` (a window's surface texture, viewed
    /// in `format`, which must not be sRGB: the canvas is already encoded).
    pub fn show(&mut self, gpu: &Gpu, target: &wgpu::TextureView, format: wgpu::TextureFormat) {
        if self.blit.as_ref().is_none_or(|(f, ..)| *f != format) {
            let module = gpu
                .device
                .create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("view.wgsl"),
                    source: wgpu::ShaderSource::Wgsl(SHADER.into()),
                });
            let p = pipeline(
                &gpu.device,
                &module,
                &self.blit_layout,
                Spec {
                    entries: ("blit_vs", "blit_fs"),
                    buffers: &[],
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    target: format,
                    blend: None,
                    depth: false,
                },
            );
            let bind = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("view blit"),
                layout: &self.blit_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&self.canvas_view),
                }],
            });
            self.blit = Some((format, p, bind));
        }
        let Some((_, p, bind)) = &self.blit else {
            return;
        };
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("view blit"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(p);
            pass.set_bind_group(0, bind, &[]);
            pass.draw(0..3, 0..1);
        }
        gpu.queue.submit([encoder.finish()]);
    }

    /// The canvas as it was last drawn, top row first.
    pub fn read(&self, gpu: &Gpu) -> Result<image::RgbaImage, Failure> {
        let (w, h) = (self.size.x, self.size.y);
        let row = (4 * w).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
            * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("view screenshot"),
            size: u64::from(row) * u64::from(h),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            self.canvas.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        gpu.queue.submit([encoder.finish()]);
        let slice = buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        gpu.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Failure::Runtime(format!("screenshot: {e}")))?;
        rx.recv()
            .map_err(|e| Failure::Runtime(format!("screenshot: {e}")))?
            .map_err(|e| Failure::Runtime(format!("screenshot: {e}")))?;
        let mapped = slice
            .get_mapped_range()
            .map_err(|e| Failure::Runtime(format!("screenshot: {e}")))?;
        let mut pixels = Vec::with_capacity((4 * w * h) as usize);
        for y in 0..h as usize {
            let start = y * row as usize;
            pixels.extend_from_slice(&mapped[start..start + 4 * w as usize]);
        }
        drop(mapped);
        buffer.unmap();
        image::RgbaImage::from_raw(w, h, pixels)
            .ok_or_else(|| Failure::Runtime("screenshot: the canvas read back short".into()))
    }
}

/// Images laid side by side in `viewport`, row by row, pixel for pixel
/// where they fit (then `exact`), else scaled down alike.
pub fn flat_stage(viewport: [f32; 4], sizes: &[UVec2], stereo: u32) -> Stage {
    const GAP: f32 = 4.0;
    let n = sizes.len().max(1);
    let cell = sizes.iter().fold(UVec2::ONE, |m, s| m.max(*s)).as_vec2();
    let [_, _, vw, vh] = viewport;
    // The columns at which the images are largest; of those, the grid
    // whose shape is nearest the viewport's.
    let shape = |cols: usize| {
        let rows = n.div_ceil(cols) as f32;
        ((cols as f32 * cell.x) / (rows * cell.y) / (vw / vh))
            .ln()
            .abs()
    };
    let (cols, scale) = (1..=n)
        .map(|cols| {
            let rows = n.div_ceil(cols) as f32;
            let sx = (vw - GAP * (cols as f32 + 1.0)) / (cols as f32 * cell.x);
            let sy = (vh - GAP * (rows + 1.0)) / (rows * cell.y);
            (cols, sx.min(sy).min(1.0))
        })
        .fold((1, f32::MIN), |best, c| {
            let better = c.1 > best.1 + 1e-6 || (c.1 > best.1 - 1e-6 && shape(c.0) < shape(best.0));
            if better {
                c
            } else {
                best
            }
        });
    let scale = scale.max(0.01);
    let exact = scale >= 1.0;
    let ndc = |x: f32, y: f32| Vec3::new(2.0 * x / vw - 1.0, 1.0 - 2.0 * y / vh, 0.5);
    let rects: Vec<[f32; 4]> = sizes
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let (col, row) = ((i % cols) as f32, (i / cols) as f32);
            let x0 = (GAP + col * (cell.x * scale + GAP)).round();
            let y0 = (GAP + row * (cell.y * scale + GAP)).round();
            [
                x0,
                y0,
                (s.x as f32 * scale).round(),
                (s.y as f32 * scale).round(),
            ]
        })
        .collect();
    let walls = rects
        .iter()
        .map(|&[x0, y0, w, h]| {
            Some(WallDraw {
                clip: Mat4::IDENTITY,
                corners: [
                    ndc(x0, y0 + h),
                    ndc(x0 + w, y0 + h),
                    ndc(x0 + w, y0),
                    ndc(x0, y0),
                ],
                stereo,
                exact,
            })
        })
        .collect();
    Stage {
        viewport,
        walls,
        lines: Vec::new(),
        lines_clip: Mat4::IDENTITY,
        rects,
    }
}
