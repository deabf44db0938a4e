//! The uniforms the shaders read, as `#[repr(C)]` Rust structs, and the
//! constants both sides share: written here once, and given to the shaders
//! from here as WGSL modules (modules.rs): `constants`, `iso_constants`,
//! and one module per struct, listed by [`modules`] (the WGSL structs are
//! generated from the Rust ones; a test parses them and checks that WGSL
//! lays them out as Rust does).
//!
//! The passes bind these structs as read-only storage buffers, not
//! uniforms: Mesa's lavapipe folds uniform values that decide branches and
//! loop bounds into the shader it compiles, and compiles again (seconds
//! for the march) whenever they change, as they do with every head pose.
//! It does not fold storage values, and hardware drivers read both alike,
//! so no pass compiles a shader while it renders.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::context::WORKGROUP;
use super::resources::{pixel_words, BrickSlot, SurfaceSlot};
use super::volume_texture::{TextureSlot, LOD_LEVELS};
use crate::geometry::RayGen;
use crate::render::empty_space::{BRICK, LEAP_MARGIN};
use crate::render::frame::{ColorFormat, FrameDesc};
use crate::render::hits::{WHAT_NOTHING, WHAT_VOLUME};
use crate::render::iso::{same_view_offsets, SAME_VIEW_SAMPLES, SEARCH_MARGIN_STEPS};
use crate::render::march_plan::{FieldKind, MarchPlan, VolumePlan};
use crate::render::settings::{
    Shading, DIRECTIONAL_STEPS, MAX_CLIP_PLANES, SHADOW_AMBIENT, SHADOW_STEPS,
};
use crate::render::shapes::packed::{
    COLOR_IMAGE, FLAG_ALBEDO, FLAG_BLEND, FLAG_IMAGE, FLAG_MASK, FLAG_NORMALS, FLAG_OPACITY,
    FLAG_OPACITY_IMAGE, FLAG_PBR, KIND_CONE, KIND_CURVE, KIND_SPHERE, KIND_TRIANGLE, OPACITY_IMAGE,
    SHAPE_WORDS, TRAVERSAL_STACK,
};
use crate::render::shapes::{MAX_TRANSLUCENT, MIN_ROUGHNESS, SURFACE_PASSES};
use crate::render::stereo::Reprojection;
use crate::render::warp::SOLID;
use crate::render::{Lamp, RenderSettings, Spot, SurfaceShading, MAX_LAMPS};
use crate::scene::{
    Filter, AMR_ABSENT, AMR_EMPTY, CELL_TOLERANCE, MAX_AMR_LEVELS, MAX_VOLUMES, MESH_STACK,
    NEWTON_STEPS, NEWTON_TOLERANCE, TABLE_SIZE, WALK_STEPS, WALK_WORDS,
};

/// The WGSL type of a uniform field's Rust type.
trait WgslType {
    const WGSL: &'static str;
}

macro_rules! wgsl_types {
    ($($rust:ty => $wgsl:literal),* $(,)?) => {
        $(impl WgslType for $rust { const WGSL: &'static str = $wgsl; })*
    };
}

// The WGSL types of the clip planes and volumes below name the counts.
const _: () = assert!(MAX_CLIP_PLANES == 8 && MAX_VOLUMES == 8 && MAX_LAMPS == 8);

wgsl_types! {
    f32 => "f32", u32 => "u32", i32 => "i32",
    [f32; 3] => "vec3f", [f32; 4] => "vec4f", [u32; 2] => "vec2u", [u32; 3] => "vec3u",
    [u32; 4] => "vec4u",
    [i32; 2] => "vec2i",
    [[f32; 4]; MAX_CLIP_PLANES] => "array<vec4f, 8>",
    [VolumeSlot; MAX_VOLUMES] => "array<VolumeSlot, 8>",
    [LampSlot; MAX_LAMPS] => "array<LampSlot, 8>",
}

/// Defines a uniform struct, its WGSL declaration (module `$module`,
/// importing the modules of the structs it holds), and the list of its
/// fields with their byte offsets, which the layout test holds against
/// what WGSL makes of the declaration. Fields named `_...` pad the Rust
/// struct to WGSL's size and are not declared.
macro_rules! uniform {
    ($(#[$doc:meta])* $name:ident = $module:literal imports [$($import:literal),*] {
        $($(#[$fdoc:meta])* $field:ident: $ty:ty,)*
    }) => {
        $(#[$doc])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
        pub(super) struct $name {
            $($(#[$fdoc])* pub $field: $ty,)*
        }

        impl $name {
            /// Field names and offsets, padding included.
            #[cfg(test)]
            const FIELDS: &'static [(&'static str, usize)] =
                &[$((stringify!($field), std::mem::offset_of!($name, $field)),)*];

            /// The WGSL module declaring it.
            const MODULE: &'static str = $module;

            /// `struct Name { field: type, ... }` in WGSL, after the
            /// imports of the structs it holds.
            fn wgsl() -> String {
                let fields: &[(&str, &str)] = &[$((stringify!($field), <$ty as WgslType>::WGSL),)*];
                let imports: &[&str] = &[$($import),*];
                let mut out = String::from("// Generated from src/render/gpu/uniforms.rs.\n");
                if !imports.is_empty() {
                    out += &format!("// #import {}\n", imports.join(", "));
                }
                out += &format!("struct {} {{\n", stringify!($name));
                for (field, ty) in fields.iter().filter(|(f, _)| !f.starts_with('_')) {
                    out += &format!("    {field}: {ty},\n");
                }
                out + "}\n"
            }
        }
    };
}

uniform! {
    /// `VolumeSlot` in shaders/volume.wgsl: how one volume is sampled.
    VolumeSlot = "volume_slot" imports [] {
        /// Rows of the world-to-grid affine map, applied to (p, 1).
        world_to_grid_x: [f32; 4],
        world_to_grid_y: [f32; 4],
        world_to_grid_z: [f32; 4],
        dims: [u32; 3],
        /// One of the FILTER_ codes.
        sampling: u32,
        /// Field value mapped to the first table entry.
        value_lo: f32,
        /// 1 / (value hi - value lo).
        value_scale: f32,
        inv_unit_distance: f32,
        /// Where this volume's bricks start in `bricks`.
        brick_offset: u32,
        /// Bricks per axis (render::empty_space).
        bricks: [u32; 3],
        /// Texel to field value: value = texel * scale + offset.
        texel_scale: f32,
        texel_offset: f32,
        /// Levels of a paged volume's chain (0: the volume is one
        /// texture; src/render/gpu/paging.rs).
        levels: u32,
        /// Slots per row and column of its pool texture.
        atlas_bricks: [u32; 2],
        /// Voxels a brick covers per axis (its texels hold one more on
        /// the axes cut into several bricks).
        brick_side: [u32; 3],
        /// Its page table's first word in `pages`.
        page_offset: u32,
        /// An unstructured volume's first word in `meshes`.
        mesh_offset: u32,
        _pad: [u32; 3],
    }
}

uniform! {
    /// `RayUniforms` in shaders/volume.wgsl (`params`): one eye's rays and
    /// the march plan.
    RayUniforms = "ray_uniforms" imports ["volume_slot", "lamp_slot"] {
        /// The ray of pixel (0, 0) and its change per pixel.
        ray_origin: [f32; 3],
        /// Primary step length, world units.
        step: f32,
        ray_origin_dx: [f32; 3],
        /// Step of shadow and directional rays.
        shading_step: f32,
        ray_origin_dy: [f32; 3],
        ao_radius: f32,
        ray_dir: [f32; 3],
        /// Opacity at which a ray stops.
        termination: f32,
        ray_dir_dx: [f32; 3],
        /// Entries of `directions` in use.
        direction_count: u32,
        ray_dir_dy: [f32; 3],
        /// One of the SHADE_ codes.
        shading: u32,
        /// Towards the parallel light.
        light: [f32; 3],
        /// One of the FORMAT_ codes.
        color_format: u32,
        /// Straight RGBA behind the volume.
        background: [f32; 4],
        /// Depth is measured from `eye` if `has_eye`, else from each ray's
        /// origin.
        eye: [f32; 3],
        has_eye: u32,
        width: u32,
        height: u32,
        /// Accumulated opacity at which depth is taken.
        depth_threshold: f32,
        /// The camera's clip range along each unit ray: t_near, t_far.
        t_near: f32,
        t_far: f32,
        clip_count: u32,
        /// Entries of `volumes` in use.
        volume_count: u32,
        /// 1: the background is the image bound beside, not `background`.
        has_background_image: u32,
        /// Multiplies every shaded sample.
        light_color: [f32; 3],
        /// The most steps a primary ray takes.
        max_steps: u32,
        /// 1: primary rays leap over clear bricks.
        skipping: u32,
        /// Level of detail under filtered sampling (0: full detail).
        lod: f32,
        /// A pixel's footprint along a ray at t: ray_width + t ray_spread
        /// (world units), at the image's centre.
        ray_width: f32,
        ray_spread: f32,
        /// Towards the surfaces' directional light; where the surfaces
        /// buffer's BVH nodes (none: 0), primitives and shapes begin
        /// (render/shapes/packed.rs).
        surface_light: [f32; 3],
        surface_nodes: u32,
        /// Color times strength of the surfaces' light.
        surface_light_color: [f32; 3],
        surface_prims: u32,
        /// Lights every surface (the renderer's ambient light).
        ambient: [f32; 3],
        surface_shapes: u32,
        /// One of the SURFACE_LIT_ codes: which lights the surfaces see
        /// beside the point and spot lights.
        surface_lighting: u32,
        /// Entries of `lamps` in use.
        lamp_count: u32,
        /// Under SURFACE_LIT_EYE_BLEND, the eye light's share.
        eye_blend: f32,
        /// Words per pixel of samples_out: the samples taken, then, where
        /// the frame asks for hits, the pixel's HitRecord (render/hits.rs).
        pixel_words: u32,
        /// Under data-parallel rendering (`has_part`, render::Part): world
        /// point to the parts' frame (rows applied to (p, 1)), the box the
        /// steps are laid along, and the box whose samples this renderer
        /// takes.
        part_x: [f32; 4],
        part_y: [f32; 4],
        part_z: [f32; 4],
        whole_lo: [f32; 3],
        has_part: u32,
        whole_hi: [f32; 3],
        _part_pad: u32,
        owned_lo: [f32; 3],
        _owned_pad: u32,
        owned_hi: [f32; 3],
        _owned_hi_pad: u32,
        /// Clip planes (n, d): keep dot(n, p) < d.
        clip: [[f32; 4]; MAX_CLIP_PLANES],
        volumes: [VolumeSlot; MAX_VOLUMES],
        /// The surfaces' point and spot lights.
        lamps: [LampSlot; MAX_LAMPS],
    }
}

uniform! {
    /// `LampSlot` in shaders/surface.wgsl: a point or spot light
    /// (render::Lamp).
    LampSlot = "lamp_slot" imports [] {
        position: [f32; 3],
        /// 1: a spot light.
        spot: u32,
        /// Color times intensity.
        color: [f32; 3],
        cos_outer: f32,
        /// The way a spot's light travels.
        direction: [f32; 3],
        cos_inner: f32,
    }
}

uniform! {
    /// `Stereo` in shaders/stereo.wgsl: what the re-projection and the
    /// compositing pass share (src/render/stereo/epipolar.rs explains
    /// the epipole and lambda).
    Stereo = "stereo_uniforms" imports [] {
        /// Right-eye pixel (x, y) of world point p is
        /// (dot(right_x, (p, 1)), dot(right_y, (p, 1))) / dot(right_w, (p, 1)).
        right_x: [f32; 4],
        right_y: [f32; 4],
        right_w: [f32; 4],
        /// Straight RGBA behind the volume.
        background: [f32; 4],
        /// The epipole (x, y, w, unused) in homogeneous pixels.
        epipole: [f32; 4],
        /// Right-eye depth is the distance from here.
        right_eye: [f32; 3],
        depth_threshold: f32,
        /// lambda at the nearest and the farthest visible depth.
        lambda_near: f32,
        lambda_far: f32,
        /// Layers of each family; the rows family's follow the columns'.
        layers: i32,
        /// Bit 0: the columns family is written, bit 1: the rows family.
        families: u32,
        /// The first left pixel cast and how many.
        first: [i32; 2],
        cast_pixels: [u32; 2],
        width: u32,
        height: u32,
        color_format: u32,
        /// Opacity at which a right pixel stops compositing.
        termination: f32,
        /// Whether the composite writes depth.
        has_depth: u32,
        /// Whether segments record their right-eye distances (for the
        /// depth channel, and to place the right eye's surfaces among
        /// them).
        segment_depths: u32,
        /// The right eye's clip range along each unit ray.
        right_t_near: f32,
        right_t_far: f32,
        /// The right eye's ray of pixel (0, 0) and its change per pixel
        /// (xyz), as `RayUniforms` holds the left eye's: its surfaces are
        /// ray traced, not re-projected.
        right_origin: [f32; 4],
        right_origin_dx: [f32; 4],
        right_origin_dy: [f32; 4],
        right_dir: [f32; 4],
        right_dir_dx: [f32; 4],
        right_dir_dy: [f32; 4],
    }
}

uniform! {
    /// `Warp` in shaders/warp.wgsl: a source view, a target view and how
    /// one is shown from the other.
    Warp = "warp_uniforms" imports [] {
        /// The target's rays (xyz; w unused), as `RayUniforms` holds them.
        to_origin: [f32; 4],
        to_origin_dx: [f32; 4],
        to_origin_dy: [f32; 4],
        to_direction: [f32; 4],
        to_direction_dx: [f32; 4],
        to_direction_dy: [f32; 4],
        /// xyz: where depth is measured from; w: 1 if the view has an eye.
        to_eye: [f32; 4],
        from_origin: [f32; 4],
        from_origin_dx: [f32; 4],
        from_origin_dy: [f32; 4],
        from_direction: [f32; 4],
        from_direction_dx: [f32; 4],
        from_direction_dy: [f32; 4],
        from_eye: [f32; 4],
        /// Each view's projector: inverse matrix columns, and the centre
        /// (xyz) with w = 0 for rays through it, 1 for parallel rays.
        from_inverse_x: [f32; 4],
        from_inverse_y: [f32; 4],
        from_inverse_z: [f32; 4],
        from_centre: [f32; 4],
        to_inverse_x: [f32; 4],
        to_inverse_y: [f32; 4],
        to_inverse_z: [f32; 4],
        to_centre: [f32; 4],
        /// The quad's plane: the source's image normal and the scene's centre.
        normal: [f32; 4],
        focus: [f32; 4],
        /// The scene's bounds.
        lo: [f32; 4],
        hi: [f32; 4],
        from_size: [u32; 2],
        to_size: [u32; 2],
        nodes: [u32; 2],
        spacing: u32,
        layers: u32,
        steps: u32,
        depth_threshold: f32,
        /// The target's clip distances.
        near: f32,
        far: f32,
    }
}

uniform! {
    /// `Iso` in shaders/iso.wgsl: one view's rays at one volume's
    /// isosurface, and how it is shaded (src/render/iso/).
    Iso = "iso_uniforms" imports [] {
        /// The ray of pixel (0, 0) and its change per pixel (xyz).
        ray_origin: [f32; 4],
        ray_origin_dx: [f32; 4],
        ray_origin_dy: [f32; 4],
        ray_dir: [f32; 4],
        ray_dir_dx: [f32; 4],
        ray_dir_dy: [f32; 4],
        /// xyz: where depth is measured from; w: 1 if the view has an eye.
        eye: [f32; 4],
        /// Rows of the world-to-grid affine map, applied to (p, 1).
        to_grid_x: [f32; 4],
        to_grid_y: [f32; 4],
        to_grid_z: [f32; 4],
        /// The flat color (rgb).
        color: [f32; 4],
        /// Towards the light (xyz); w: 1 if given, else a headlight.
        light: [f32; 4],
        /// Ambient, diffuse, specular, shininess.
        shading: [f32; 4],
        background: [f32; 4],
        /// The grid's vertices per axis (xyz).
        dims: [u32; 4],
        /// The grid-space box outside which the field cannot cross the
        /// iso-value (xyz; render::iso::crossing_box).
        box_lo: [f32; 4],
        box_hi: [f32; 4],
        isovalue: f32,
        /// The march's step, world units.
        step: f32,
        near: f32,
        far: f32,
        width: u32,
        height: u32,
        secant_steps: u32,
        /// 0 trilinear, 1 tricubic B-spline.
        filtering: u32,
        /// 1: color by mean curvature.
        curvature: u32,
        radius: f32,
        color_format: u32,
        /// Texel to field value: value = texel * scale + offset.
        texel_scale: f32,
        texel_offset: f32,
        _pad: [u32; 3],
    }
}

impl VolumeSlot {
    fn new(plan: &VolumePlan, bricks: BrickSlot, texture: TextureSlot) -> Self {
        let (brick_side, atlas_bricks, levels, page_offset) =
            texture.pages.map_or(([1; 3], [1; 2], 0, 0), |p| {
                (p.side.to_array(), p.atlas, p.levels, p.offset)
            });
        let [x, y, z] = plan.world_to_grid.map(|r| r.to_array());
        Self {
            world_to_grid_x: x,
            world_to_grid_y: y,
            world_to_grid_z: z,
            dims: plan.dims.to_array(),
            sampling: match plan.kind {
                FieldKind::Grid => plan.filter.code(),
                FieldKind::Cells => FILTER_CELLS,
                FieldKind::Amr => FILTER_AMR,
                FieldKind::Vdb => FILTER_VDB,
            },
            value_lo: plan.value_lo,
            value_scale: plan.value_scale,
            inv_unit_distance: plan.inv_unit_distance,
            brick_offset: bricks.offset,
            bricks: bricks.bricks,
            texel_scale: texture.to_value.slope,
            texel_offset: texture.to_value.intercept,
            levels,
            atlas_bricks,
            brick_side,
            page_offset,
            mesh_offset: texture.mesh.unwrap_or(0),
            _pad: [0; 3],
        }
    }
}

impl RayUniforms {
    /// `bricks`: each volume's place in the bricks buffer, when `plan`
    /// skips; `textures`: how each volume's texture is read; `surfaces`:
    /// the surfaces buffer's parts, lit as `settings` say.
    pub fn new(
        rays: &RayGen,
        plan: &MarchPlan,
        (bricks, textures, surfaces): (&[BrickSlot], &[TextureSlot], SurfaceSlot),
        settings: &RenderSettings,
        desc: &FrameDesc,
    ) -> Self {
        let (size, format) = (desc.size, desc.color);
        let v = |v: Vec3| v.to_array();
        let mut clip = [[0.0; 4]; MAX_CLIP_PLANES];
        for (slot, plane) in clip.iter_mut().zip(&plan.clip_planes) {
            *slot = plane.to_array();
        }
        let mut volumes = [VolumeSlot::default(); MAX_VOLUMES];
        for (i, (slot, volume)) in volumes.iter_mut().zip(&plan.volumes).enumerate() {
            *slot = VolumeSlot::new(
                volume,
                bricks.get(i).copied().unwrap_or_default(),
                textures.get(i).copied().unwrap_or_default(),
            );
        }
        let skipping = plan.skipping && bricks.len() == plan.volumes.len();
        Self {
            ray_origin: v(rays.origin),
            step: plan.step,
            ray_origin_dx: v(rays.origin_dx),
            shading_step: plan.shading_step,
            ray_origin_dy: v(rays.origin_dy),
            ao_radius: plan.ao_radius,
            ray_dir: v(rays.direction),
            termination: plan.termination,
            ray_dir_dx: v(rays.direction_dx),
            direction_count: plan.directions.len() as u32,
            ray_dir_dy: v(rays.direction_dy),
            shading: plan.shading.code(),
            light: v(plan.light),
            color_format: format.code(),
            background: plan.background.to_array(),
            eye: rays.eye.unwrap_or_default().to_array(),
            has_eye: u32::from(rays.eye.is_some()),
            width: size.x,
            height: size.y,
            depth_threshold: plan.depth_threshold,
            t_near: rays.t_near,
            t_far: rays.t_far,
            clip_count: plan.clip_planes.len() as u32,
            part_x: plan.part.map_or([0.0; 4], |p| p.to_box[0].to_array()),
            part_y: plan.part.map_or([0.0; 4], |p| p.to_box[1].to_array()),
            part_z: plan.part.map_or([0.0; 4], |p| p.to_box[2].to_array()),
            whole_lo: plan.part.map_or([0.0; 3], |p| v(p.whole.0)),
            has_part: u32::from(plan.part.is_some()),
            whole_hi: plan.part.map_or([0.0; 3], |p| v(p.whole.1)),
            owned_lo: plan.part.map_or([0.0; 3], |p| v(p.owned.0)),
            owned_hi: plan.part.map_or([0.0; 3], |p| v(p.owned.1)),
            _part_pad: 0,
            _owned_pad: 0,
            _owned_hi_pad: 0,
            volume_count: plan.volumes.len() as u32,
            has_background_image: u32::from(plan.has_background_image),
            light_color: plan.light_color.to_array(),
            max_steps: plan.max_steps,
            skipping: u32::from(skipping),
            lod: plan.level_of_detail,
            ray_width: rays.pixel_width(),
            ray_spread: rays.pixel_spread(size),
            surface_light: v(settings.light),
            surface_nodes: surfaces.nodes,
            surface_light_color: v(settings.light_color),
            surface_prims: surfaces.prims,
            ambient: v(settings.ambient),
            surface_shapes: surfaces.shapes,
            surface_lighting: if let SurfaceShading::EyeLight { .. } = settings.surface_shading {
                SURFACE_LIT_EYE_BLEND
            } else if settings.headlight {
                SURFACE_LIT_FROM_EYE
            } else if settings.directional {
                SURFACE_LIT_DIRECTIONAL
            } else {
                SURFACE_LIT_BY_LAMPS
            },
            lamp_count: settings.lamps.len().min(MAX_LAMPS) as u32,
            eye_blend: match settings.surface_shading {
                SurfaceShading::EyeLight { blend } => blend,
                SurfaceShading::Lights => 0.0,
            },
            pixel_words: pixel_words(desc.hits),
            clip,
            volumes,
            lamps: lamp_slots(&settings.lamps),
        }
    }
}

impl Stereo {
    /// `surfaces`: the world has surfaces, which the composite places
    /// among the segments by their distances.
    pub fn new(
        r: &Reprojection,
        format: ColorFormat,
        settings: &RenderSettings,
        depth: bool,
        surfaces: bool,
    ) -> Self {
        let plan = &r.plan;
        let rays = &r.right_rays;
        let v = |v: Vec3| v.extend(0.0).to_array();
        Self {
            right_x: r.right_x.to_array(),
            right_y: r.right_y.to_array(),
            right_w: r.right_w.to_array(),
            background: settings.background.to_array(),
            epipole: plan.epipole.as_vec3().extend(0.0).to_array(),
            right_eye: r.right_eye.to_array(),
            depth_threshold: settings.depth_threshold,
            lambda_near: plan.lambda[0] as f32,
            lambda_far: plan.lambda[1] as f32,
            layers: r.layers as i32,
            families: u32::from(plan.families[0]) | u32::from(plan.families[1]) << 1,
            first: plan.first.to_array(),
            cast_pixels: plan.cast.to_array(),
            width: r.size.x,
            height: r.size.y,
            color_format: format.code(),
            termination: settings.termination,
            has_depth: u32::from(depth),
            segment_depths: u32::from(depth || surfaces),
            right_t_near: rays.t_near,
            right_t_far: rays.t_far,
            right_origin: v(rays.origin),
            right_origin_dx: v(rays.origin_dx),
            right_origin_dy: v(rays.origin_dy),
            right_dir: v(rays.direction),
            right_dir_dx: v(rays.direction_dx),
            right_dir_dy: v(rays.direction_dy),
        }
    }
}

fn lamp_slots(lamps: &[Lamp]) -> [LampSlot; MAX_LAMPS] {
    let mut slots = [LampSlot::default(); MAX_LAMPS];
    for (slot, lamp) in slots.iter_mut().zip(lamps) {
        let spot = lamp.spot.unwrap_or(Spot {
            direction: Vec3::NEG_Z,
            cos_outer: -1.0,
            cos_inner: -1.0,
        });
        *slot = LampSlot {
            position: lamp.position.to_array(),
            spot: u32::from(lamp.spot.is_some()),
            color: lamp.color.to_array(),
            cos_outer: spot.cos_outer,
            direction: spot.direction.to_array(),
            cos_inner: spot.cos_inner,
        };
    }
    slots
}

/// The sampling code of an unstructured volume: inside its cells
/// (shaders/volume.wgsl `mesh_value`), past Filter's codes 0 and 1.
const FILTER_CELLS: u32 = 2;
/// The sampling code of an AMR volume: among its cells (shaders/amr.wgsl).
const FILTER_AMR: u32 = 3;
/// The sampling code of a NanoVDB grid: through its tree
/// (shaders/nanovdb.wgsl).
const FILTER_VDB: u32 = 4;

/// Which lights the surfaces see besides the point and spot lights: the
/// directional light, a light at the eye (the world has none), or none.
const SURFACE_LIT_DIRECTIONAL: u32 = 0;
const SURFACE_LIT_FROM_EYE: u32 = 1;
const SURFACE_LIT_BY_LAMPS: u32 = 2;
const SURFACE_LIT_EYE_BLEND: u32 = 3;

/// The directions storage buffer: vec4 per direction, at least one entry
/// because WGSL storage arrays cannot be bound empty.
pub(super) fn directions(dirs: &[Vec3]) -> Vec<[f32; 4]> {
    let mut out: Vec<[f32; 4]> = dirs.iter().map(|d| d.extend(0.0).to_array()).collect();
    if out.is_empty() {
        out.push([0.0; 4]);
    }
    out
}

/// The generated WGSL modules, as (name, source): the shared constants,
/// the multi-view panel's constants, and each uniform struct.
pub(super) fn modules() -> Vec<(&'static str, String)> {
    vec![
        ("constants", constants()),
        ("iso_constants", iso_constants()),
        (VolumeSlot::MODULE, VolumeSlot::wgsl()),
        (LampSlot::MODULE, LampSlot::wgsl()),
        (RayUniforms::MODULE, RayUniforms::wgsl()),
        (Stereo::MODULE, Stereo::wgsl()),
        (Warp::MODULE, Warp::wgsl()),
        (Iso::MODULE, Iso::wgsl()),
    ]
}

/// The constants Rust and the shaders share.
fn constants() -> String {
    let u32s = [
        ("WORKGROUP", WORKGROUP),
        ("TABLE_SIZE", TABLE_SIZE as u32),
        ("MAX_VOLUMES", MAX_VOLUMES as u32),
        ("SHADOW_STEPS", SHADOW_STEPS),
        ("DIRECTIONAL_STEPS", DIRECTIONAL_STEPS),
        ("SHADE_NONE", Shading::None.code()),
        ("SHADE_SHADOWS", Shading::Shadows.code()),
        ("SHADE_AO", Shading::Ao.code()),
        ("SHADE_SHADOWS_AO", Shading::ShadowsAo.code()),
        ("SHADE_DIRECTIONAL", Shading::Directional(0).code()),
        ("FORMAT_RGBA8", ColorFormat::Rgba8.code()),
        ("FORMAT_SRGBA8", ColorFormat::Srgba8.code()),
        ("FORMAT_RGBA32F", ColorFormat::Rgba32F.code()),
        ("FILTER_LINEAR", Filter::Linear.code()),
        ("FILTER_NEAREST", Filter::Nearest.code()),
        ("FILTER_CELLS", FILTER_CELLS),
        ("FILTER_AMR", FILTER_AMR),
        ("FILTER_VDB", FILTER_VDB),
        ("AMR_ABSENT", AMR_ABSENT),
        ("AMR_EMPTY", AMR_EMPTY),
        ("MAX_AMR_LEVELS", MAX_AMR_LEVELS as u32),
        ("MESH_STACK", MESH_STACK as u32),
        ("NEWTON_STEPS", NEWTON_STEPS),
        ("WALK_STEPS", WALK_STEPS),
        ("WALK_WORDS", WALK_WORDS as u32),
        ("BRICK", BRICK),
        ("LOD_LEVELS", LOD_LEVELS),
        ("KIND_TRIANGLE", KIND_TRIANGLE),
        ("KIND_SPHERE", KIND_SPHERE),
        ("KIND_CONE", KIND_CONE),
        ("KIND_CURVE", KIND_CURVE),
        ("FLAG_ALBEDO", FLAG_ALBEDO),
        ("FLAG_NORMALS", FLAG_NORMALS),
        ("FLAG_IMAGE", FLAG_IMAGE),
        ("FLAG_PBR", FLAG_PBR),
        ("FLAG_OPACITY", FLAG_OPACITY),
        ("FLAG_OPACITY_IMAGE", FLAG_OPACITY_IMAGE),
        ("FLAG_BLEND", FLAG_BLEND),
        ("FLAG_MASK", FLAG_MASK),
        ("SHAPE_WORDS", SHAPE_WORDS as u32),
        ("COLOR_IMAGE", COLOR_IMAGE as u32),
        ("OPACITY_IMAGE", OPACITY_IMAGE as u32),
        ("TRAVERSAL_STACK", TRAVERSAL_STACK),
        ("MAX_TRANSLUCENT", MAX_TRANSLUCENT),
        ("SURFACE_PASSES", SURFACE_PASSES),
        ("SURFACE_LIT_DIRECTIONAL", SURFACE_LIT_DIRECTIONAL),
        ("SURFACE_LIT_FROM_EYE", SURFACE_LIT_FROM_EYE),
        ("SURFACE_LIT_BY_LAMPS", SURFACE_LIT_BY_LAMPS),
        ("SURFACE_LIT_EYE_BLEND", SURFACE_LIT_EYE_BLEND),
        ("WHAT_VOLUME", WHAT_VOLUME),
        ("WHAT_NOTHING", WHAT_NOTHING),
    ];
    let mut out = String::from("// Generated from src/render/gpu/uniforms.rs.\n");
    for (name, value) in u32s {
        out += &format!("const {name}: u32 = {value}u;\n");
    }
    // Rust's shortest round-trip form with the f suffix is the same f32.
    out += &format!("const SHADOW_AMBIENT: f32 = {SHADOW_AMBIENT:?}f;\n");
    out += &format!("const MIN_ROUGHNESS: f32 = {MIN_ROUGHNESS:?}f;\n");
    out += &format!("const PI: f32 = {:?}f;\n", std::f32::consts::PI);
    out += &format!("const LEAP_MARGIN: f32 = {LEAP_MARGIN:?}f;\n");
    out += &format!("const SOLID: f32 = {SOLID:?}f;\n");
    out += &format!("const NEWTON_TOLERANCE: f32 = {NEWTON_TOLERANCE:?}f;\n");
    out += &format!("const CELL_TOLERANCE: f32 = {CELL_TOLERANCE:?}f;\n");
    out
}

/// The spectral pass's: steps before its samples' surfaces at which it
/// searches, how many samples, and where it looks for them.
fn iso_constants() -> String {
    let mut out = String::from("// Generated from src/render/gpu/uniforms.rs.\n");
    out += &format!("const SEARCH_MARGIN_STEPS: f32 = {SEARCH_MARGIN_STEPS:?}f;\n");
    out += &format!("const SAME_VIEW_SAMPLES: u32 = {SAME_VIEW_SAMPLES}u;\n");
    let offsets = same_view_offsets();
    let listed: Vec<String> = offsets
        .iter()
        .map(|(dx, dy)| format!("vec2i({dx}, {dy})"))
        .collect();
    out += &format!("const SAME_VIEW_OFFSET_COUNT: u32 = {}u;\n", offsets.len());
    out += &format!(
        "var<private> SAME_VIEW_OFFSETS: array<vec2i, {}> = array<vec2i, {}>({});\n",
        offsets.len(),
        offsets.len(),
        listed.join(", ")
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu::modules::Library;
    use wgpu::naga;

    /// Struct module `module` with the modules it imports.
    fn composed(module: &str) -> String {
        let mut lib = Library::default();
        for (name, source) in modules() {
            lib.add(name, source);
        }
        lib.compose(module).unwrap()
    }

    /// The members of WGSL struct `name` as (name, offset), and its size.
    fn wgsl_struct(source: &str, name: &str) -> (Vec<(String, usize)>, usize) {
        let module = naga::front::wgsl::parse_str(source).unwrap_or_else(|e| {
            panic!("{}", e.emit_to_string(source));
        });
        for (_, ty) in module.types.iter() {
            if ty.name.as_deref() != Some(name) {
                continue;
            }
            if let naga::TypeInner::Struct { members, span } = &ty.inner {
                let fields = members
                    .iter()
                    .map(|m| (m.name.clone().unwrap_or_default(), m.offset as usize))
                    .collect();
                return (fields, *span as usize);
            }
        }
        panic!("no struct {name} in the shader");
    }

    fn same_layout(rust: &[(&str, usize)], size: usize, source: &str, name: &str) {
        let (wgsl, span) = wgsl_struct(source, name);
        let rust: Vec<(String, usize)> = rust
            .iter()
            .filter(|(f, _)| !f.starts_with('_'))
            .map(|(f, o)| (f.to_string(), *o))
            .collect();
        assert_eq!(wgsl, rust, "{name}: WGSL members differ from Rust's");
        assert_eq!(span, size, "{name}: WGSL size differs from Rust's");
    }

    #[test]
    fn the_wgsl_structs_mirror_the_rust_ones() {
        let rays = composed(RayUniforms::MODULE);
        same_layout(
            RayUniforms::FIELDS,
            size_of::<RayUniforms>(),
            &rays,
            "RayUniforms",
        );
        same_layout(LampSlot::FIELDS, size_of::<LampSlot>(), &rays, "LampSlot");
        same_layout(
            VolumeSlot::FIELDS,
            size_of::<VolumeSlot>(),
            &rays,
            "VolumeSlot",
        );
        same_layout(
            Stereo::FIELDS,
            size_of::<Stereo>(),
            &composed(Stereo::MODULE),
            "Stereo",
        );
        same_layout(
            Warp::FIELDS,
            size_of::<Warp>(),
            &composed(Warp::MODULE),
            "Warp",
        );
        same_layout(Iso::FIELDS, size_of::<Iso>(), &composed(Iso::MODULE), "Iso");
    }

    #[test]
    fn the_shadow_ambient_constant_is_the_same_f32() {
        let c = constants();
        let line = c.lines().find(|l| l.contains("SHADOW_AMBIENT")).unwrap();
        let literal = line.split('=').nth(1).unwrap().trim().trim_end_matches(";");
        let parsed: f32 = literal.trim_end_matches('f').parse().unwrap();
        assert_eq!(parsed.to_bits(), SHADOW_AMBIENT.to_bits());
    }
}
