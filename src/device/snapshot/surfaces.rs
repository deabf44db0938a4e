//! A world's surfaces as a frame renders them: each surface's geometry
//! and material resolved; an isosurface becomes one `IsoSurface` per
//! iso-value, shaded by the renderer's settings and the world's light (its
//! direction: the isosurface shading's light is white); a surface of
//! primitives becomes a placed shape beside the volumes.

use std::sync::{Arc, OnceLock};

use glam::Mat4;

use crate::device::geometry::GeometryModel;
use crate::device::light::DirectionalLight;
use crate::device::material::MaterialModel;
use crate::device::object::{ObjectCell, ObjectRef};
use crate::device::sampler::SamplerModel;
use crate::device::surface::SurfaceModel;
use crate::device::world::Placement;
use crate::render::iso::{IsoSettings, IsoSurface};
use crate::render::RenderSettings;
use crate::scene::{ObjectIds, PlacedShape, PlacedVolume, Source, SpatialField, TransferFunction};

/// The transfer function a surface's field is placed with: the caster
/// reads the field alone and never evaluates it. One for all, so the GPU
/// renderer, which keeps tables by identity, writes it once.
fn unclassified() -> Result<Arc<TransferFunction>, String> {
    static ONE: OnceLock<Option<Arc<TransferFunction>>> = OnceLock::new();
    ONE.get_or_init(|| {
        TransferFunction::new(vec![glam::Vec4::ONE], vec![1.0], (0.0, 1.0), 1.0)
            .ok()
            .map(Arc::new)
    })
    .clone()
    .ok_or_else(|| "internal: no transfer function for an isosurface's field".to_string())
}

/// A world's surfaces as the renderers take them.
#[derive(Default)]
pub struct Surfaces {
    pub iso: Vec<IsoSurface>,
    pub shapes: Vec<PlacedShape>,
}

/// The isosurfaces and shapes of `surfaces` (each with the transform of
/// the instance that placed it), or why one cannot be drawn.
pub fn surfaces(
    surfaces: &[(ObjectRef, Placement)],
    renderer: &RenderSettings,
    light: Option<DirectionalLight>,
) -> Result<Surfaces, String> {
    let mut out = Surfaces::default();
    for (surface, placement) in surfaces {
        let transform = placement.transform.unwrap_or(Mat4::IDENTITY);
        let not_ours = |o: &ObjectCell| format!("{} is not implemented by caveray", o.describe());
        let model = surface.ready::<SurfaceModel>(not_ours)?;
        let (geometry, material) = (&model.geometry, &model.material);
        let geometry_model = geometry.ready::<GeometryModel>(not_ours)?;
        let material_model = material.ready::<MaterialModel>(not_ours)?;
        let geometry_model = match geometry_model {
            GeometryModel::Iso(iso) => iso,
            GeometryModel::Shape(shape) => {
                let mut drawn = material_model.surface.clone().ok_or_else(|| {
                    format!(
                        "{}: {} colors isosurfaces only (it needs a field's curvature)",
                        surface.describe(),
                        material.describe()
                    )
                })?;
                let sampled = |sampler: &ObjectRef, what: &str| {
                    sampler.ready::<SamplerModel>(not_ours).map_err(|e| {
                        format!(
                            "{}: {} {what} by {e}",
                            surface.describe(),
                            material.describe()
                        )
                    })
                };
                if let Some(sampler) = &material_model.color_sampler {
                    drawn.color = Source::Sampler(sampled(sampler, "colors")?);
                }
                if let Some(sampler) = &material_model.opacity_sampler {
                    drawn.opacity = Source::Sampler(sampled(sampler, "takes its opacity")?);
                }
                let mut placed = PlacedShape::new(shape, drawn, transform);
                placed.ids = ObjectIds {
                    object: model.id,
                    instance: placement.instance,
                };
                placed.uniform = placement.uniform;
                out.shapes.push(placed);
                continue;
            }
        };
        let coloring = material_model.coloring;
        let volume = geometry_model.field.ready::<Arc<SpatialField>>(not_ours)?;
        let placed = PlacedVolume {
            volume,
            transfer_function: unclassified()?,
            transform,
            ids: ObjectIds {
                object: model.id,
                instance: placement.instance,
            },
        };
        for &isovalue in &geometry_model.isovalues {
            let settings = IsoSettings {
                filter: geometry_model.filter,
                // The renderer's step is in half cells.
                steps_per_cell: (2.0 / renderer.step_half_voxels()).clamp(0.25, 64.0),
                coloring,
                light: light.map(|l| l.towards),
                background: renderer.background,
                ..IsoSettings::new(isovalue)
            };
            settings
                .validate()
                .map_err(|e| format!("{}: {e}", surface.describe()))?;
            out.iso.push(IsoSurface {
                placed: placed.clone(),
                settings,
            });
        }
    }
    Ok(out)
}
