//! The world: the scene a frame renders, its volumes and surfaces
//! (directly, or in groups placed by instances, as VTK builds worlds) and
//! its lights.

use glam::Mat4;

use super::group::GroupModel;
use super::instance::InstanceModel;
use super::object::{ObjectRef, State, Unready};
use super::table::Read;
use super::table::{object_list, SubtypeInfo};
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
    ],
    commit: Some(commit),
};

/// A world after commit: the objects its arrays name, each volume and
/// surface with the transform of the instance that placed it (`None`: in
/// the world directly), each surface with that instance's attributes.
#[derive(Clone, Default)]
pub struct WorldModel {
    pub volumes: Vec<(ObjectRef, Option<Mat4>)>,
    pub surfaces: Vec<(ObjectRef, Option<Mat4>, Uniforms)>,
    pub lights: Vec<ObjectRef>,
}

fn commit(r: &Read<'_>, _warn: &mut dyn FnMut(String)) -> Result<Option<State>, String> {
    let direct = |name, kind| -> Result<Vec<(ObjectRef, Option<Mat4>)>, String> {
        Ok(r.objects(name, kind)?
            .into_iter()
            .map(|o| (o, None))
            .collect())
    };
    let mut volumes = direct("volume", T::VOLUME)?;
    let mut surfaces: Vec<_> = direct("surface", T::SURFACE)?
        .into_iter()
        .map(|(o, t)| (o, t, Uniforms::default()))
        .collect();
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
        let placed = |o: &ObjectRef| (o.clone(), Some(model.transform));
        volumes.extend(members.volumes.iter().map(placed));
        surfaces.extend(
            members
                .surfaces
                .iter()
                .map(|o| (o.clone(), Some(model.transform), model.uniform)),
        );
    }
    if volumes.len() > MAX_VOLUMES {
        return Err(format!(
            "{} volumes (directly and through instances); caveray composites up to {MAX_VOLUMES} per world",
            volumes.len()
        ));
    }
    Ok(Some(State::ready(WorldModel {
        volumes,
        surfaces,
        lights: r.objects("light", T::LIGHT)?,
    })))
}
