//! The scene on the GPU: its volumes as textures, its transfer functions
//! as rows of one table texture, the background image and the clear-brick
//! distances and the surfaces' BVH, uploaded when a scene brings new ones
//! and kept otherwise.
//! Passes bind these; `generation` tells them when a bind group made
//! before binds something no longer current.

use std::sync::Arc;

use super::context::Context;
use super::resources::{self, BrickSlot, SurfaceSlot};
use super::volume_texture::{self, TextureSlot, VolumeTexture};
use crate::render::empty_space::{EmptySpace, SpaceCache};
use crate::render::march_plan::MarchPlan;
use crate::render::shapes::ShapeSet;
use crate::render::{BackgroundImage, RenderError};
use crate::scene::{PlacedShape, Scene, StructuredVolume, TransferFunction, MAX_VOLUMES};

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
    /// The scene's volumes on the GPU, in its order.
    volumes: Vec<(Arc<StructuredVolume>, VolumeTexture)>,
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
        Self {
            mips: false,
            volumes: Vec::new(),
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
        self.volumes
            .get(i)
            .map_or(&self.no_volume, |(_, t)| &t.view)
    }

    /// The first volume's texture, if the scene has one.
    pub fn first_volume(&self) -> Option<&VolumeTexture> {
        self.volumes.first().map(|(_, t)| t)
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
        let packed = ShapeSet::build(shapes)?.pack()?;
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
        self.volumes.clear();
        self.generation += 1;
    }

    /// From now on volumes carry their mip chains: those on the GPU are
    /// uploaded again on the next upload.
    pub fn use_mips(&mut self) {
        if !self.mips {
            self.mips = true;
            self.volumes.clear();
            self.generation += 1;
        }
    }

    /// Uploads whatever of the scene is not on the GPU (a new volume
    /// texture changes the generation; tables are rows of one texture,
    /// rewritten in place).
    pub fn upload(&mut self, ctx: &Context, scene: &Scene) -> Result<(), RenderError> {
        let mut volumes = Vec::with_capacity(scene.volumes().len());
        for placed in scene.volumes() {
            // A grid placed twice is one texture.
            let kept = volumes
                .iter()
                .chain(&self.volumes)
                .find(|(v, _)| Arc::ptr_eq(v, &placed.volume))
                .map(|(_, texture)| texture.clone());
            let texture = match kept {
                Some(t) => t,
                None => {
                    // Textures no longer in the scene go before new ones
                    // are made, so that replacing a large volume does not
                    // need room for both.
                    self.volumes
                        .retain(|(v, _)| scene.volumes().iter().any(|p| Arc::ptr_eq(v, &p.volume)));
                    self.uploads.volumes += 1;
                    volume_texture::upload(ctx, &placed.volume, self.mips)?
                }
            };
            volumes.push((Arc::clone(&placed.volume), texture));
        }
        let changed = volumes.len() != self.volumes.len()
            || volumes
                .iter()
                .zip(&self.volumes)
                .any(|((a, _), (b, _))| !Arc::ptr_eq(a, b));
        self.volumes = volumes;
        for (row, placed) in scene.volumes().iter().enumerate() {
            let tf = &placed.transfer_function;
            if !matches!(&self.tables[row], Some(t) if Arc::ptr_eq(t, tf)) {
                resources::write_table(ctx, &self.table, row as u32, tf);
                self.tables[row] = Some(Arc::clone(tf));
                self.uploads.transfer_functions += 1;
            }
        }
        if changed {
            self.generation += 1;
        }
        Ok(())
    }

    /// How the shaders read each of the scene's volume textures.
    pub fn texture_slots(&self) -> Vec<TextureSlot> {
        self.volumes.iter().map(|(_, t)| t.slot()).collect()
    }

    /// Bytes the scene's volume textures hold on the GPU, each texture
    /// once.
    pub fn volume_bytes(&self) -> u64 {
        let v = &self.volumes;
        v.iter()
            .enumerate()
            .filter(|(i, (a, _))| !v[..*i].iter().any(|(b, _)| Arc::ptr_eq(a, b)))
            .map(|(_, (_, t))| t.bytes)
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
