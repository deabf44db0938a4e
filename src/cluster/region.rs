//! The part of space one rank owns in a data-parallel job: a box in some
//! affine frame (a brick's owned vertices in its volume's grid, or a box in
//! world space). Its rank takes the samples within it of the steps one
//! renderer of the whole would take (`render::Part`), so that no sample is
//! counted twice or missed, and its partial image is composited where rays
//! enter it: the regions are convex and disjoint, so along every ray they
//! follow one another in that order.

use glam::{DMat4, DVec3, Vec3};

use super::split::Brick;
use crate::geometry::enter_exit;
use crate::render::Part;
use crate::scene::PlacedVolume;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Region {
    /// World to the box's frame: affine.
    to_box: DMat4,
    lo: DVec3,
    hi: DVec3,
}

impl Region {
    /// An axis-aligned box in world space; None unless `lo` < `hi` on
    /// every axis and both are finite.
    pub fn world(lo: Vec3, hi: Vec3) -> Option<Self> {
        (lo.is_finite() && hi.is_finite() && lo.cmplt(hi).all()).then(|| Self {
            to_box: DMat4::IDENTITY,
            lo: lo.as_dvec3(),
            hi: hi.as_dvec3(),
        })
    }

    /// The cells `brick` owns of `volume`'s grid, wherever the volume is
    /// placed (its grid may be turned or sheared in the world).
    pub fn of_brick(volume: &PlacedVolume, brick: &Brick) -> Self {
        Self {
            to_box: volume.world_to_grid(),
            lo: brick.owned.0.as_dvec3(),
            hi: brick.owned.1.as_dvec3(),
        }
    }

    /// The whole grid of `volume`: the region every brick's steps are
    /// laid along.
    pub fn of_grid(volume: &PlacedVolume) -> Self {
        Self {
            to_box: volume.world_to_grid(),
            lo: DVec3::ZERO,
            hi: (volume.volume.dims() - glam::UVec3::ONE).as_dvec3(),
        }
    }

    /// A renderer's share of `whole` (a region in the same frame): it lays
    /// its steps as one renderer of `whole` would and takes the samples in
    /// this region.
    pub fn part_of(&self, whole: &Region) -> Part {
        let m = self.to_box.as_mat4();
        Part {
            to_box: [m.row(0), m.row(1), m.row(2)],
            whole: (whole.lo.as_vec3(), whole.hi.as_vec3()),
            owned: (self.lo.as_vec3(), self.hi.as_vec3()),
        }
    }

    /// The box's corners in its own frame (the world's, for
    /// [`Region::world`]).
    pub fn corners(&self) -> (Vec3, Vec3) {
        (self.lo.as_vec3(), self.hi.as_vec3())
    }

    /// How far along the ray `o + t d` (t >= 0) it enters the region, if it
    /// meets it.
    pub fn entry(&self, o: Vec3, d: Vec3) -> Option<f32> {
        let q = self.to_box.transform_point3(o.as_dvec3()).as_vec3();
        let qd = self.to_box.transform_vector3(d.as_dvec3()).as_vec3();
        enter_exit(
            q,
            qd,
            self.lo.as_vec3(),
            self.hi.as_vec3(),
            (0.0, f32::INFINITY),
        )
        .map(|(t0, _)| t0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_entry_orders_the_boxes_along_a_ray() {
        let near = Region::world(Vec3::new(0.0, 0.0, 0.0), Vec3::ONE).unwrap_or_else(|| panic!());
        let far = Region::world(Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 1.0, 2.0))
            .unwrap_or_else(|| panic!());
        let (o, d) = (Vec3::new(0.5, 0.5, -1.0), Vec3::Z);
        assert_eq!(near.entry(o, d), Some(1.0));
        assert_eq!(far.entry(o, d), Some(2.0));
        assert_eq!(near.entry(Vec3::splat(0.5), d), Some(0.0));
        assert_eq!(far.entry(o, Vec3::X), None);
        assert!(Region::world(Vec3::ONE, Vec3::ONE).is_none());
        let part = near.part_of(&far);
        assert_eq!(part.owned, (Vec3::ZERO, Vec3::ONE));
        assert_eq!(part.whole, (Vec3::Z, Vec3::new(1.0, 1.0, 2.0)));
        assert_eq!(part.to_box[0], glam::Vec4::X);
    }
}
