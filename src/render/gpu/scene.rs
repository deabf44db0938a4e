//! The scene on the GPU: its volumes as textures (or brick pools and page
//! tables, paging.rs), its transfer functions as rows of one table
//! texture, the background image and the clear-brick distances and the
//! surfaces' BVH, uploaded when a scene brings new ones and kept
//! otherwise.
//! Passes bind these; `generation` tells them when a bind group made
//! before binds something no longer current.

use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;

use super::context::Context;
use super::paging::{self, Footprint, Layout, PagedVolume, Sight, StreamWait, Streaming, View};
use super::resources::{self, BrickSlot, SurfaceSlot};
use super::volume_texture::{self, PageSlot, TextureSlot, VolumeTexture};
use super::{amr, mesh, nanovdb};
use crate::geometry::RayGen;
use crate::render::empty_space::{EmptySpace, SpaceCache, Visibility};
use crate::render::march_plan::MarchPlan;
use crate::render::shapes::ShapeSet;
use crate::render::{BackgroundImage, FrameDesc, RenderError, Sampling};
use crate::scene::{Filter, PlacedShape, Scene, SpatialField, TransferFunction, MAX_VOLUMES};

/// A field on the GPU: one texture, paged, or a mesh's words in the
/// meshes buffer.
enum OnGpu {
    Whole(VolumeTexture),
    Paged(Box<PagedVolume>),
    Cells,
}

impl OnGpu {
    fn view<'a>(&'a self, stand_in: &'a wgpu::TextureView) -> &'a wgpu::TextureView {
        match self {
            OnGpu::Whole(t) => &t.view,
            OnGpu::Paged(p) => &p.view,
            OnGpu::Cells => stand_in,
        }
    }

    /// Bytes of its own texture or pool (a mesh's are the meshes
    /// buffer's).
    fn bytes(&self) -> u64 {
        match self {
            OnGpu::Whole(t) => t.bytes,
            OnGpu::Paged(p) => p.bytes(),
            OnGpu::Cells => 0,
        }
    }

    fn fits(&self, layout: &Layout) -> bool {
        match (self, layout) {
            (OnGpu::Whole(_), Layout::Whole { .. }) | (OnGpu::Cells, Layout::Cells { .. }) => true,
            (OnGpu::Paged(p), Layout::Paged { pool, .. }) => p.pool == *pool,
            _ => false,
        }
    }
}

/// How often data went to the GPU; lets tests (and curious users) check
/// that unchanged scenes are not uploaded again.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Uploads {
    pub volumes: u32,
    pub transfer_functions: u32,
    /// BVHs of the world's surfaces built and uploaded.
    pub surfaces: u32,
}

pub(super) struct GpuScene {
    /// Whether the volume textures carry mip chains: from the first frame
    /// with level of detail on (software Vulkan samples textures without
    /// them faster, so full detail does not pay for them before).
    mips: bool,
    /// The scene's grids on the GPU, each once (Scene::grids order).
    grids: Vec<(Arc<SpatialField>, OnGpu)>,
    /// Per scene volume, its grid's index in `grids`.
    placed: Vec<usize>,
    /// The paged grids' page tables, one after the other, and where each
    /// grid's starts (by index in `grids`).
    pages: wgpu::Buffer,
    page_offsets: Vec<Option<u32>>,
    /// The meshes' words one after the other (mesh.rs), and where each
    /// mesh begins (by index in `grids`).
    meshes: wgpu::Buffer,
    mesh_offsets: Vec<Option<u32>>,
    /// Bound where a scene has fewer than MAX_VOLUMES volumes.
    no_volume: wgpu::TextureView,
    /// One row per volume slot; which transfer function each row holds.
    table: wgpu::Texture,
    table_view: wgpu::TextureView,
    tables: [Option<Arc<TransferFunction>>; MAX_VOLUMES],
    /// Which table and step exponent each stepped table row holds.
    stepped: [Option<(Arc<TransferFunction>, f32)>; MAX_VOLUMES],
    /// The background image bound now (`None`: the stand-in), and the
    /// stand-in bound when there is none.
    background: Option<(Arc<BackgroundImage>, wgpu::TextureView)>,
    no_background: wgpu::TextureView,
    /// Each placed volume's clear bricks under its table, which the bricks
    /// buffer holds.
    space_cache: SpaceCache,
    bricks: wgpu::Buffer,
    brick_slots: Vec<BrickSlot>,
    /// The placed shapes the surfaces buffer holds, in the scene's order.
    shapes: Vec<PlacedShape>,
    /// The traced words and the shading words (render/shapes/packed.rs).
    surfaces: [wgpu::Buffer; 2],
    surface_slot: SurfaceSlot,
    uploads: Uploads,
    /// Counts changes of what is bound: the volume textures, the
    /// background, the bricks and the surfaces buffers (tables are
    /// rewritten in place).
    generation: u64,
}

impl GpuScene {
    pub fn new(ctx: &Context) -> Self {
        let no_background = resources::upload_background(ctx, None);
        let no_volume = volume_texture::stand_in(ctx);
        let table = resources::table_texture(ctx);
        let table_view = table.create_view(&Default::default());
        let (bricks, _) = resources::bricks_buffer(ctx, &[]);
        let surfaces = [
            resources::words_buffer(ctx, &[]),
            resources::words_buffer(ctx, &[]),
        ];
        let pages = resources::words_u32_buffer(ctx, "pages", &[]);
        let meshes = resources::words_u32_buffer(ctx, "meshes", &[]);
        Self {
            mips: false,
            grids: Vec::new(),
            placed: Vec::new(),
            pages,
            page_offsets: Vec::new(),
            meshes,
            mesh_offsets: Vec::new(),
            no_volume,
            table,
            table_view,
            tables: Default::default(),
            stepped: Default::default(),
            background: None,
            no_background,
            space_cache: SpaceCache::default(),
            bricks,
            brick_slots: Vec::new(),
            shapes: Vec::new(),
            surfaces,
            surface_slot: SurfaceSlot::default(),
            uploads: Uploads::default(),
            generation: 0,
        }
    }

    pub fn uploads(&self) -> Uploads {
        self.uploads
    }

    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Volume slot `i`'s texture (the stand-in past the scene's volumes).
    pub fn volume(&self, i: usize) -> &wgpu::TextureView {
        self.placed
            .get(i)
            .and_then(|&g| self.grids.get(g))
            .map_or(&self.no_volume, |(_, t)| t.view(&self.no_volume))
    }

    /// The first volume's texture, if the scene has one in one texture.
    pub fn first_volume(&self) -> Option<&VolumeTexture> {
        match self.grids.get(*self.placed.first()?)?.1 {
            OnGpu::Whole(ref t) => Some(t),
            OnGpu::Paged(_) | OnGpu::Cells => None,
        }
    }

    pub fn pages(&self) -> &wgpu::Buffer {
        &self.pages
    }

    pub fn meshes(&self) -> &wgpu::Buffer {
        &self.meshes
    }

    pub fn table_view(&self) -> &wgpu::TextureView {
        &self.table_view
    }

    pub fn background(&self) -> &wgpu::TextureView {
        self.background
            .as_ref()
            .map_or(&self.no_background, |(_, v)| v)
    }

    pub fn bricks(&self) -> &wgpu::Buffer {
        &self.bricks
    }

    pub fn surfaces(&self) -> &[wgpu::Buffer; 2] {
        &self.surfaces
    }

    pub fn surface_slot(&self) -> SurfaceSlot {
        self.surface_slot
    }

    /// Builds the BVH of the scene's surfaces and uploads it, unless the
    /// buffer holds these shapes already.
    pub fn upload_surfaces(&mut self, ctx: &Context, scene: &Scene) -> Result<(), RenderError> {
        let shapes = scene.shapes();
        let same = self.shapes.len() == shapes.len()
            && self.shapes.iter().zip(shapes).all(|(a, b)| a.same(b));
        if same {
            return Ok(());
        }
        let packed = ShapeSet::packed(shapes)?;
        (self.surfaces, self.surface_slot) = resources::surfaces_buffers(ctx, &packed)?;
        self.shapes = shapes.to_vec();
        self.uploads.surfaces += u32::from(!shapes.is_empty());
        self.generation += 1;
        Ok(())
    }

    /// Each volume's place in the bricks buffer, when primary rays skip.
    pub fn brick_slots(&self, skipping: bool) -> &[BrickSlot] {
        if skipping {
            &self.brick_slots
        } else {
            &[]
        }
    }

    /// Drops the volume textures: the next upload makes them again.
    pub fn forget_volumes(&mut self) {
        self.grids.clear();
        self.placed.clear();
        self.generation += 1;
    }

    /// From now on volumes carry their mip chains: those on the GPU are
    /// uploaded again on the next upload.
    pub fn use_mips(&mut self) {
        if !self.mips {
            self.mips = true;
            self.grids
                .retain(|(_, g)| matches!(g, OnGpu::Paged(_) | OnGpu::Cells));
            self.placed.clear();
            self.generation += 1;
        }
    }

    /// Uploads whatever of the scene is not on the GPU (a new volume
    /// texture or pool changes the generation; tables are rows of one
    /// texture, rewritten in place). Paged volumes get their pools here,
    /// and their bricks as frames stream them.
    pub fn upload(&mut self, ctx: &Context, scene: &Scene) -> Result<(), RenderError> {
        let layouts = paging::layouts(ctx, scene)?;
        let wanted: Vec<&Arc<SpatialField>> = scene.grids().collect();
        // Grids no longer in the scene, or laid out differently now, go
        // before new ones are made, so that replacing a large volume does
        // not need room for both.
        let before: Vec<*const SpatialField> =
            self.grids.iter().map(|(v, _)| Arc::as_ptr(v)).collect();
        self.grids.retain(|(v, g)| {
            wanted
                .iter()
                .zip(&layouts)
                .any(|(w, l)| Arc::ptr_eq(v, w) && g.fits(l))
        });
        let mut grids = Vec::with_capacity(wanted.len());
        let mut made_new = 0;
        for (volume, layout) in wanted.into_iter().zip(&layouts) {
            let kept = self
                .grids
                .iter()
                .position(|(v, _)| Arc::ptr_eq(v, volume))
                .map(|i| self.grids.swap_remove(i));
            made_new += u32::from(kept.is_none());
            let made = match (kept, layout, &**volume) {
                (Some(g), ..) => Ok(g.1),
                (None, Layout::Whole { .. }, SpatialField::Structured(v)) => {
                    volume_texture::upload(ctx, v, self.mips).map(OnGpu::Whole)
                }
                (None, Layout::Paged { pool, .. }, SpatialField::Structured(v)) => {
                    PagedVolume::new(ctx, &Arc::new(v.clone()), *pool)
                        .map(|p| OnGpu::Paged(Box::new(p)))
                }
                // Laid out with the others once all are made.
                (None, ..) => Ok(OnGpu::Cells),
            };
            match made {
                Ok(on_gpu) => grids.push((Arc::clone(volume), on_gpu)),
                Err(e) => {
                    // What is on the GPU stays, unbound until an upload
                    // succeeds.
                    self.grids.extend(grids);
                    self.placed.clear();
                    self.generation += 1;
                    return Err(e);
                }
            }
        }
        self.uploads.volumes += made_new;
        self.grids = grids;
        // New textures, or the same in another order: bind groups go stale.
        let mut changed = made_new > 0
            || self.grids.len() != before.len()
            || self
                .grids
                .iter()
                .zip(&before)
                .any(|((v, _), b)| Arc::as_ptr(v) != *b);
        let placed: Vec<usize> = scene
            .volumes()
            .iter()
            .map(|p| {
                self.grids
                    .iter()
                    .position(|(v, _)| Arc::ptr_eq(v, &p.volume))
                    .unwrap_or(0)
            })
            .collect();
        changed |= placed != self.placed;
        self.placed = placed;
        if changed {
            self.lay_out_pages(ctx);
            self.lay_out_meshes(ctx);
            self.generation += 1;
        }
        for (row, placed) in scene.volumes().iter().enumerate() {
            let tf = &placed.transfer_function;
            if !matches!(&self.tables[row], Some(t) if Arc::ptr_eq(t, tf)) {
                resources::write_table(ctx, &self.table, row as u32, tf);
                self.tables[row] = Some(Arc::clone(tf));
                self.uploads.transfer_functions += 1;
            }
        }
        Ok(())
    }

    /// The pages buffer for the grids now paged, every table written.
    fn lay_out_pages(&mut self, ctx: &Context) {
        let mut words = Vec::new();
        self.page_offsets = self
            .grids
            .iter_mut()
            .map(|(_, g)| match g {
                OnGpu::Whole(_) | OnGpu::Cells => None,
                OnGpu::Paged(p) => {
                    let at = words.len() as u32;
                    words.extend(p.table());
                    p.dirty = false;
                    Some(at)
                }
            })
            .collect();
        self.pages = resources::words_u32_buffer(ctx, "pages", &words);
    }

    /// The meshes buffer for the meshes now held (their sizes were
    /// checked when they were laid out).
    fn lay_out_meshes(&mut self, ctx: &Context) {
        let mut words = Vec::new();
        self.mesh_offsets = self
            .grids
            .iter()
            .map(|(v, _)| {
                let at = words.len() as u32;
                match &**v {
                    SpatialField::Unstructured(m) => mesh::pack(m, &mut words),
                    SpatialField::Amr(a) => amr::pack(a, &mut words),
                    SpatialField::NanoVdb(g) => nanovdb::pack(g, &mut words),
                    SpatialField::Structured(_) => return None,
                }
                Some(at)
            })
            .collect();
        self.meshes = resources::words_u32_buffer(ctx, "meshes", &words);
    }

    /// Streams the paged volumes' bricks for a frame cast along `rays`:
    /// selects what its view asks for, uploads what is built (waiting as
    /// `wait` says) and writes the page tables that changed.
    pub fn stream(
        &mut self,
        ctx: &Context,
        scene: &Scene,
        plan: &MarchPlan,
        rays: &RayGen,
        (sampling, desc): (Sampling, &FrameDesc),
        wait: StreamWait,
    ) -> Result<Streaming, RenderError> {
        let mut total = Streaming::default();
        self.space_cache.retain(scene);
        let until = Instant::now()
            + match wait {
                StreamWait::Complete => std::time::Duration::ZERO,
                StreamWait::Budget { wait, .. } => wait,
            };
        let centre = desc.size.as_vec2() * 0.5;
        let eye = rays
            .eye
            .unwrap_or(rays.origin + centre.x * rays.origin_dx + centre.y * rays.origin_dy);
        let eyes: [Vec3; 1] = [eye];
        for (g, (volume, on_gpu)) in self.grids.iter_mut().enumerate() {
            let OnGpu::Paged(paged) = on_gpu else {
                continue;
            };
            let sights: Vec<Sight> = scene
                .volumes()
                .iter()
                .zip(&plan.volumes)
                .filter(|(p, _)| Arc::ptr_eq(&p.volume, volume))
                .map(|(p, vplan)| {
                    let world_to_grid = p.world_to_grid().as_mat4();
                    Sight {
                        world_to_grid,
                        grid_to_world: world_to_grid.inverse(),
                        visible: Visibility::new(
                            &p.transfer_function.table(),
                            vplan.value_lo,
                            vplan.value_scale,
                        ),
                    }
                })
                .collect();
            let lod = if sampling == Sampling::Filtered && volume.filter() != Filter::Nearest {
                plan.level_of_detail
            } else {
                0.0
            };
            let view = View {
                eyes: &eyes,
                footprint: Footprint {
                    lod,
                    width: rays.pixel_width(),
                    spread: rays.pixel_spread(desc.size),
                    step: plan.shading_step,
                },
                sights: &sights,
            };
            // The bricks the empty-space grid finds clear are refined last.
            let ranges = self.space_cache.ranges_of(volume)?;
            total.add(paged.stream(ctx, (&view, &ranges), wait, until)?);
            if paged.dirty {
                if let Some(at) = self.page_offsets.get(g).copied().flatten() {
                    let words = paged.table();
                    ctx.queue.write_buffer(
                        &self.pages,
                        u64::from(at) * 4,
                        bytemuck::cast_slice(&words),
                    );
                }
                paged.dirty = false;
            }
        }
        Ok(total)
    }

    /// How the shaders read each of the scene's volumes.
    pub fn texture_slots(&self) -> Vec<TextureSlot> {
        self.placed
            .iter()
            .map(|&g| match &self.grids[g].1 {
                OnGpu::Whole(t) => TextureSlot {
                    to_value: t.to_value,
                    ..TextureSlot::default()
                },
                OnGpu::Cells => TextureSlot {
                    mesh: Some(self.mesh_offsets[g].unwrap_or(0)),
                    ..TextureSlot::default()
                },
                OnGpu::Paged(p) => TextureSlot {
                    to_value: p.to_value,
                    pages: Some(PageSlot {
                        offset: self.page_offsets[g].unwrap_or(0),
                        levels: p.pyramid.levels(),
                        side: p.pool.side,
                        atlas: p.pool.atlas.to_array(),
                    }),
                    mesh: None,
                },
            })
            .collect()
    }

    /// Bytes the scene's volumes hold on the GPU: textures and pools, each
    /// grid once, and the page tables.
    pub fn volume_bytes(&self) -> u64 {
        let pages = if self.page_offsets.iter().any(Option::is_some) {
            self.pages.size()
        } else {
            0
        };
        let meshes = if self.mesh_offsets.iter().any(Option::is_some) {
            self.meshes.size()
        } else {
            0
        };
        self.grids.iter().map(|(_, g)| g.bytes()).sum::<u64>() + pages + meshes
    }

    /// Bytes the paged grids keep in host memory: their coarser levels.
    pub fn host_volume_bytes(&self) -> u64 {
        self.grids
            .iter()
            .map(|(_, g)| match g {
                OnGpu::Paged(p) => p.host_bytes(),
                OnGpu::Whole(_) | OnGpu::Cells => 0,
            })
            .sum()
    }

    /// Binds `background` (or the stand-in), uploading it if it is not the
    /// one bound now.
    pub fn set_background(&mut self, ctx: &Context, background: Option<&Arc<BackgroundImage>>) {
        let same = match (&self.background, background) {
            (None, None) => true,
            (Some((a, _)), Some(b)) => Arc::ptr_eq(a, b),
            _ => false,
        };
        if !same {
            self.background =
                background.map(|b| (Arc::clone(b), resources::upload_background(ctx, Some(b))));
            self.generation += 1;
        }
    }

    /// The tables with opacities corrected for this plan's primary step,
    /// rewritten where the table or the step changed.
    pub fn write_stepped_tables(&mut self, ctx: &Context, scene: &Scene, plan: &MarchPlan) {
        for (row, (placed, vplan)) in scene.volumes().iter().zip(&plan.volumes).enumerate() {
            let tf = &placed.transfer_function;
            let exponent = plan.step * vplan.inv_unit_distance;
            let current =
                matches!(&self.stepped[row], Some((t, e)) if Arc::ptr_eq(t, tf) && *e == exponent);
            if !current {
                resources::write_stepped_table(ctx, &self.table, row as u32, tf, exponent);
                self.stepped[row] = Some((Arc::clone(tf), exponent));
            }
        }
    }

    /// Makes the clear-brick distances of the scene's volumes under their
    /// tables, where they are new, and the buffer that holds them.
    pub fn find_clear_bricks(
        &mut self,
        ctx: &Context,
        scene: &Scene,
        plan: &MarchPlan,
    ) -> Result<(), RenderError> {
        let (spaces, changed) = self.space_cache.update(scene, plan)?;
        if changed {
            let list: Vec<&EmptySpace> = spaces.iter().map(Arc::as_ref).collect();
            (self.bricks, self.brick_slots) = resources::bricks_buffer(ctx, &list);
            self.generation += 1;
        }
        Ok(())
    }
}
