//! How a surface reflects one light: Lambertian for matte, and for a
//! physically based material the metallic-roughness model glTF made
//! common (Cook-Torrance: GGX distribution, Smith-Schlick shadowing,
//! Schlick's Fresnel; dielectrics reflect 4 % head-on, metals their base
//! color). shaders/surface.wgsl's `reflected` is the same arithmetic.

use glam::Vec3;

use crate::scene::Pbr;

/// The roughest a highlight may be sharpened to: below this, GGX's peak
/// outgrows what one sample per pixel can show.
pub const MIN_ROUGHNESS: f32 = 0.03;

/// Light reflected towards `v` per unit of light arriving from `l`
/// (all unit vectors, `n` facing the viewer), the cosine included: for
/// matte `albedo · max(n·l, 0)`.
pub fn reflected(n: Vec3, v: Vec3, l: Vec3, albedo: Vec3, pbr: Option<&Pbr>) -> Vec3 {
    let nl = n.dot(l);
    if nl <= 0.0 {
        return Vec3::ZERO;
    }
    let Some(pbr) = pbr else {
        return albedo * nl;
    };
    let nv = n.dot(v).max(1e-4);
    let h = (l + v).normalize_or_zero();
    let (nh, vh) = (n.dot(h).max(0.0), v.dot(h).clamp(0.0, 1.0));
    let r = pbr.roughness.max(MIN_ROUGHNESS);
    let a2 = (r * r) * (r * r);
    let d = a2 / (std::f32::consts::PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
    let k = r * r / 2.0;
    let g = (nl / (nl * (1.0 - k) + k)) * (nv / (nv * (1.0 - k) + k));
    let f0 = Vec3::splat(0.04).lerp(albedo, pbr.metallic);
    let f = f0 + (Vec3::ONE - f0) * (1.0 - vh).powi(5);
    // The diffuse term is albedo x cos without 1/pi (a light of 1 lights
    // a facing matte surface to its color): the highlight takes the same pi.
    let specular = f * (std::f32::consts::PI * d * g / (4.0 * nv));
    albedo * (1.0 - pbr.metallic) * nl + specular
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matte_is_lambert_and_pbr_peaks_in_the_mirror_direction() {
        let n = Vec3::Z;
        let l = Vec3::new(0.6, 0.0, 0.8);
        let albedo = Vec3::new(0.8, 0.4, 0.2);
        assert_eq!(reflected(n, Vec3::Z, l, albedo, None), albedo * 0.8);
        assert_eq!(reflected(n, Vec3::Z, -l, albedo, None), Vec3::ZERO);
        let glossy = Pbr {
            metallic: 1.0,
            roughness: 0.2,
            emissive: Vec3::ZERO,
        };
        let mirror = Vec3::new(-0.6, 0.0, 0.8);
        let at_mirror = reflected(n, mirror, l, albedo, Some(&glossy));
        let off = reflected(n, Vec3::Z, l, albedo, Some(&glossy));
        assert!(at_mirror.x > 10.0 * off.x, "{at_mirror} vs {off}");
        // A metal's highlight takes its color; a dielectric's is white.
        assert!(at_mirror.x > at_mirror.z * 3.0);
        let plastic = Pbr {
            metallic: 0.0,
            ..glossy
        };
        let spec = reflected(n, mirror, l, Vec3::ZERO, Some(&plastic));
        assert!((spec.x - spec.z).abs() < 1e-6 && spec.x > 0.0);
        // Fully rough and dielectric: near the matte answer, plus 4 %-ish.
        let rough = Pbr {
            metallic: 0.0,
            roughness: 1.0,
            emissive: Vec3::ZERO,
        };
        let r = reflected(n, Vec3::Z, Vec3::Z, albedo, Some(&rough));
        assert!((r - albedo).abs().max_element() < 0.1, "{r}");
    }
}
