//! A world's surfaces as a frame renders them: each surface's geometry,
//! field and material resolved, one `IsoSurface` per iso-value, shaded by
//! the renderer's settings and the world's light (its direction: the
//! isosurface shading's light is white).

use std::sync::{Arc, OnceLock};

use glam::Mat4;

use crate::device::geometry::IsoGeometry;
use crate::device::light::DirectionalLight;
use crate::device::material::Coloring;
use crate::device::object::{ObjectCell, ObjectRef};
use crate::device::surface::SurfaceModel;
use crate::render::iso::{IsoSettings, IsoSurface};
use crate::render::RenderSettings;
use crate::scene::{PlacedVolume, StructuredVolume, TransferFunction};

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

/// The isosurfaces of `surfaces` (each with the transform of the instance
/// that placed it), or why one cannot be drawn.
pub fn iso_surfaces(
    surfaces: &[(ObjectRef, Option<Mat4>)],
    renderer: &RenderSettings,
    light: Option<DirectionalLight>,
) -> Result<Vec<IsoSurface>, String> {
    let mut out = Vec::new();
    for (surface, transform) in surfaces {
        let not_ours = |o: &ObjectCell| format!("{} is not implemented by caveray", o.describe());
        let model = surface.ready::<SurfaceModel>(not_ours)?;
        let (geometry, material) = (&model.geometry, &model.material);
        let geometry_model = geometry.ready::<IsoGeometry>(not_ours)?;
        let coloring = material.ready::<Coloring>(not_ours)?;
        let volume = geometry_model
            .field
            .ready::<Arc<StructuredVolume>>(not_ours)?;
        let placed = PlacedVolume {
            volume,
            transfer_function: unclassified()?,
            transform: transform.unwrap_or(Mat4::IDENTITY),
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
            out.push(IsoSurface {
                placed: placed.clone(),
                settings,
            });
        }
    }
    Ok(out)
}
