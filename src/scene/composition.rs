//! A scene: up to `MAX_VOLUMES` volumes, each with its own transfer
//! function and its own place in the world, composited sample by sample
//! where they overlap.

use std::sync::Arc;

use glam::{DMat4, Mat4, Vec3};
use thiserror::Error;

use super::placement::{check_affine, transformed_box, ObjectIds};
use super::storage::Lent;
use super::{PlacedShape, ShapeError, SpatialField, TransferFunction};

/// The most volumes one scene composites. The shaders bind one 3D texture
/// per volume, and eight plus the other textures stay inside the sixteen
/// sampled textures per stage every adapter allows.
pub const MAX_VOLUMES: usize = 8;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum SceneError {
    #[error("a scene needs at least one volume or surface")]
    Empty,
    #[error("surface {index}: {error}")]
    BadShape { index: usize, error: ShapeError },
    #[error("{count} volumes in one scene; caveray composites up to {MAX_VOLUMES}")]
    TooManyVolumes { count: usize },
    #[error("volume {index}: transform {transform} {reason}")]
    BadTransform {
        index: usize,
        transform: String,
        reason: &'static str,
    },
}

/// A volume classified by its transfer function and placed in the world.
#[derive(Clone, Debug)]
pub struct PlacedVolume {
    pub volume: Arc<SpatialField>,
    pub transfer_function: Arc<TransferFunction>,
    /// Object to world: affine (any rotation, scale, shear or mirror) and
    /// invertible.
    pub transform: Mat4,
    pub ids: ObjectIds,
}

impl PlacedVolume {
    /// Why `transform` cannot place a volume, if it cannot.
    pub fn check_transform(transform: Mat4) -> Result<(), &'static str> {
        check_affine(transform)
    }

    /// World coordinates to lattice coordinates (vertex i at i), computed in
    /// double precision so that large offsets lose nothing.
    pub fn world_to_grid(&self) -> DMat4 {
        let v = &self.volume;
        let object_to_grid = DMat4::from_scale(v.spacing().as_dvec3().recip())
            * DMat4::from_translation(-v.origin().as_dvec3());
        object_to_grid * self.transform.as_dmat4().inverse()
    }

    /// The world-space length of the field's smallest cell edge (a
    /// mesh's typical one).
    pub fn smallest_cell(&self) -> f32 {
        let s = self.volume.cell_edges();
        let m = glam::Mat3::from_mat4(self.transform);
        (m.x_axis * s.x)
            .length()
            .min((m.y_axis * s.y).length())
            .min((m.z_axis * s.z).length())
    }

    /// The world-space box around the placed grid.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        transformed_box(self.transform, self.volume.bounds())
    }
}

/// What a renderer draws. Volumes and tables are shared so a renderer can
/// keep them uploaded and tell, by identity, when they were replaced.
#[derive(Clone, Debug)]
pub struct Scene {
    volumes: Vec<PlacedVolume>,
    /// Surfaces beside the volumes, marched with them: a ray stops at the
    /// nearest one.
    shapes: Vec<PlacedShape>,
}

impl Scene {
    /// One volume where its field says, classified by `transfer_function`.
    pub fn new(volume: impl Into<SpatialField>, transfer_function: TransferFunction) -> Self {
        Self::shared(Arc::new(volume.into()), Arc::new(transfer_function))
    }

    /// `new` with shared parts.
    pub fn shared(volume: Arc<SpatialField>, transfer_function: Arc<TransferFunction>) -> Self {
        Self {
            volumes: vec![PlacedVolume {
                volume,
                transfer_function,
                transform: Mat4::IDENTITY,
                ids: ObjectIds::NONE,
            }],
            shapes: Vec::new(),
        }
    }

    /// Several volumes, each placed by its transform.
    pub fn placed(volumes: Vec<PlacedVolume>) -> Result<Self, SceneError> {
        if volumes.is_empty() {
            return Err(SceneError::Empty);
        }
        if volumes.len() > MAX_VOLUMES {
            return Err(SceneError::TooManyVolumes {
                count: volumes.len(),
            });
        }
        for (index, v) in volumes.iter().enumerate() {
            PlacedVolume::check_transform(v.transform).map_err(|reason| {
                SceneError::BadTransform {
                    index,
                    transform: format!("{}", v.transform),
                    reason,
                }
            })?;
        }
        Ok(Self {
            volumes,
            shapes: Vec::new(),
        })
    }

    /// Surfaces alone, no volume.
    pub fn of_shapes(shapes: Vec<PlacedShape>) -> Result<Self, SceneError> {
        if shapes.is_empty() {
            return Err(SceneError::Empty);
        }
        Self {
            volumes: Vec::new(),
            shapes: Vec::new(),
        }
        .with_shapes(shapes)
    }

    /// This scene with `shapes` beside its volumes.
    pub fn with_shapes(mut self, shapes: Vec<PlacedShape>) -> Result<Self, SceneError> {
        for (index, shape) in shapes.iter().enumerate() {
            shape
                .check()
                .map_err(|error| SceneError::BadShape { index, error })?;
        }
        self.shapes = shapes;
        Ok(self)
    }

    /// In the order given; none in a scene of surfaces alone.
    pub fn volumes(&self) -> &[PlacedVolume] {
        &self.volumes
    }

    /// The scene's fields, each once however often it is placed.
    pub fn grids(&self) -> impl Iterator<Item = &Arc<SpatialField>> {
        let all = &self.volumes;
        all.iter()
            .enumerate()
            .filter(|(i, p)| !all[..*i].iter().any(|q| Arc::ptr_eq(&q.volume, &p.volume)))
            .map(|(_, p)| &p.volume)
    }

    /// The host memory this scene's grids and shapes read in place: a
    /// render holds a [`Lent::reading`] of each while it runs.
    pub fn lenders(&self) -> impl Iterator<Item = &Arc<Lent>> {
        let shapes = self.shapes.iter().flat_map(|s| s.shape.lenders());
        self.grids().filter_map(|g| g.lender()).chain(shapes)
    }

    pub fn shapes(&self) -> &[PlacedShape] {
        &self.shapes
    }

    /// The world-space box around every volume and surface.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let shapes = self.shapes.iter().map(PlacedShape::bounds);
        self.volumes
            .iter()
            .map(PlacedVolume::bounds)
            .chain(shapes)
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), (a, b)| {
                (l.min(a), h.max(b))
            })
    }

    /// Whether `other` draws the same data the same way: the same volumes
    /// and tables by identity, the same transforms by value.
    pub fn same(&self, other: &Scene) -> bool {
        self.volumes.len() == other.volumes.len()
            && self.volumes.iter().zip(&other.volumes).all(|(a, b)| {
                Arc::ptr_eq(&a.volume, &b.volume)
                    && Arc::ptr_eq(&a.transfer_function, &b.transfer_function)
                    && a.transform == b.transform
                    && a.ids == b.ids
            })
            && self.shapes.len() == other.shapes.len()
            && self
                .shapes
                .iter()
                .zip(&other.shapes)
                .all(|(a, b)| a.same(b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{StructuredVolume, Voxels};
    use glam::UVec3;

    fn placed(transform: Mat4) -> PlacedVolume {
        let volume = StructuredVolume::new(
            UVec3::new(3, 5, 9),
            Voxels::F32(vec![0.0; 3 * 5 * 9].into()),
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(0.5, 0.25, 2.0),
        )
        .unwrap();
        let tf = TransferFunction::new(vec![glam::Vec4::ONE; 2], vec![0.0, 1.0], (0.0, 1.0), 1.0)
            .unwrap();
        PlacedVolume {
            volume: Arc::new(volume.into()),
            transfer_function: Arc::new(tf),
            transform,
            ids: ObjectIds::NONE,
        }
    }

    #[test]
    fn world_to_grid_sends_the_placed_vertices_to_their_indices() {
        let m = Mat4::from_translation(Vec3::new(-4.0, 7.0, 0.5))
            * Mat4::from_rotation_y(0.7)
            * Mat4::from_scale(Vec3::new(2.0, 1.0, -0.5));
        let v = placed(m);
        let w2g = v.world_to_grid();
        for index in [UVec3::ZERO, UVec3::new(2, 4, 8), UVec3::new(1, 3, 5)] {
            let object = v.volume.origin() + index.as_vec3() * v.volume.spacing();
            let world = m.transform_point3(object);
            let grid = w2g.transform_point3(world.as_dvec3());
            assert!(
                (grid - index.as_dvec3()).abs().max_element() < 1e-5,
                "{index} -> {grid}"
            );
        }
        // The smallest world edge: y's 0.25 (x 0.5 * 2, z 2 * 0.5).
        assert!((v.smallest_cell() - 0.25).abs() < 1e-6);
    }

    #[test]
    fn projective_singular_and_too_many_are_refused() {
        let mut projective = Mat4::IDENTITY;
        projective.x_axis.w = 0.5;
        let flat = Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0));
        for (m, reason) in [(projective, "projective"), (flat, "singular")] {
            let e = Scene::placed(vec![placed(Mat4::IDENTITY), placed(m)]).unwrap_err();
            assert!(
                matches!(&e, SceneError::BadTransform { index: 1, .. }),
                "{e}"
            );
            assert!(e.to_string().contains(reason), "{e}");
        }
        let nine = vec![placed(Mat4::IDENTITY); MAX_VOLUMES + 1];
        assert_eq!(
            Scene::placed(nine).unwrap_err().to_string(),
            "9 volumes in one scene; caveray composites up to 8"
        );
        assert_eq!(Scene::placed(vec![]).unwrap_err(), SceneError::Empty);
    }

    #[test]
    fn bounds_enclose_every_placed_volume() {
        let a = placed(Mat4::IDENTITY);
        let b = placed(Mat4::from_translation(Vec3::new(10.0, 0.0, 0.0)));
        let scene = Scene::placed(vec![a.clone(), b]).unwrap();
        let (lo, hi) = scene.bounds();
        let (alo, ahi) = a.bounds();
        assert_eq!(lo, alo);
        assert_eq!(hi, ahi + Vec3::new(10.0, 0.0, 0.0));
    }
}
