use std::fmt;
use std::str::FromStr;

use std::sync::Arc;

use glam::{UVec2, Vec3, Vec4};

use super::RenderError;

/// Most directions `directional:N` may ask for (Buchacher & Erdt used up to 16).
pub const MAX_DIRECTIONS: u32 = 64;

/// Most clip planes a renderer takes.
pub const MAX_CLIP_PLANES: usize = 8;

/// The most point and spot lights that light surfaces.
pub const MAX_LAMPS: usize = 8;

/// A point or spot light on the surfaces: radiant intensity `color` from
/// `position`, falling off with the square of the distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lamp {
    pub position: Vec3,
    /// Color times intensity.
    pub color: Vec3,
    pub spot: Option<Spot>,
}

/// A spot light's cone: full intensity within `cos_inner` of `direction`
/// (the way the light travels, unit length), none past `cos_outer`, a
/// smooth step between.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spot {
    pub direction: Vec3,
    pub cos_outer: f32,
    pub cos_inner: f32,
}

impl Lamp {
    /// The unit vector from `p` to the lamp, and the light that arrives at
    /// `p` from it before the cosine with a surface's normal.
    pub fn at(&self, p: Vec3) -> (Vec3, Vec3) {
        let offset = self.position - p;
        let d2 = offset.length_squared().max(1e-12);
        let towards = offset / d2.sqrt();
        let mut strength = 1.0 / d2;
        if let Some(spot) = self.spot {
            strength *= cone(spot, -towards);
        }
        (towards, self.color * strength)
    }
}

/// How much of a spot's light leaves along unit vector `out`.
pub fn cone(spot: Spot, out: Vec3) -> f32 {
    let c = out.dot(spot.direction);
    let (lo, hi) = (spot.cos_outer, spot.cos_inner);
    if hi <= lo {
        return if c >= lo { 1.0 } else { 0.0 };
    }
    let t = ((c - lo) / (hi - lo)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The step factors caveray takes (ANARI's `stepFactor`, the renderer
/// table's `minimum` and `maximum`): at the default sampling rate, from
/// 1/64 of a half voxel (128 samples per voxel) to 64 (one every 32
/// voxels). Below, a render of any size takes hours; above, it samples
/// nothing of a volume's detail.
pub const STEP_FACTOR_RANGE: (f32, f32) = (1.0 / 64.0, 64.0);

/// The most steps one primary ray takes, whatever the scene's size and
/// step: 2^20 covers the diagonal of a 2048^3 volume at the finest step
/// factor several times over. Rays that would take more are cut there
/// (`MarchPlan::cut_short` says when that can happen).
pub const MAX_STEPS_PER_RAY: u32 = 1 << 20;

/// Half-spaces that cut the primary rays: plane (n, d) keeps the points p
/// with dot(n, p) < d (anari-visionaray's convention, which OpenCOVER
/// sends).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ClipPlanes {
    planes: [Vec4; MAX_CLIP_PLANES],
    count: usize,
}

impl ClipPlanes {
    /// `planes`, each scaled to a unit normal; `None` if there are more
    /// than `MAX_CLIP_PLANES`.
    pub fn new(planes: &[Vec4]) -> Option<Self> {
        let mut out = Self::default();
        for (slot, plane) in out.planes.get_mut(..planes.len())?.iter_mut().zip(planes) {
            *slot = unit_normal(*plane);
        }
        out.count = planes.len();
        Some(out)
    }

    pub fn as_slice(&self) -> &[Vec4] {
        &self.planes[..self.count]
    }
}

/// Plane (n, d) as (n / |n|, d / |n|), the same half-space. The length is
/// taken in f64: in f32 the squared length of (1e-30, 0, 0) is 0 and that
/// of (3e38, 3e38, 3e38) infinite, though both name a plane, and the
/// renderers' f32 arithmetic on such normals loses the plane. A zero or
/// non-finite normal is left as it is, for `validate` to refuse; a
/// distance beyond f32 keeps its side (the plane is far past any volume).
fn unit_normal(plane: Vec4) -> Vec4 {
    let p = plane.as_dvec4();
    let length = p.truncate().length();
    if !(length.is_finite() && length > 0.0 && p.w.is_finite()) {
        return plane;
    }
    let most = f64::from(f32::MAX);
    (p.truncate() / length)
        .extend((p.w / length).clamp(-most, most))
        .as_vec4()
}

/// One renderer's share of a data-parallel job: boxes in a frame that an
/// affine map takes world points to. Every rank lays its steps along each
/// ray as one renderer of the whole would (from where the ray enters
/// `whole`) and takes only the samples whose points lie in `owned`, so
/// that the ranks' samples together are that renderer's, each taken once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Part {
    /// World point to the boxes' frame: rows x, y, z applied to (p, 1).
    pub to_box: [Vec4; 3],
    pub whole: (Vec3, Vec3),
    pub owned: (Vec3, Vec3),
}

/// How surfaces are shaded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SurfaceShading {
    /// The reference device's look, which hosts and the conformance tool
    /// are tuned on: color x (blend |n . v| + 1 - blend), v towards the
    /// eye; the world's lights and the ambient light are not used.
    EyeLight { blend: f32 },
    /// Lambertian under the world's lights (a light at the eye where it
    /// has none), plus the ambient light.
    Lights,
}

impl Default for SurfaceShading {
    fn default() -> Self {
        Self::EyeLight { blend: 0.5 }
    }
}

/// How each sample is lit, as in Buchacher & Erdt's benchmark ladder.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Shading {
    /// Transfer-function color only.
    #[default]
    None,
    /// 24 samples towards a parallel light.
    Shadows,
    /// Ambient occlusion from 14 samples on a sphere.
    Ao,
    ShadowsAo,
    /// Buchacher & Erdt's parametrised shading: N random directions, each traced
    /// up to 4 steps (N = 0 adds no samples and equals `None`).
    Directional(u32),
}

impl Shading {
    /// The shaders' SHADE_ code (the number of directions travels apart).
    pub(crate) fn code(self) -> u32 {
        match self {
            Shading::None => 0,
            Shading::Shadows => 1,
            Shading::Ao => 2,
            Shading::ShadowsAo => 3,
            Shading::Directional(_) => 4,
        }
    }

    /// Whether samples are lit, so that a light's colour and strength
    /// scale them (`None` and `directional:0` show the transfer function's
    /// colour as it is).
    pub fn lights(self) -> bool {
        !matches!(self, Shading::None | Shading::Directional(0))
    }

    /// Extra volume samples per shaded sample.
    pub fn extra_samples(self) -> u32 {
        match self {
            Shading::None => 0,
            Shading::Shadows => SHADOW_STEPS,
            Shading::Ao => AO_DIRECTIONS,
            Shading::ShadowsAo => SHADOW_STEPS + AO_DIRECTIONS,
            Shading::Directional(n) => n * DIRECTIONAL_STEPS,
        }
    }
}

pub(crate) const SHADOW_STEPS: u32 = 24;
pub(crate) const AO_DIRECTIONS: u32 = 14;
pub(crate) const DIRECTIONAL_STEPS: u32 = 4;
/// Light reaching a shadowed sample, so shadows darken but never black out.
pub(crate) const SHADOW_AMBIENT: f32 = 0.3;

impl fmt::Display for Shading {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Shading::None => f.write_str("none"),
            Shading::Shadows => f.write_str("shadows"),
            Shading::Ao => f.write_str("ao"),
            Shading::ShadowsAo => f.write_str("shadows+ao"),
            Shading::Directional(n) => write!(f, "directional:{n}"),
        }
    }
}

impl FromStr for Shading {
    type Err = RenderError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || {
            RenderError::Settings(format!(
            "unknown shading mode \"{s}\": expected none, shadows, ao, shadows+ao or directional:N (N = 0..={MAX_DIRECTIONS})"
        ))
        };
        Ok(match s {
            "none" => Shading::None,
            "shadows" => Shading::Shadows,
            "ao" => Shading::Ao,
            "shadows+ao" => Shading::ShadowsAo,
            _ => {
                let n = s.strip_prefix("directional:").ok_or_else(bad)?;
                let n: u32 = n.parse().map_err(|_| bad())?;
                if n > MAX_DIRECTIONS {
                    return Err(bad());
                }
                Shading::Directional(n)
            }
        })
    }
}

/// The largest level-of-detail factor (pixels' footprints scaled by it).
pub const LOD_MAX: f32 = 16.0;

/// How the GPU reads a sample (the CPU always reads it exactly).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sampling {
    /// Eight texel loads and a trilinear interpolation in the shader, the
    /// table interpolated by hand and the opacity corrected per sample:
    /// the reference's arithmetic, which the GPU-vs-CPU tests hold.
    #[default]
    Exact,
    /// One hardware-filtered volume fetch and one filtered fetch of a
    /// table whose opacities are already corrected for the primary step:
    /// what GPUs are built for (docs/empty_space.md, "Filtered sampling").
    Filtered,
}

impl Sampling {
    pub const NAMES: [&'static str; 2] = ["exact", "filtered"];
}

impl fmt::Display for Sampling {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Sampling::Exact => "exact",
            Sampling::Filtered => "filtered",
        })
    }
}

impl FromStr for Sampling {
    type Err = RenderError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "exact" => Ok(Sampling::Exact),
            "filtered" => Ok(Sampling::Filtered),
            _ => Err(RenderError::Settings(format!(
                "unknown GPU sampling \"{s}\": expected exact or filtered"
            ))),
        }
    }
}

/// An image behind the volume, stretched over the frame and sampled
/// bilinearly at each pixel's centre (a 1 x N image is a vertical
/// gradient, bottom row first, as ANARI's images are).
#[derive(Clone, Debug, PartialEq)]
pub struct BackgroundImage {
    size: UVec2,
    /// Straight RGBA, row by row from the bottom.
    pixels: Vec<Vec4>,
}

impl BackgroundImage {
    /// `None` unless `pixels` holds `size.x * size.y` values (whose
    /// range `RenderSettings::validate` checks).
    pub fn new(size: UVec2, pixels: Vec<Vec4>) -> Option<Self> {
        (size.min_element() > 0 && pixels.len() as u64 == u64::from(size.x) * u64::from(size.y))
            .then_some(Self { size, pixels })
    }
    pub fn size(&self) -> UVec2 {
        self.size
    }
    pub fn pixels(&self) -> &[Vec4] {
        &self.pixels
    }

    /// The color behind pixel (x, y) of a `frame`-sized image; the shaders
    /// compute the same (shaders/color.wgsl).
    pub fn at(&self, x: u32, y: u32, frame: UVec2) -> Vec4 {
        let texel = |i: u32, j: u32| self.pixels[(j * self.size.x + i) as usize];
        let coord = |p: u32, f: u32, n: u32| {
            let c = ((p as f32 + 0.5) / f as f32 * n as f32 - 0.5).clamp(0.0, (n - 1) as f32);
            let i0 = (c.floor() as u32).min(n - 1);
            (i0, (i0 + 1).min(n - 1), c - i0 as f32)
        };
        let (x0, x1, fx) = coord(x, frame.x, self.size.x);
        let (y0, y1, fy) = coord(y, frame.y, self.size.y);
        let bottom = texel(x0, y0) * (1.0 - fx) + texel(x1, y0) * fx;
        let top = texel(x0, y1) * (1.0 - fx) + texel(x1, y1) * fx;
        bottom * (1.0 - fy) + top * fy
    }
}

/// Renderer parameters that do not depend on the scene or the camera.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Straight (not premultiplied) RGBA behind the volume.
    pub background: Vec4,
    /// Behind the volume instead of `background`, if set.
    pub background_image: Option<Arc<BackgroundImage>>,
    /// ANARI's `stepFactor`: multiplies the step that `sampling_rate`
    /// sets (see [`RenderSettings::step_half_voxels`]).
    pub step_factor: f32,
    /// ANARI's `volumeSamplingRate`: samples per smallest voxel extent.
    pub sampling_rate: f32,
    /// Accumulated opacity at which a ray stops (ANARI hosts expect 0.99);
    /// a value above 1 turns early termination off.
    pub termination: f32,
    pub shading: Shading,
    /// Direction towards the parallel light of `shadows`, in world space.
    pub light: Vec3,
    /// Accumulated opacity at which a ray's depth is taken: a host that
    /// composites geometry behind the volume sees it through a faint haze
    /// (0 takes the first sample that contributes anything).
    pub depth_threshold: f32,
    pub clip_planes: ClipPlanes,
    /// Under data-parallel rendering, the part of the volumes this
    /// renderer draws.
    pub part: Option<Part>,
    /// Color times strength of the light, multiplying every lit sample
    /// (a host's directional light; 1 without one; unused unless
    /// [`Shading::lights`]).
    pub light_color: Vec3,
    /// Surfaces' ambient light: the renderer's `ambientColor` times
    /// `ambientRadiance` times AMBIENT_SCALE (under
    /// [`SurfaceShading::Lights`]).
    pub ambient: Vec3,
    pub surface_shading: SurfaceShading,
    /// Under [`SurfaceShading::Lights`]: surfaces lit from the eye, where
    /// the world has no light.
    pub headlight: bool,
    /// Whether `light` and `light_color` light the surfaces (not where a
    /// world has point or spot lights only).
    pub directional: bool,
    /// Point and spot lights on the surfaces (up to MAX_LAMPS).
    pub lamps: Vec<Lamp>,
    /// Leap over bricks the transfer function leaves clear
    /// (render::empty_space). Exact: the image does not change.
    pub skipping: bool,
    /// How the GPU reads samples.
    pub sampling: Sampling,
    /// Level of detail under filtered GPU sampling: 0 is full detail;
    /// F > 0 reads the volume's mip level log2(F · footprint / voxel) and
    /// lengthens the step by 2^level, where a pixel's footprint along the
    /// ray exceeds a voxel (1/F voxels).
    pub level_of_detail: f32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            background: Vec4::new(0.0, 0.0, 0.0, 1.0),
            background_image: None,
            step_factor: 1.0,
            sampling_rate: 2.0,
            termination: 0.99,
            shading: Shading::None,
            light: Vec3::new(0.3, 0.5, 0.8).normalize(),
            depth_threshold: 0.5,
            clip_planes: ClipPlanes::default(),
            part: None,
            light_color: Vec3::ONE,
            ambient: Vec3::splat(super::shapes::AMBIENT_SCALE),
            surface_shading: SurfaceShading::default(),
            headlight: true,
            directional: true,
            lamps: Vec::new(),
            skipping: true,
            sampling: Sampling::Exact,
            level_of_detail: 0.0,
        }
    }
}

/// `step` if it lies in [`STEP_FACTOR_RANGE`].
pub fn check_step_factor(step: f32) -> Result<f32, RenderError> {
    let (lo, hi) = STEP_FACTOR_RANGE;
    if step.is_finite() && (lo..=hi).contains(&step) {
        Ok(step)
    } else {
        Err(RenderError::Settings(format!(
            "step factor must be in [{lo}, {hi}], got {step:?}"
        )))
    }
}

impl RenderSettings {
    /// The step length in units of half the smallest voxel extent: 1 at
    /// the defaults, the reference's half-voxel steps.
    pub fn step_half_voxels(&self) -> f32 {
        self.step_factor * 2.0 / self.sampling_rate
    }

    /// Why these settings cannot render, if they cannot.
    pub fn validate(&self) -> Result<(), RenderError> {
        let unit = |c: &Vec4| c.to_array().into_iter().all(|x| (0.0..=1.0).contains(&x));
        if !unit(&self.background) {
            return Err(RenderError::Settings(format!(
                "background must be four numbers in [0, 1], got {}",
                self.background
            )));
        }
        // The image is held to the color's range: out of it, a NaN or a
        // negative reaches the frame's pixels through the blend.
        if let Some(image) = &self.background_image {
            if let Some((i, c)) = image.pixels.iter().enumerate().find(|(_, c)| !unit(c)) {
                let w = image.size.x as usize;
                return Err(RenderError::Settings(format!(
                    "'background' pixel ({}, {}) is {c}; every pixel must be four numbers in [0, 1], as the background color's",
                    i % w,
                    i / w
                )));
            }
        }
        check_step_factor(self.step_factor)?;
        if let Some(part) = &self.part {
            let finite = part.to_box.iter().all(|r| r.is_finite());
            let boxed =
                |(lo, hi): (Vec3, Vec3)| lo.is_finite() && hi.is_finite() && lo.cmple(hi).all();
            if !(finite && boxed(part.whole) && boxed(part.owned)) {
                return Err(RenderError::Settings(format!(
                    "a data-parallel part needs a finite frame and boxes with lo <= hi, got {part:?}"
                )));
            }
        }
        if !(self.sampling_rate.is_finite() && self.sampling_rate > 0.0) {
            return Err(RenderError::Settings(format!(
                "sampling rate must be finite and positive, got {:?}",
                self.sampling_rate
            )));
        }
        if !(self.termination.is_finite() && self.termination > 0.0) {
            return Err(RenderError::Settings(format!(
                "termination threshold must be finite and positive, got {}",
                self.termination
            )));
        }
        if !(self.ambient.is_finite() && self.ambient.min_element() >= 0.0) {
            return Err(RenderError::Settings(format!(
                "ambient light must be finite and not negative, got {}",
                self.ambient
            )));
        }
        if let SurfaceShading::EyeLight { blend } = self.surface_shading {
            if !(0.0..=1.0).contains(&blend) {
                return Err(RenderError::Settings(format!(
                    "the eye light's blend must be from 0 to 1, got {blend}"
                )));
            }
        }
        if self.lamps.len() > MAX_LAMPS {
            return Err(RenderError::Settings(format!(
                "{} point and spot lights; surfaces take up to {MAX_LAMPS}",
                self.lamps.len()
            )));
        }
        for lamp in &self.lamps {
            let spot_ok = lamp.spot.is_none_or(|s| {
                s.direction.is_finite() && s.cos_outer.is_finite() && s.cos_inner.is_finite()
            });
            if !(lamp.position.is_finite()
                && lamp.color.is_finite()
                && lamp.color.min_element() >= 0.0
                && spot_ok)
            {
                return Err(RenderError::Settings(format!(
                    "a point or spot light must be finite, its color not negative: {lamp:?}"
                )));
            }
        }
        if !self.light.is_finite() || self.light.length_squared() < 1e-12 {
            return Err(RenderError::Settings(format!(
                "light direction must be a finite non-zero vector, got {}",
                self.light
            )));
        }
        if !(self.depth_threshold.is_finite() && (0.0..=1.0).contains(&self.depth_threshold)) {
            return Err(RenderError::Settings(format!(
                "depth threshold must be in [0, 1], got {}",
                self.depth_threshold
            )));
        }
        if !(self.level_of_detail.is_finite() && (0.0..=LOD_MAX).contains(&self.level_of_detail)) {
            return Err(RenderError::Settings(format!(
                "level of detail must be in [0, {LOD_MAX}], got {}",
                self.level_of_detail
            )));
        }
        if !self.light_color.is_finite() || self.light_color.min_element() < 0.0 {
            return Err(RenderError::Settings(format!(
                "light color must be finite and not negative, got {}",
                self.light_color
            )));
        }
        if let Some(p) = self
            .clip_planes
            .as_slice()
            .iter()
            .find(|p| !p.is_finite() || p.truncate().length_squared() == 0.0)
        {
            return Err(RenderError::Settings(format!(
                "clip plane {p} needs a finite, non-zero normal and a finite distance"
            )));
        }
        if let Shading::Directional(n) = self.shading {
            if n > MAX_DIRECTIONS {
                return Err(RenderError::Settings(format!(
                    "directional shading takes at most {MAX_DIRECTIONS} directions, got {n}"
                )));
            }
        }
        Ok(())
    }
}
