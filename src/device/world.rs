//! The world: the scene a frame renders, its volumes and surfaces
//! (directly, or in groups placed by instances, as VTK builds worlds) and
//! its lights.

use glam::Mat4;

use super::group::GroupModel;
use super::instance::InstanceModel;
use super::object::{ObjectRef, State, Unready};
use super::table::Read;
use super::table::{object_list, p, DefaultValue, SubtypeInfo};
use super::types::DataType as T;
use crate::scene::Uniforms;
use crate::scene::MAX_VOLUMES;

pub static INFO: SubtypeInfo = SubtypeInfo {
    kind: T::WORLD,
    subtype: "",
    description: "the scene: up to 8 volumes, composited sample by sample where they overlap, or isosurfaces, the nearest showing; lit by the first directional light",
    extensions: &[],
    params: &[
        object_list("volume", &[T::VOLUME, T::OBJECT], "ARRAY1D of ANARI_VOLUME"),
        object_list("surface", &[T::SURFACE, T::OBJECT], "ARRAY1D of ANARI_SURFACE (isosurfaces)"),
        object_list("light", &[T::LIGHT, T::OBJECT], "ARRAY1D of ANARI_LIGHT; the first directional light sets the shading's light"),
        object_list("instance", &[T::INSTANCE, T::OBJECT], "ARRAY1D of ANARI_INSTANCE: groups of volumes and surfaces, each placed by its transform"),
        p("caveray.region", &[T::FLOAT32_BOX3], false, DefaultValue::None,
          "under the device's caveray.mpi: the box of world space this rank's world owns (lower corner, \
           upper corner); its samples are this rank's, the ranks' boxes must not overlap, and their \
           bounding box is the whole; default: the bounds of the world's volumes"),
    ],
    commit: Some(commit),
};

/// How a world holds one of its volumes or surfaces: directly
/// ([`Placement::DIRECT`]) or through an instance, whose transform,
/// uniform attributes (surfaces only) and `id` it takes.
#[derive(Clone, Copy)]
pub struct Placement {
    pub transform: Option<Mat4>,
    pub uniform: Uniforms,
    /// The instance's `id`, UINT32 max where it set none.
    pub instance: u32,
}

impl Placement {
    pub const DIRECT: Self = Self {
        transform: None,
        uniform: [None; 5],
        instance: u32::MAX,
    };
}

/// A world after commit: the objects its arrays name, each volume and
/// surface as it is placed.
#[derive(Clone, Default)]
pub struct WorldModel {
    pub volumes: Vec<(ObjectRef, Placement)>,
    pub surfaces: Vec<(ObjectRef, Placement)>,
    pub lights: Vec<ObjectRef>,
    /// `caveray.region`: lower and upper corner.
    pub region: Option<(glam::Vec3, glam::Vec3)>,
}

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let direct = |name, kind| -> Result<Vec<(ObjectRef, Placement)>, String> {
        Ok(r.objects(name, kind)?
            .into_iter()
            .map(|o| (o, Placement::DIRECT))
            .collect())
    };
    let mut volumes = direct("volume", T::VOLUME)?;
    let mut surfaces = direct("surface", T::SURFACE)?;
    for instance in r.objects("instance", T::INSTANCE)? {
        let model = match instance.derived::<InstanceModel>() {
            Ok(model) => model,
            Err(Unready::OtherKind) => continue,
            Err(Unready::Unusable(why)) => return Err(why),
        };
        let members = match model.group.derived::<GroupModel>() {
            Ok(members) => members,
            Err(Unready::OtherKind) => continue,
            Err(Unready::Unusable(why)) => return Err(why),
        };
        let placement = Placement {
            transform: Some(model.transform),
            uniform: model.uniform,
            instance: model.id,
        };
        let placed = |o: &ObjectRef| (o.clone(), placement);
        volumes.extend(members.volumes.iter().map(placed));
        surfaces.extend(members.surfaces.iter().map(placed));
    }
    if volumes.len() > MAX_VOLUMES {
        return Err(format!(
            "{} volumes (directly and through instances); caveray composites up to {MAX_VOLUMES} per world",
            volumes.len()
        ));
    }
    let region = match r.set("caveray.region") {
        None => None,
        Some(_) => {
            let [a, b, c, d, e, f] = r.floats::<6>("caveray.region")?;
            let (lo, hi) = (glam::Vec3::new(a, b, c), glam::Vec3::new(d, e, f));
            if !(lo.is_finite() && hi.is_finite() && lo.cmplt(hi).all()) {
                return Err(format!(
                    "'caveray.region' must be a box with its lower corner below its upper one on every axis, got {lo} to {hi}"
                ));
            }
            Some((lo, hi))
        }
    };
    Ok(Some(State::ready(WorldModel {
        volumes,
        surfaces,
        lights: r.objects("light", T::LIGHT)?,
        region,
    })))
}
