//! The scene graph VTK and ParaView build: the world's `instance` array,
//! `transform` instances placing groups of volumes. A volume placed by a
//! translation and an axis scale renders as the same grid with its origin
//! and spacing moved there.

mod common;

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

#[test]
fn rotated_volumes_are_refused_with_the_reason() {
    let mut h = Host::new();
    let field = h.field(|x| x as f32 / 3.0, None);
    let volume = h.volume(field);
    h.d.commit(Subject::Object(volume));
    // 90 degrees about z.
    let rotate = [
        0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    ];
    let world = instanced_world(&mut h, volume, rotate);
    let (frame, _camera) = h.frame(volume, 3.0);
    h.set_object(frame, "world", DataType::WORLD, world);
    h.d.commit(Subject::Object(frame));
    h.d.render_frame(frame, None);
    assert!(h.d.map_frame(frame, "channel.color").is_none());
    let errors = h.messages(Severity::Error);
    assert!(
        errors
            .iter()
            .any(|e| e.contains("rotates, shears, mirrors or projects the volume")),
        "{errors:?}"
    );
}
