//! The scene graph VTK and ParaView build: the world's `instance` array,
//! `transform` instances placing groups of volumes. A volume placed by a
//! translation and an axis scale renders as the same grid with its origin
//! and spacing moved there.

use crate::common;

use anari_library_caveray::device::{DataType, Property, Severity, Subject};
use common::device::{bytes, same, Host};

/// A world holding `volume` through an instance with `transform`.
fn instanced_world(h: &mut Host, volume: u64, transform: [f32; 16]) -> u64 {
    let group = h.d.new_object(DataType::GROUP, "");
    let list = h.array(
        DataType::ARRAY1D,
        DataType::VOLUME,
        [1, 1, 1],
        &bytes(&[volume as usize]),
    );
    h.set_object(group, "volume", DataType::ARRAY1D, list);
    h.d.commit(Subject::Object(group));
    let instance = h.d.new_object(DataType::INSTANCE, "transform");
    h.set_object(instance, "group", DataType::GROUP, group);
    h.set(
        instance,
        "transform",
        DataType::FLOAT32_MAT4,
        bytes(&transform),
    );
    h.d.commit(Subject::Object(instance));
    let instances = h.array(
        DataType::ARRAY1D,
        DataType::INSTANCE,
        [1, 1, 1],
        &bytes(&[instance as usize]),
    );
    let world = h.d.new_object(DataType::WORLD, "");
    h.set_object(world, "instance", DataType::ARRAY1D, instances);
    h.d.commit(Subject::Object(world));
    for o in [group, list, instance, instances] {
        h.d.release(o);
    }
    world
}

fn scale_then_move(s: f32, t: [f32; 3]) -> [f32; 16] {
    [
        s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0, 0.0, s, 0.0, t[0], t[1], t[2], 1.0,
    ]
}

#[test]
fn instanced_volumes_render_where_their_transform_puts_them() {
    let mut h = Host::new();
    // A ramp on [-1, 1]^3 (Host::field's placement), translucent.
    let ramp = |x: u32| x as f32 / 3.0;
    let field = h.field(ramp, None);
    let volume = h.volume(field);
    h.set(volume, "opacity", DataType::FLOAT32, bytes(&[0.3f32]));
    h.d.commit(Subject::Object(volume));
    let m = scale_then_move(0.5, [0.25, 0.0, 0.0]);
    let world = instanced_world(&mut h, volume, m);

    // The bounds: [-1, 1]^3 halved and moved by 0.25 in x.
    let bounds = h.d.property(Subject::Object(world), "bounds", true);
    assert_eq!(
        bounds,
        Some(Property::Box3([-0.25, -0.5, -0.5, 0.75, 0.5, 0.5]))
    );

    let (frame, _camera) = h.frame(volume, 3.0);
    h.set_object(frame, "world", DataType::WORLD, world);
    h.d.commit(Subject::Object(frame));
    let instanced = h.pixels(frame);
    // Unchanged: the placed grid is kept, so the image is too.
    same(&h.pixels(frame), &instanced).unwrap();
    assert_eq!(
        h.d.property(Subject::Object(frame), "numSamples", true),
        Some(Property::Int32(2))
    );

    // The same grid placed by hand: origin and spacing moved.
    let moved = h.field(ramp, None);
    h.set(
        moved,
        "origin",
        DataType::FLOAT32_VEC3,
        bytes(&[-0.25f32, -0.5, -0.5]),
    );
    h.set(
        moved,
        "spacing",
        DataType::FLOAT32_VEC3,
        bytes(&[1.0f32 / 3.0; 3]),
    );
    h.d.commit(Subject::Object(moved));
    let direct = h.volume(moved);
    h.set(direct, "opacity", DataType::FLOAT32, bytes(&[0.3f32]));
    let by_hand = h.render(direct);
    same(&instanced, &by_hand).unwrap();
    assert!(h.messages(Severity::Error).is_empty());
    assert!(h.messages(Severity::Warning).is_empty());
}

/// A field on [-1, 1]^3 (as Host::field) whose voxel (i, j, k) is
/// `value(i, j)`.
fn field_xy(h: &mut Host, value: impl Fn(u32, u32) -> f32) -> u64 {
    let voxels: Vec<f32> = (0..64).map(|w| value(w % 4, (w / 4) % 4)).collect();
    let data = h.array(
        DataType::ARRAY3D,
        DataType::FLOAT32,
        [4, 4, 4],
        &bytes(&voxels),
    );
    let f = h.d.new_object(DataType::SPATIAL_FIELD, "structuredRegular");
    h.set_object(f, "data", DataType::ARRAY3D, data);
    h.set(f, "origin", DataType::FLOAT32_VEC3, bytes(&[-1.0f32; 3]));
    h.set(
        f,
        "spacing",
        DataType::FLOAT32_VEC3,
        bytes(&[2.0f32 / 3.0; 3]),
    );
    h.d.commit(Subject::Object(f));
    h.d.release(data);
    f
}

/// A volume over `field` whose color (red to blue) and opacity (none to
/// 0.6) follow the value over [0, 1].
fn tinted(h: &mut Host, field: u64) -> u64 {
    let v = h.volume(field);
    let colors = h.array(
        DataType::ARRAY1D,
        DataType::FLOAT32_VEC3,
        [2, 1, 1],
        &bytes(&[1.0f32, 0.0, 0.0, 0.0, 0.0, 1.0]),
    );
    let opacities = h.array(
        DataType::ARRAY1D,
        DataType::FLOAT32,
        [2, 1, 1],
        &bytes(&[0.0f32, 0.6]),
    );
    h.set_object(v, "color", DataType::ARRAY1D, colors);
    h.set_object(v, "opacity", DataType::ARRAY1D, opacities);
    h.set(
        v,
        "valueRange",
        DataType::FLOAT32_BOX1,
        bytes(&[0.0f32, 1.0]),
    );
    h.d.commit(Subject::Object(v));
    h.d.release(colors);
    h.d.release(opacities);
    v
}

#[test]
fn a_rotated_instance_renders_as_the_grid_turned() {
    let mut h = Host::new();
    // A ramp along x, turned 90 degrees about z, is a ramp along y.
    let ramp = |i: u32| 0.1 + i as f32 / 4.0;
    let field = field_xy(&mut h, |i, _| ramp(i));
    let volume = tinted(&mut h, field);
    let quarter_turn = [
        0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    ];
    let world = instanced_world(&mut h, volume, quarter_turn);
    let (frame, _camera) = h.frame(volume, 3.0);
    h.set_object(frame, "world", DataType::WORLD, world);
    h.d.commit(Subject::Object(frame));
    let turned = h.pixels(frame);

    let along_y = field_xy(&mut h, |_, j| ramp(j));
    let direct = tinted(&mut h, along_y);
    let by_hand = h.render(direct);
    same(&turned, &by_hand).unwrap();
    // Not merely the unturned ramp.
    assert!(same(&turned, &h.render(volume)).is_err());
    assert!(h.messages(Severity::Error).is_empty());
    assert!(h.messages(Severity::Warning).is_empty());
}

#[test]
fn singular_and_projective_instances_are_refused_with_the_reason() {
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let volume = h.volume(field);
    h.d.commit(Subject::Object(volume));
    let mut flat = scale_then_move(1.0, [0.0; 3]);
    flat[5] = 0.0;
    let mut projective = scale_then_move(1.0, [0.0; 3]);
    projective[3] = 0.5;
    for (m, reason) in [(flat, "is singular"), (projective, "is projective")] {
        let world = instanced_world(&mut h, volume, m);
        let errors = h.messages(Severity::Error);
        assert!(errors.iter().any(|e| e.contains(reason)), "{errors:?}");
        h.d.release(world);
    }
}

/// A world whose `volume` array holds `volumes`.
fn world_of(h: &mut Host, volumes: &[u64]) -> u64 {
    let handles: Vec<usize> = volumes.iter().map(|&v| v as usize).collect();
    let list = h.array(
        DataType::ARRAY1D,
        DataType::VOLUME,
        [volumes.len() as u64, 1, 1],
        &bytes(&handles),
    );
    let world = h.d.new_object(DataType::WORLD, "");
    h.set_object(world, "volume", DataType::ARRAY1D, list);
    h.d.commit(Subject::Object(world));
    h.d.release(list);
    world
}

#[test]
fn several_volumes_in_one_world_are_all_drawn_and_more_than_eight_refused() {
    let mut h = Host::new();
    // Two halves of one ramp: low values in one volume, high in the
    // other, each transparent where the other is not.
    let low = h.field(|x| if x < 2 { 0.5 } else { 0.0 }, None);
    let high = h.field(|x| if x >= 2 { 0.5 } else { 0.0 }, None);
    let whole = h.field(|_| 0.5, None);
    let [low, high, whole] = [low, high, whole].map(|f| tinted(&mut h, f));
    let one = h.render(whole);
    let world = world_of(&mut h, &[low, high]);
    let (frame, _camera) = h.frame(low, 3.0);
    h.set_object(frame, "world", DataType::WORLD, world);
    h.d.commit(Subject::Object(frame));
    let two = h.pixels(frame);
    let low_only = h.render(low);
    // Both halves are there: unlike either alone, close to the whole.
    assert!(same(&two, &low_only).is_err());
    let worst = two
        .iter()
        .zip(&one)
        .map(|(a, b)| a.abs_diff(*b))
        .max()
        .unwrap();
    assert!(worst <= 40, "two halves vs the whole: off by {worst}");
    assert!(h.messages(Severity::Error).is_empty());
    assert!(h.messages(Severity::Warning).is_empty());

    let nine = world_of(&mut h, &[low; 9]);
    let errors = h.messages(Severity::Error);
    assert!(
        errors.iter().any(|e| e.contains(
            "9 volumes (directly and through instances); caveray composites up to 8 per world"
        )),
        "{errors:?}"
    );
    h.d.release(nine);
}

/// A world whose `volume` list is an ARRAY1D of `element` holding `objects`.
fn world_listing(h: &mut Host, element: DataType, objects: &[u64]) -> u64 {
    let handles: Vec<usize> = objects.iter().map(|&o| o as usize).collect();
    let list = h.array(
        DataType::ARRAY1D,
        element,
        [objects.len() as u64, 1, 1],
        &bytes(&handles),
    );
    let world = h.d.new_object(DataType::WORLD, "");
    h.set_object(world, "volume", DataType::ARRAY1D, list);
    h.d.commit(Subject::Object(world));
    h.d.release(list);
    world
}

#[test]
fn object_lists_typed_as_anari_object_hold_their_kind() {
    // pynari types every object list it builds as ANARI_OBJECT.
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let volume = h.volume(field);
    h.d.commit(Subject::Object(volume));
    let typed = world_listing(&mut h, DataType::VOLUME, &[volume]);
    let generic = world_listing(&mut h, DataType::OBJECT, &[volume]);
    assert!(h.messages(Severity::Warning).is_empty());
    assert!(h.messages(Severity::Error).is_empty());
    // Host::field places its grid on [-1, 1]^3.
    let cube = Some(Property::Box3([-1.0, -1.0, -1.0, 1.0, 1.0, 1.0]));
    for world in [typed, generic] {
        assert_eq!(h.d.property(Subject::Object(world), "bounds", true), cube);
    }

    // Anything but volumes in the list is refused by name.
    let camera = h.d.new_object(DataType::CAMERA, "perspective");
    world_listing(&mut h, DataType::OBJECT, &[volume, camera]);
    let errors = h.messages(Severity::Error);
    assert!(
        errors.len() == 1
            && errors[0].contains("'volume' array holds camera 'perspective'")
            && errors[0].contains("expected only ANARI_VOLUMEs"),
        "{errors:?}"
    );
}

#[test]
fn a_list_refused_for_its_kind_is_unset_and_the_other_parameters_stay() {
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let volume = h.volume(field);
    h.d.commit(Subject::Object(volume));
    let world = world_of(&mut h, &[volume]);
    assert!(h.messages(Severity::Error).is_empty());
    let camera = h.d.new_object(DataType::CAMERA, "perspective");
    let handles = [camera as usize];
    let list = h.array(
        DataType::ARRAY1D,
        DataType::OBJECT,
        [1, 1, 1],
        &bytes(&handles),
    );
    h.set_object(world, "instance", DataType::ARRAY1D, list);
    h.d.release(list);
    h.d.commit(Subject::Object(world));
    let errors = h.messages(Severity::Error);
    assert!(
        errors.len() == 1
            && errors[0].contains("'instance' array holds camera 'perspective'")
            && errors[0].ends_with("; 'instance' is unset"),
        "{errors:?}"
    );
    // Committed again, the world has its volume and no instance list.
    h.d.commit(Subject::Object(world));
    assert!(h.messages(Severity::Error).is_empty());
    let cube = Some(Property::Box3([-1.0, -1.0, -1.0, 1.0, 1.0, 1.0]));
    assert_eq!(h.d.property(Subject::Object(world), "bounds", true), cube);
}
