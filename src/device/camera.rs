//! Cameras after commit: each lowers to the renderer's `RayGen` for a frame.

use glam::{DVec2, DVec3, UVec2};

use super::value::Params;
use crate::geometry::{
    ImageRegion, MatrixCamera, OffAxisCamera, PinholeCamera, PrimaryRays, RayGen, Screen,
};

#[derive(Clone, Debug)]
pub enum CameraModel {
    /// ANARI's perspective camera; `aspect` falls back to the frame's.
    Perspective {
        position: DVec3,
        direction: DVec3,
        up: DVec3,
        fovy: f64,
        aspect: Option<f64>,
        region: ImageRegion,
    },
    Matrix(Box<MatrixCamera>),
    OffAxis(OffAxisCamera),
}

impl CameraModel {
    /// The camera a committed `subtype` describes, or what is wrong with it.
    pub fn from_params(subtype: &str, p: &Params) -> Result<Self, String> {
        let vec3 = |name: &str, default: Option<[f64; 3]>| -> Result<DVec3, String> {
            match (p.vec3(name), default) {
                (Some(v), _) => Ok(v.as_dvec3()),
                (None, Some(d)) => Ok(DVec3::from(d)),
                (None, None) => Err(format!("parameter '{name}' (FLOAT32_VEC3) is required")),
            }
        };
        let model = match subtype {
            "perspective" => {
                let region = p.get("imageRegion").and_then(|v| v.f32s());
                let region = match region.as_deref() {
                    Some(&[x0, y0, x1, y1]) => ImageRegion {
                        min: DVec2::new(x0.into(), y0.into()),
                        max: DVec2::new(x1.into(), y1.into()),
                    },
                    _ => ImageRegion::FULL,
                };
                CameraModel::Perspective {
                    position: vec3("position", Some([0.0, 0.0, 0.0]))?,
                    direction: vec3("direction", Some([0.0, 0.0, -1.0]))?,
                    up: vec3("up", Some([0.0, 1.0, 0.0]))?,
                    fovy: p.f32("fovy", std::f32::consts::FRAC_PI_3).into(),
                    aspect: p.get("aspect").map(|_| p.f32("aspect", 1.0).into()),
                    region,
                }
            }
            "matrix" => {
                let mat = |name: &str| {
                    p.mat4(name)
                        .ok_or_else(|| format!("parameter '{name}' (FLOAT32_MAT4) is required"))
                };
                let camera = MatrixCamera::from_f32(mat("view")?, mat("proj")?);
                CameraModel::Matrix(Box::new(camera.map_err(|e| e.to_string())?))
            }
            "offAxis" => {
                let screen = Screen::new(
                    vec3("lowerLeft", None)?,
                    vec3("lowerRight", None)?,
                    vec3("upperRight", None)?,
                )
                .map_err(|e| e.to_string())?;
                let eye = vec3("eye", None)?;
                CameraModel::OffAxis(OffAxisCamera::new(screen, eye).map_err(|e| e.to_string())?)
            }
            other => return Err(format!("camera subtype '{other}' is not implemented")),
        };
        // A perspective camera is checked now with a square frame; its
        // aspect is only known for certain when a frame renders it.
        model.ray_gen(UVec2::ONE)?;
        Ok(model)
    }

    pub fn ray_gen(&self, size: UVec2) -> Result<RayGen, String> {
        match self {
            CameraModel::Perspective {
                position,
                direction,
                up,
                fovy,
                aspect,
                region,
            } => {
                let aspect = aspect.unwrap_or(f64::from(size.x) / f64::from(size.y));
                PinholeCamera::new(*position, *direction, *up, *fovy, aspect, *region)
                    .map(|c| c.ray_gen(size))
                    .map_err(|e| e.to_string())
            }
            CameraModel::Matrix(c) => Ok(c.ray_gen(size)),
            CameraModel::OffAxis(c) => Ok(c.ray_gen(size)),
        }
    }
}
