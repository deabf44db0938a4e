//! Samplers: what maps a surface's attribute to its color, as ANARI's
//! `image1D`, `image2D`, `image3D`, `primitive` and `transform` samplers
//! define them. VTK colors a surface by its scalars through an `image1D`
//! sampler holding the color map; textures are `image2D`; a 3D image
//! colors by position.
//!
//! An image's texel i covers [i, i + 1) / n of its coordinate, its centre
//! at (i + 0.5) / n, as the reference device reads images; linear
//! filtering blends the two (four, eight) nearest centres, nearest takes
//! the nearer of them.

use glam::{Mat4, UVec3, Vec4};
use thiserror::Error;

/// The most texels one image holds (a 4096^3 volume's worth of colors
/// would be 1 TiB; hosts send color maps and textures).
pub const MAX_TEXELS: usize = 1 << 28;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum SamplerError {
    #[error("an image of {given} texels for {dims:?}")]
    Size { given: usize, dims: [u32; 3] },
    #[error("an image of {texels} texels; one sampler holds up to {MAX_TEXELS}")]
    TooLarge { texels: usize },
    #[error("{what} is not finite")]
    NotFinite { what: &'static str },
}

/// What happens to an image coordinate outside [0, 1].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    #[default]
    ClampToEdge,
    Repeat,
    MirrorRepeat,
}

impl Wrap {
    pub const NAMES: [&'static str; 3] = ["clampToEdge", "repeat", "mirrorRepeat"];

    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "clampToEdge" => Some(Wrap::ClampToEdge),
            "repeat" => Some(Wrap::Repeat),
            "mirrorRepeat" => Some(Wrap::MirrorRepeat),
            _ => None,
        }
    }

    /// The code the GPU reads.
    pub fn code(self) -> u32 {
        self as u32
    }

    /// Texel index `i` of `n` wrapped into [0, n).
    pub fn index(self, i: i64, n: u32) -> u32 {
        let n = i64::from(n.max(1));
        let wrapped = match self {
            Wrap::ClampToEdge => i.clamp(0, n - 1),
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::MirrorRepeat => {
                let m = i.rem_euclid(2 * n);
                if m >= n {
                    2 * n - 1 - m
                } else {
                    m
                }
            }
        };
        wrapped as u32
    }
}

/// An image's texels, x fastest; unused axes are 1 texel long.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub dims: UVec3,
    pub texels: Vec<Vec4>,
    /// Linear (true) or nearest.
    pub linear: bool,
    pub wrap: [Wrap; 3],
}

impl Image {
    pub fn new(
        dims: UVec3,
        texels: Vec<Vec4>,
        linear: bool,
        wrap: [Wrap; 3],
    ) -> Result<Self, SamplerError> {
        let count = dims.as_u64vec3().element_product();
        if count > MAX_TEXELS as u64 {
            return Err(SamplerError::TooLarge {
                texels: count as usize,
            });
        }
        if count == 0 || texels.len() as u64 != count {
            return Err(SamplerError::Size {
                given: texels.len(),
                dims: dims.to_array(),
            });
        }
        if !texels.iter().all(|t| t.is_finite()) {
            return Err(SamplerError::NotFinite { what: "a texel" });
        }
        Ok(Self {
            dims,
            texels,
            linear,
            wrap,
        })
    }

    fn texel(&self, i: [u32; 3]) -> Vec4 {
        let d = self.dims;
        self.texels[(i[0] + d.x * (i[1] + d.y * i[2])) as usize]
    }

    /// The image at coordinates `c` (x, y, z in [0, 1] across it).
    pub fn at(&self, c: Vec4) -> Vec4 {
        let mut lower = [0i64; 3];
        let mut frac = [0.0f32; 3];
        for k in 0..3 {
            let n = self.dims[k] as f32;
            // Texel centres at (i + 0.5) / n.
            let x = c[k] * n - 0.5;
            let f = x.floor();
            // Saturating: a coordinate far outside lands on an edge or
            // wraps from there.
            lower[k] = f as i64;
            frac[k] = if f.is_finite() { x - f } else { 0.0 };
        }
        let mut sum = Vec4::ZERO;
        for corner in 0..8u32 {
            let mut weight = 1.0;
            let mut index = [0u32; 3];
            for k in 0..3 {
                let upper = (corner >> k) & 1 == 1;
                let w = if self.linear {
                    if upper {
                        frac[k]
                    } else {
                        1.0 - frac[k]
                    }
                } else if upper == (frac[k] >= 0.5) {
                    1.0
                } else {
                    0.0
                };
                weight *= w;
                index[k] = self.wrap[k].index(lower[k].saturating_add(upper.into()), self.dims[k]);
            }
            if weight != 0.0 {
                sum += self.texel(index) * weight;
            }
        }
        sum
    }
}

/// What a sampler does with its input.
#[derive(Clone, Debug, PartialEq)]
pub enum SamplerKind {
    /// `in_transform` applied, then the image read there.
    Image(Image),
    /// `in_transform` applied: ANARI's `transform` sampler.
    Transform,
    /// Value per host primitive, from `offset` on: the input is ignored.
    Primitive { values: Vec<Vec4>, offset: u64 },
}

/// A sampler as a material reads it: input attribute slot (`None`: the
/// sampler's input is ANARI's default attribute value), then
/// `in_transform` x a + `in_offset`, the image (if any), and
/// `out_transform` x v + `out_offset`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sampler {
    pub kind: SamplerKind,
    pub in_attribute: Option<usize>,
    pub in_transform: Mat4,
    pub in_offset: Vec4,
    pub out_transform: Mat4,
    pub out_offset: Vec4,
}

/// ANARI's value of an attribute that is not there.
pub const DEFAULT_ATTRIBUTE: Vec4 = Vec4::new(0.0, 0.0, 0.0, 1.0);

impl Sampler {
    pub fn new(kind: SamplerKind) -> Self {
        Self {
            kind,
            in_attribute: Some(1),
            in_transform: Mat4::IDENTITY,
            in_offset: Vec4::ZERO,
            out_transform: Mat4::IDENTITY,
            out_offset: Vec4::ZERO,
        }
    }

    /// Why its maps cannot be used, if they cannot.
    pub fn check(&self) -> Result<(), SamplerError> {
        let finite = |m: &Mat4| m.is_finite();
        if !finite(&self.in_transform) || !self.in_offset.is_finite() {
            return Err(SamplerError::NotFinite {
                what: "the input transform",
            });
        }
        if !finite(&self.out_transform) || !self.out_offset.is_finite() {
            return Err(SamplerError::NotFinite {
                what: "the output transform",
            });
        }
        Ok(())
    }

    /// The input after the in-transform: an image's coordinates.
    pub fn coordinates(&self, attribute: Vec4) -> Vec4 {
        self.in_transform * attribute + self.in_offset
    }

    /// The sample for attribute value `attribute` on host primitive
    /// `primitive`.
    pub fn sample(&self, attribute: Vec4, primitive: u32) -> Vec4 {
        let v = match &self.kind {
            SamplerKind::Image(image) => image.at(self.coordinates(attribute)),
            SamplerKind::Transform => self.coordinates(attribute),
            SamplerKind::Primitive { values, offset } => {
                let i = u64::from(primitive).saturating_add(*offset);
                usize::try_from(i)
                    .ok()
                    .and_then(|i| values.get(i))
                    .copied()
                    .unwrap_or(DEFAULT_ATTRIBUTE)
            }
        };
        self.out_transform * v + self.out_offset
    }

    /// Whether the sample is an affine function of the attribute (or
    /// constant per primitive): then interpolating samples taken at a
    /// primitive's corners gives the sample of the interpolated attribute.
    pub fn is_affine(&self) -> bool {
        !matches!(self.kind, SamplerKind::Image(_))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(n: u32, linear: bool, wrap: Wrap) -> Image {
        let texels = (0..n).map(|i| Vec4::splat(i as f32)).collect();
        Image::new(UVec3::new(n, 1, 1), texels, linear, [wrap; 3]).unwrap()
    }

    #[test]
    fn texel_centres_read_their_texel_and_linear_blends_between() {
        let image = ramp(4, true, Wrap::ClampToEdge);
        for i in 0..4 {
            let c = (i as f32 + 0.5) / 4.0;
            assert_eq!(image.at(Vec4::new(c, 0.0, 0.0, 1.0)).x, i as f32);
        }
        // Halfway between the centres of texels 1 and 2.
        assert!((image.at(Vec4::new(0.5, 0.0, 0.0, 1.0)).x - 1.5).abs() < 1e-6);
        // Clamped past either end.
        assert_eq!(image.at(Vec4::new(-3.0, 0.0, 0.0, 1.0)).x, 0.0);
        assert_eq!(image.at(Vec4::new(7.0, 0.0, 0.0, 1.0)).x, 3.0);
        let nearest = ramp(4, false, Wrap::ClampToEdge);
        assert_eq!(nearest.at(Vec4::new(0.49, 0.0, 0.0, 1.0)).x, 1.0);
        assert_eq!(nearest.at(Vec4::new(0.51, 0.0, 0.0, 1.0)).x, 2.0);
    }

    #[test]
    fn wrap_modes_repeat_and_mirror() {
        assert_eq!(
            (-3..7)
                .map(|i| Wrap::Repeat.index(i, 3))
                .collect::<Vec<_>>(),
            [0, 1, 2, 0, 1, 2, 0, 1, 2, 0]
        );
        assert_eq!(
            (-4..8)
                .map(|i| Wrap::MirrorRepeat.index(i, 3))
                .collect::<Vec<_>>(),
            [2, 2, 1, 0, 0, 1, 2, 2, 1, 0, 0, 1]
        );
        let repeat = ramp(4, false, Wrap::Repeat);
        assert_eq!(repeat.at(Vec4::new(1.125, 0.0, 0.0, 1.0)).x, 0.0);
        assert_eq!(repeat.at(Vec4::new(-0.125, 0.0, 0.0, 1.0)).x, 3.0);
        for name in Wrap::NAMES {
            assert_eq!(
                Wrap::from_name(name).map(|w| Wrap::NAMES[w.code() as usize]),
                Some(name)
            );
        }
    }

    #[test]
    fn a_2d_image_blends_four_texels_bilinearly() {
        let texels = vec![
            Vec4::splat(0.0),
            Vec4::splat(1.0),
            Vec4::splat(2.0),
            Vec4::splat(4.0),
        ];
        let image = Image::new(UVec3::new(2, 2, 1), texels, true, [Wrap::ClampToEdge; 3]).unwrap();
        let v = image.at(Vec4::new(0.5, 0.5, 0.0, 1.0)).x;
        assert!((v - 1.75).abs() < 1e-6, "{v}");
        let v = image.at(Vec4::new(0.75, 0.25, 0.0, 1.0)).x;
        assert!((v - 1.0).abs() < 1e-6, "{v}");
    }

    #[test]
    fn transforms_in_and_out_and_primitive_values() {
        let mut s = Sampler::new(SamplerKind::Image(ramp(5, true, Wrap::ClampToEdge)));
        // attribute x in [10, 20] to [0, 1]; the color doubled.
        s.in_transform = Mat4::from_scale(glam::Vec3::splat(0.1));
        s.in_offset = Vec4::new(-1.0, 0.0, 0.0, 0.0);
        s.out_transform = Mat4::from_scale(glam::Vec3::splat(2.0));
        s.out_offset = Vec4::new(0.5, 0.0, 0.0, 0.0);
        assert!((s.sample(Vec4::new(15.0, 0.0, 0.0, 1.0), 0).x - 4.5).abs() < 1e-5);
        assert!(!s.is_affine());
        let p = Sampler::new(SamplerKind::Primitive {
            values: vec![Vec4::X, Vec4::Y, Vec4::Z],
            offset: 1,
        });
        assert_eq!(p.sample(Vec4::ZERO, 0), Vec4::Y);
        assert_eq!(p.sample(Vec4::ZERO, 1), Vec4::Z);
        assert_eq!(p.sample(Vec4::ZERO, 2), DEFAULT_ATTRIBUTE);
        assert_eq!(p.sample(Vec4::ZERO, u32::MAX), DEFAULT_ATTRIBUTE);
        assert!(p.is_affine());
    }

    #[test]
    fn bad_images_are_refused() {
        let one = vec![Vec4::ONE];
        assert!(matches!(
            Image::new(UVec3::new(2, 1, 1), one.clone(), true, [Wrap::Repeat; 3]),
            Err(SamplerError::Size { .. })
        ));
        assert!(matches!(
            Image::new(
                UVec3::new(1 << 20, 1 << 20, 1),
                one,
                true,
                [Wrap::Repeat; 3]
            ),
            Err(SamplerError::TooLarge { .. })
        ));
        assert!(matches!(
            Image::new(UVec3::ONE, vec![Vec4::NAN], true, [Wrap::Repeat; 3]),
            Err(SamplerError::NotFinite { .. })
        ));
    }
}
