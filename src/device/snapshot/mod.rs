//! What a committed frame renders, read out of its objects into the plain
//! values the engine takes (`engine::Inputs`): the world as a `Scene` with
//! its surfaces, the camera as views, the renderer's settings, the
//! frame's size and channels. The device keeps a frame's snapshot until
//! anything is committed, changed or released (its epoch moves on), so
//! that pairing frames compares snapshots instead of reading every
//! candidate's objects again.

mod surfaces;

use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::camera::CameraModel;
use super::frame::{self, color_format};
use super::light::DirectionalLight;
use super::object::{ObjectCell, ObjectRef};
use super::types::{kind_name, DataType};
use super::volume::VolumeModel;
use super::world::WorldModel;
use crate::cluster::Ranks;
use crate::engine::{Deadline, Inputs, Share, Unrenderable, Views};
use crate::render::{Backend, FrameDesc, RenderSettings, StreamWait};
use crate::render::{Lamp, MAX_LAMPS};
use crate::scene::{ObjectIds, PlacedVolume, Scene, SpatialField};

/// The device's count of changes: a snapshot taken at one epoch stands
/// while the epoch is the same.
pub type Epoch = u64;

/// A frame's render, as values.
pub struct FrameSnapshot {
    pub inputs: Arc<Inputs>,
    /// The color channel's ANARI type, if the frame has one.
    pub color_type: Option<DataType>,
    pub hit_channels: frame::HitChannels,
    pub deadline: Option<Deadline>,
}

/// Reads what `frame` renders with `backend` out of its committed
/// objects, or says why it cannot render.
pub fn take(
    frame: &ObjectRef,
    backend: Backend,
    gpu_budget: Option<u64>,
    stream_wait: StreamWait,
    ranks: Option<&Arc<Ranks>>,
) -> Result<FrameSnapshot, String> {
    let params = frame
        .lock()
        .committed
        .clone()
        .ok_or("the frame has not been committed")?;
    let frame::Setup {
        size,
        color_type,
        depth,
        hit_channels,
        accumulate,
        deadline,
    } = frame::setup(&params)?;
    let needed = |name: &str, kind: DataType| -> Result<ObjectRef, String> {
        let o = params.object(name).ok_or_else(|| {
            format!(
                "no {0}: set parameter '{name}' to a {0} and commit the frame",
                kind_name(kind)
            )
        })?;
        if !o.implemented {
            return Err(format!("{} is not implemented by caveray", o.describe()));
        }
        Ok(o.clone())
    };
    let camera = needed("camera", DataType::CAMERA)?;
    let renderer = needed("renderer", DataType::RENDERER)?;
    let world = needed("world", DataType::WORLD)?;
    let cannot_be = |role: &'static str| {
        move |o: &ObjectCell| format!("{} cannot be used as the frame's {role}", o.describe())
    };
    let camera_model = camera.ready::<CameraModel>(cannot_be("camera"))?;
    let views = camera_model.views(size)?;
    let mut settings = renderer.ready::<RenderSettings>(cannot_be("renderer"))?;
    let world_model = world.ready::<WorldModel>(cannot_be("world"))?;
    // The first usable directional light lights the shading.
    let light = world_model
        .lights
        .iter()
        .find_map(|l| l.usable::<DirectionalLight>());
    if let Some(light) = light {
        settings.light = light.towards;
        settings.light_color = light.color;
    }
    // Surfaces also take the point and spot lights, the first MAX_LAMPS.
    settings.lamps = world_model
        .lights
        .iter()
        .filter_map(|l| l.usable::<Lamp>())
        .take(MAX_LAMPS)
        .collect();
    settings.headlight = light.is_none() && settings.lamps.is_empty();
    settings.directional = light.is_some();
    let not_ours = |o: &ObjectCell| format!("{} is not implemented by caveray", o.describe());
    let mut placed = Vec::with_capacity(world_model.volumes.len());
    for (v, placement) in &world_model.volumes {
        let model = v.ready::<VolumeModel>(not_ours)?;
        let volume = model.field.ready::<Arc<SpatialField>>(not_ours)?;
        placed.push(PlacedVolume {
            volume,
            transfer_function: model.transfer_function,
            transform: placement.transform.unwrap_or(Mat4::IDENTITY),
            ids: ObjectIds {
                object: model.id,
                instance: placement.instance,
            },
        });
    }
    let surfaces = surfaces::surfaces(&world_model.surfaces, &settings, light)?;
    let in_world = |e: crate::scene::SceneError| format!("{}: {e}", world.describe());
    let scene = match (placed.is_empty(), surfaces.shapes.is_empty()) {
        (true, true) => None,
        (true, false) => Some(Scene::of_shapes(surfaces.shapes).map_err(in_world)?),
        (false, _) => Some(
            Scene::placed(placed)
                .and_then(|s| s.with_shapes(surfaces.shapes))
                .map_err(in_world)?,
        ),
    };
    if let Some(scene) = &scene {
        camera_model.check_eyes(&views, scene.bounds())?;
    }
    let surfaces = surfaces.iso;
    let share = match ranks {
        None => None,
        Some(ranks) => {
            let refuse = |what: &str| {
                Err(format!(
                    "a data-parallel frame (the device's caveray.mpi) {what}"
                ))
            };
            if !matches!(views, Views::Mono(_)) {
                return refuse("takes a camera with one view: no stereo pair or multi-view panel");
            }
            if depth || !hit_channels.is_empty() {
                return refuse("composites color only: unset channel.depth and the hit channels");
            }
            if deadline.is_some() {
                return refuse("has no deadline: unset caveray.deadline");
            }
            if settings.background_image.is_some() {
                return refuse("is composited over the background color, not an image");
            }
            if !surfaces.is_empty() || scene.as_ref().is_some_and(|s| !s.shapes().is_empty()) {
                return refuse(
                    "composites volumes alone: every rank would draw the world's surfaces over its part",
                );
            }
            // A world with nothing and no region sends an empty box, which
            // every rank then refuses together; the bounds of bricks stored
            // with an apron overlap, which they refuse too.
            let region = world_model
                .region
                .or_else(|| scene.as_ref().map(Scene::bounds))
                .unwrap_or((Vec3::ZERO, Vec3::ZERO));
            Some(Share {
                ranks: Arc::clone(ranks),
                region,
            })
        }
    };
    let mut desc =
        FrameDesc::new(size).with_color(color_type.and_then(color_format).unwrap_or_default());
    desc.depth = depth;
    desc.hits = !hit_channels.is_empty();
    let inputs = Inputs {
        scene,
        surfaces,
        views,
        settings,
        desc,
        backend,
        gpu_budget,
        stream_wait,
        accumulate: accumulate && share.is_none(),
        share,
    };
    inputs.check().map_err(|e| match e {
        Unrenderable::VolumesAndSurfaces => format!(
            "{} holds isosurfaces beside volumes or surfaces of primitives; caveray draws isosurfaces alone in a frame (an isosurface composited with a volume is not implemented)",
            world.describe()
        ),
        Unrenderable::PanelDepth => "a multi-view panel image has no depth channel (each subpixel has its own eye): unset 'channel.depth', or set the camera's 'view'".into(),
        Unrenderable::PanelHits => "a multi-view panel image has no id, normal or albedo channels (each subpixel has its own eye): unset them, or set the camera's 'view'".into(),
        Unrenderable::IsosurfaceHits => format!(
            "{} holds isosurfaces, whose frames have color and depth channels only: unset channel.primitiveId, objectId, instanceId, normal and albedo",
            world.describe()
        ),
        Unrenderable::PanelSurfaces(n) => format!(
            "{} has {n} isosurfaces (surfaces times iso-values); a multi-view panel image shows one",
            world.describe()
        ),
    })?;
    Ok(FrameSnapshot {
        inputs: Arc::new(inputs),
        color_type,
        hit_channels,
        deadline,
    })
}
