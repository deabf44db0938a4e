//! What a scene has that the GPU passes are compiled for, as one key, and
//! the pipelines a pass compiles from it. Every pass that marches volumes
//! or meets surfaces (ray casting, capture, re-projection, compositing)
//! takes its pipeline from a [`Keyed`] with the frame's [`SceneKey`], so
//! no pass carries code for what its scene lacks: software Vulkan runs a
//! shader that merely contains the surfaces' traversal several times
//! slower, whether or not a ray takes it. A feature added to the scene is
//! added here once, as a field and its override constant.

use std::sync::OnceLock;

use super::bindings::GroupLayout;
use super::context::Context;
use super::paging;
use super::shaders::compute_pipeline;
use crate::render::{RenderError, RenderSettings, Sampling};
use crate::scene::Scene;

/// The scene-dependent variant of a pass: each field is an override
/// constant of the shaders (declared in volume.wgsl and surface.wgsl).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct SceneKey {
    /// The world has surfaces (`SURFACES`): without, the traversal and
    /// the surface shading are dropped.
    pub surfaces: bool,
    /// A volume is read through its page table (`PAGED`).
    pub paged: bool,
    /// The world has one volume (`ONE_VOLUME`): loops over the volumes
    /// run once and switches take volume 0.
    pub one_volume: bool,
    /// Samples are filtered by the texture unit (`FILTERED`).
    pub filtered: bool,
    /// A volume is an unstructured mesh (`MESHES`): without, the cells'
    /// traversal and shape functions are dropped.
    pub meshes: bool,
    /// A volume is an AMR field (`AMR`): without, its sampling is dropped.
    pub amr: bool,
    /// A volume is a NanoVDB grid (`VDB`): without, its tree's reading is
    /// dropped.
    pub vdb: bool,
}

/// Which fields of the key a pass's shader depends on: the others are
/// left at their defaults, so that the pass is not compiled again for
/// scenes that differ only in them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Uses {
    pub surfaces: bool,
    pub paged: bool,
    pub one_volume: bool,
    pub filtered: bool,
    pub meshes: bool,
    pub amr: bool,
    pub vdb: bool,
}

impl Uses {
    /// A pass that marches volumes and meets surfaces.
    pub const ALL: Uses = Uses {
        surfaces: true,
        paged: true,
        one_volume: true,
        filtered: true,
        meshes: true,
        amr: true,
        vdb: true,
    };
    /// A pass that marches with exact sampling only (the stereo passes).
    pub const EXACT: Uses = Uses {
        filtered: false,
        ..Uses::ALL
    };
    /// A pass that meets surfaces but samples no volume.
    pub const SURFACES: Uses = Uses {
        surfaces: true,
        paged: false,
        one_volume: false,
        filtered: false,
        meshes: false,
        amr: false,
        vdb: false,
    };
}

impl SceneKey {
    /// The key of `scene` rendered with `settings` on this adapter.
    pub fn of(
        ctx: &Context,
        scene: &Scene,
        settings: &RenderSettings,
    ) -> Result<Self, RenderError> {
        let filtered = match settings.sampling {
            Sampling::Exact => false,
            Sampling::Filtered if ctx.filterable => true,
            Sampling::Filtered => return Err(no_filtering(ctx)),
        };
        Ok(Self {
            surfaces: !scene.shapes().is_empty(),
            paged: paging::any_paged(ctx, scene),
            one_volume: scene.volumes().len() == 1,
            filtered,
            meshes: scene
                .volumes()
                .iter()
                .any(|v| v.volume.unstructured().is_some()),
            amr: scene.volumes().iter().any(|v| v.volume.amr().is_some()),
            vdb: scene.volumes().iter().any(|v| v.volume.nanovdb().is_some()),
        })
    }

    /// The key as a pass that `uses` only some of it sees it.
    pub fn seen_by(self, uses: Uses) -> Self {
        Self {
            surfaces: self.surfaces && uses.surfaces,
            paged: self.paged && uses.paged,
            one_volume: self.one_volume && uses.one_volume,
            filtered: self.filtered && uses.filtered,
            meshes: self.meshes && uses.meshes,
            amr: self.amr && uses.amr,
            vdb: self.vdb && uses.vdb,
        }
    }

    fn index(self) -> usize {
        usize::from(self.surfaces)
            | usize::from(self.paged) << 1
            | usize::from(self.one_volume) << 2
            | usize::from(self.filtered) << 3
            | usize::from(self.meshes) << 4
            | usize::from(self.amr) << 5
            | usize::from(self.vdb) << 6
    }

    /// The override constants that select this variant.
    pub fn constants(self) -> [(&'static str, f64); 7] {
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        [
            ("SURFACES", flag(self.surfaces)),
            ("PAGED", flag(self.paged)),
            ("ONE_VOLUME", flag(self.one_volume)),
            ("FILTERED", flag(self.filtered)),
            ("MESHES", flag(self.meshes)),
            ("AMR", flag(self.amr)),
            ("VDB", flag(self.vdb)),
        ]
    }
}

pub(super) fn no_filtering(ctx: &Context) -> RenderError {
    RenderError::Settings(format!(
        "filtered GPU sampling needs 32-bit float textures to filter, which {} does not offer; use exact sampling",
        ctx.info.name
    ))
}

const VARIANTS: usize = 128;

/// One entry point of a shader, compiled for each scene key the first
/// time a frame needs it, with the pass's own fixed constants besides.
pub(super) struct Keyed {
    label: &'static str,
    module: &'static str,
    entry: &'static str,
    groups: Vec<GroupLayout>,
    uses: Uses,
    fixed: Vec<(&'static str, f64)>,
    variants: [OnceLock<wgpu::ComputePipeline>; VARIANTS],
}

impl Keyed {
    pub fn new(
        (label, module, entry): (&'static str, &'static str, &'static str),
        groups: &[&GroupLayout],
        uses: Uses,
        fixed: &[(&'static str, f64)],
    ) -> Self {
        Self {
            label,
            module,
            entry,
            groups: groups.iter().map(|g| (*g).clone()).collect(),
            uses,
            fixed: fixed.to_vec(),
            variants: std::array::from_fn(|_| OnceLock::new()),
        }
    }

    /// The pipeline for `key`, compiled if it is the first.
    pub fn get(&self, ctx: &Context, key: SceneKey) -> Result<&wgpu::ComputePipeline, RenderError> {
        let key = key.seen_by(self.uses);
        let cell = &self.variants[key.index()];
        if let Some(pipeline) = cell.get() {
            return Ok(pipeline);
        }
        let mut constants: Vec<(&str, f64)> = key.constants().to_vec();
        constants.extend(self.fixed.iter().copied());
        let groups: Vec<&GroupLayout> = self.groups.iter().collect();
        let pipeline = compute_pipeline(
            &ctx.device,
            self.label,
            self.module,
            self.entry,
            &groups,
            &constants,
        )?;
        Ok(cell.get_or_init(|| pipeline))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_key_has_its_own_variant() {
        let mut seen = std::collections::HashSet::new();
        for i in 0..VARIANTS {
            let key = SceneKey {
                surfaces: i & 1 != 0,
                paged: i & 2 != 0,
                one_volume: i & 4 != 0,
                filtered: i & 8 != 0,
                meshes: i & 16 != 0,
                amr: i & 32 != 0,
                vdb: i & 64 != 0,
            };
            assert_eq!(key.index(), i);
            assert!(seen.insert(key.constants().map(|(_, v)| v.to_bits())));
        }
    }

    #[test]
    fn a_pass_sees_only_what_it_uses() {
        let all = SceneKey {
            surfaces: true,
            paged: true,
            one_volume: true,
            filtered: true,
            meshes: true,
            amr: true,
            vdb: true,
        };
        assert_eq!(all.seen_by(Uses::ALL), all);
        assert!(!all.seen_by(Uses::EXACT).filtered);
        assert_eq!(
            all.seen_by(Uses::SURFACES),
            SceneKey {
                surfaces: true,
                ..SceneKey::default()
            }
        );
    }
}
