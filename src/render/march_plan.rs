//! The march plan: every number both renderers derive from the scene and
//! the settings before any ray is cast.

use glam::{UVec3, Vec3, Vec4};

use super::settings::{RenderSettings, Shading, AO_DIRECTIONS, MAX_STEPS_PER_RAY};
use super::RenderError;
use crate::geometry::RayGen;
use crate::scene::{Filter, PlacedVolume, Scene, SpatialField};

/// Everything both renderers derive from scene and settings before any ray
/// is cast, so that the CPU reference and the shader share one set of
/// numbers rather than two derivations.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct MarchPlan {
    /// One per scene volume, in the scene's order.
    pub volumes: Vec<VolumePlan>,
    /// Primary step length in world units: half the smallest cell edge of
    /// any volume, times the step factor.
    pub step: f32,
    /// The most steps a primary ray takes: enough to cross the scene's
    /// bounding box diagonally, at most MAX_STEPS_PER_RAY. Without it, a
    /// camera so far away that t loses its precision would march forever.
    pub max_steps: u32,
    /// Whether MAX_STEPS_PER_RAY is below what crossing the scene takes,
    /// so that some rays stop before they leave it.
    pub cut_short: bool,
    /// Step of shadow and directional rays, and the AO radius unit: one
    /// smallest cell edge, independent of the primary step factor.
    pub shading_step: f32,
    pub ao_radius: f32,
    pub termination: f32,
    pub depth_threshold: f32,
    pub clip_planes: Vec<Vec4>,
    /// Under data-parallel rendering: where steps are laid and which this
    /// renderer takes.
    pub part: Option<PartPlan>,
    /// Straight RGBA.
    pub background: Vec4,
    pub light: Vec3,
    pub light_color: Vec3,
    pub has_background_image: bool,
    pub shading: Shading,
    /// AO sphere points, or the random directions of `directional:N`.
    pub directions: Vec<Vec3>,
    /// Whether primary rays leap over clear bricks.
    pub skipping: bool,
    /// Level of detail (0: full detail); the GPU's filtered path reads it.
    pub level_of_detail: f32,
}

/// What a volume's samples read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum FieldKind {
    Grid,
    Cells,
    Amr,
    Vdb,
}

/// How one volume is sampled: where a world point falls in its grid, and
/// how its values meet its table.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct VolumePlan {
    /// World point to grid coordinates (vertex i at i): rows x, y, z of
    /// the affine map, applied to (p, 1).
    pub world_to_grid: [Vec4; 3],
    pub dims: UVec3,
    pub filter: Filter,
    /// What the field's samples read: a grid's vertices, or a mesh's or
    /// an AMR field's cells (the lattice then only lays the march and the
    /// bricks).
    pub kind: FieldKind,
    /// Field value mapped to the table's first entry, and 1 / the width
    /// of the transfer function's value range.
    pub value_lo: f32,
    pub value_scale: f32,
    pub inv_unit_distance: f32,
}

impl VolumePlan {
    fn new(placed: &PlacedVolume) -> Self {
        let m = placed.world_to_grid().as_mat4();
        let (lo, hi) = placed.transfer_function.value_range();
        Self {
            world_to_grid: [m.row(0), m.row(1), m.row(2)],
            dims: placed.volume.dims(),
            filter: placed.volume.filter(),
            kind: match &*placed.volume {
                SpatialField::Structured(_) => FieldKind::Grid,
                SpatialField::Unstructured(_) => FieldKind::Cells,
                SpatialField::Amr(_) => FieldKind::Amr,
                SpatialField::NanoVdb(_) => FieldKind::Vdb,
            },
            value_lo: lo,
            value_scale: (hi - lo).recip(),
            inv_unit_distance: placed.transfer_function.unit_distance().recip(),
        }
    }

    /// Grid coordinates of world point `p`.
    pub fn grid(&self, p: Vec3) -> Vec3 {
        let q = p.extend(1.0);
        let [x, y, z] = &self.world_to_grid;
        Vec3::new(x.dot(q), y.dot(q), z.dot(q))
    }

    /// The grid's change per unit step along world direction `d`.
    pub fn grid_direction(&self, d: Vec3) -> Vec3 {
        let [x, y, z] = &self.world_to_grid;
        Vec3::new(
            x.truncate().dot(d),
            y.truncate().dot(d),
            z.truncate().dot(d),
        )
    }

    /// The largest grid coordinate, per axis.
    pub fn last_vertex(&self) -> Vec3 {
        (self.dims - UVec3::ONE).as_vec3()
    }
}

/// The point along a march from `t0` over `len` at which step `k` is
/// sampled: the middle of its segment, every segment a full step but the
/// last. The renderers and [`PartPlan::owned_steps`] compute it alike, so
/// that two ranks agree on which of them takes a sample.
pub(crate) fn sample_t(t0: f32, len: f32, step: f32, k: u32) -> f32 {
    let start = k as f32 * step;
    t0 + start + 0.5 * step.min(len - start).max(0.0)
}

/// A data-parallel renderer's share (settings::Part), as marches read it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PartPlan {
    pub to_box: [Vec4; 3],
    pub whole: (Vec3, Vec3),
    pub owned: (Vec3, Vec3),
}

impl PartPlan {
    fn frame(&self, o: Vec3, d: Vec3) -> (Vec3, Vec3) {
        let [x, y, z] = &self.to_box;
        let q = o.extend(1.0);
        (
            Vec3::new(x.dot(q), y.dot(q), z.dot(q)),
            Vec3::new(
                x.truncate().dot(d),
                y.truncate().dot(d),
                z.truncate().dot(d),
            ),
        )
    }

    /// The whole's span along the ray `o + t d` within `clip`: where one
    /// renderer of the whole would lay its steps.
    pub fn whole_span(&self, o: Vec3, d: Vec3, clip: (f32, f32)) -> Option<(f32, f32)> {
        let (q, qd) = self.frame(o, d);
        crate::geometry::enter_exit(q, qd, self.whole.0, self.whole.1, clip)
    }

    /// Of the `n` steps of a march from `t0` over `len`, the ones
    /// `[first, end)` whose sample points lie in the owned box (a point on
    /// a face between two parts goes to the farther one).
    pub fn owned_steps(
        &self,
        (o, d): (Vec3, Vec3),
        (t0, len, n): (f32, f32, u32),
        step: f32,
    ) -> (u32, u32) {
        let (q, qd) = self.frame(o, d);
        let Some((r0, r1)) = crate::geometry::enter_exit(
            q,
            qd,
            self.owned.0,
            self.owned.1,
            (f32::NEG_INFINITY, f32::INFINITY),
        ) else {
            return (0, 0);
        };
        // The first step sampled at or beyond r: the estimate, then the
        // same comparison the march makes.
        let first_at = |r: f32| {
            let guess = ((r - t0) / step - 0.5).ceil();
            let mut k = if guess.is_nan() {
                0
            } else {
                // (n as f32 may round up past n.)
                (guess.clamp(0.0, n as f32) as u32).min(n)
            };
            while k > 0 && sample_t(t0, len, step, k - 1) >= r {
                k -= 1;
            }
            while k < n && sample_t(t0, len, step, k) < r {
                k += 1;
            }
            k
        };
        let first = first_at(r0);
        (first, first_at(r1).max(first))
    }
}

impl MarchPlan {
    pub fn new(
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
    ) -> Result<Self, RenderError> {
        settings.validate()?;
        if !rays.is_finite() {
            return Err(RenderError::Settings(
                "the camera's rays are not finite numbers (an eye or a wall beyond single precision's range?)".into(),
            ));
        }
        let smallest = scene
            .volumes()
            .iter()
            .map(PlacedVolume::smallest_cell)
            .fold(f32::INFINITY, f32::min);
        let directions = match settings.shading {
            Shading::Ao | Shading::ShadowsAo => ao_directions(),
            Shading::Directional(n) => random_directions(n),
            Shading::None | Shading::Shadows => Vec::new(),
        };
        let step = 0.5 * smallest * settings.step_half_voxels();
        let (lo, hi) = scene.bounds();
        let crossing = ((hi - lo).length() / step).ceil() + 2.0;
        let cut_short = crossing.is_nan() || crossing > MAX_STEPS_PER_RAY as f32;
        Ok(Self {
            volumes: scene.volumes().iter().map(VolumePlan::new).collect(),
            step,
            max_steps: if cut_short {
                MAX_STEPS_PER_RAY
            } else {
                crossing as u32
            },
            cut_short,
            shading_step: smallest,
            ao_radius: 2.0 * smallest,
            termination: settings.termination,
            depth_threshold: settings.depth_threshold,
            clip_planes: settings.clip_planes.as_slice().to_vec(),
            part: settings.part.map(|p| PartPlan {
                to_box: p.to_box,
                whole: p.whole,
                owned: p.owned,
            }),
            background: settings.background,
            light: settings.light.normalize(),
            // Emission-absorption alone is the transfer function's colour, as
            // the reference device draws it: a light scales only what it lights.
            light_color: if settings.shading.lights() {
                settings.light_color
            } else {
                Vec3::ONE
            },
            has_background_image: settings.background_image.is_some(),
            shading: settings.shading,
            directions,
            skipping: settings.skipping,
            level_of_detail: settings.level_of_detail,
        })
    }
}

/// The 14 AO directions: the 6 axes and the 8 cube diagonals.
fn ao_directions() -> Vec<Vec3> {
    let mut dirs = vec![
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ];
    for i in 0..8 {
        let s = |bit: u32| if i & bit == 0 { 1.0 } else { -1.0 };
        dirs.push(Vec3::new(s(1), s(2), s(4)).normalize());
    }
    debug_assert_eq!(dirs.len(), AO_DIRECTIONS as usize);
    dirs
}

/// `n` directions uniform on the sphere from a fixed seed, so every frame
/// (and both renderers) use the same set.
fn random_directions(n: u32) -> Vec<Vec3> {
    let mut state: u64 = 0x5eed_cafe_f00d_0001;
    let mut next = || {
        // SplitMix64: small, good enough for a handful of directions.
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let z = 1.0 - 2.0 * next();
            let phi = std::f64::consts::TAU * next();
            let r = (1.0 - z * z).max(0.0).sqrt();
            Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32)
        })
        .collect()
}
