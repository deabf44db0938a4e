//! `nanovdb` fields as hosts send them (one grid's bytes in an ARRAY1D of
//! UINT8), written by the NanoVDB library at test time, through the
//! device model on the CPU reference: a grid renders as its values on a
//! structured grid placed by its map; blobs that are not a valid grid are
//! refused by name and leave the device rendering; `cubic` reads as
//! linear, with a warning that says so.

use crate::common;

use anari_library_caveray::device::{DataType, Severity, Subject};
use common::device::{bytes, centre, Host};

/// The field's image under a table over the fog's densities, the fog
/// scaled to the host's view (1/6).
fn image(h: &mut Host, field: u64) -> Vec<u8> {
    let v = h.volume(field);
    h.set(
        v,
        "valueRange",
        DataType::FLOAT32_BOX1,
        bytes(&[0.0f32, 1.0]),
    );
    h.set(v, "unitDistance", DataType::FLOAT32, bytes(&[0.5f32]));
    h.d.commit(Subject::Object(v));
    let group = h.d.new_object(DataType::GROUP, "");
    h.set_objects(group, "volume", DataType::VOLUME, &[v]);
    h.d.commit(Subject::Object(group));
    let instance = h.d.new_object(DataType::INSTANCE, "transform");
    h.set_object(instance, "group", DataType::GROUP, group);
    let s = 1.0f32 / 6.0;
    let m: [f32; 16] = [
        s, 0.0, 0.0, 0.0, 0.0, s, 0.0, 0.0, 0.0, 0.0, s, 0.0, -0.25, 0.33, -0.08, 1.0,
    ];
    h.set(instance, "transform", DataType::FLOAT32_MAT4, bytes(&m));
    h.d.commit(Subject::Object(instance));
    let pixels = h.render_instances(&[instance]);
    for o in [instance, group, v] {
        h.d.release(o);
    }
    pixels
}

#[test]
fn a_grid_renders_as_its_values_on_a_structured_grid() {
    let Some(written) = common::nanovdb::grids() else {
        return;
    };
    let mut h = Host::new();
    for (name, filter) in [("fog", None), ("fog16", None), ("fog", Some("nearest"))] {
        let vdb = h.nanovdb_field(&written.blob(name), filter);
        let dense = written.dense(name);
        let grid = h.structured_field(&dense, filter);
        let (a, b) = (image(&mut h, vdb), image(&mut h, grid));
        assert!(h.errors().is_empty());
        let worst = a.iter().zip(&b).map(|(x, y)| x.abs_diff(*y)).max().unwrap();
        eprintln!(
            "{name} {filter:?}: largest channel difference {worst}, centre {:?}",
            centre(&a)
        );
        assert!(worst <= 2, "{name} {filter:?}: channels differ by {worst}");
        assert_ne!(centre(&a), [a[0], a[1], a[2]], "{name}: the fog is in view");
        h.d.release(vdb);
        h.d.release(grid);
    }
}

/// Byte offsets in a grid: its first lower node, and the table entries
/// of its first two children (leaves).
fn first_children(blob: &[u8]) -> (usize, usize, usize) {
    let u64_at = |at: usize| u64::from_le_bytes(blob[at..at + 8].try_into().unwrap());
    let lower = 672 + u64_at(672 + 8) as usize;
    let mask = &blob[lower + 544..lower + 1056];
    let mut set = (0..4096).filter(|n| mask[n / 8] >> (n % 8) & 1 == 1);
    let (a, b) = (set.next().unwrap(), set.next().unwrap());
    (lower, lower + 1088 + 8 * a, lower + 1088 + 8 * b)
}

/// Commits a `nanovdb` field of `blob`: the error it was refused with,
/// after checking that the device renders a good field next.
fn refused(blob: &[u8], good: &[u8]) -> String {
    let mut h = Host::new();
    let bad = h.nanovdb_field(blob, None);
    let errors = h.errors();
    assert_eq!(errors.len(), 1, "{errors:?}");
    h.d.release(bad);
    let field = h.nanovdb_field(good, None);
    let pixels = image(&mut h, field);
    assert_ne!(centre(&pixels), [pixels[0], pixels[1], pixels[2]]);
    assert!(h.errors().is_empty());
    errors[0].1.clone()
}

#[test]
fn blobs_that_are_not_a_grid_are_refused_by_name() {
    let Some(written) = common::nanovdb::grids() else {
        return;
    };
    let good = written.blob("fog");
    let spoilt = |f: &dyn Fn(&mut Vec<u8>)| {
        let mut b = good.clone();
        f(&mut b);
        refused(&b, &good)
    };
    let e = spoilt(&|b| b[0] ^= 0x20);
    assert!(e.contains("magic number") && e.contains("NanoVDB0"), "{e}");
    let e = spoilt(&|b| b[16..20].copy_from_slice(&(31u32 << 21).to_le_bytes()));
    assert!(
        e.contains("NanoVDB 31.0.0") && e.contains("version 32"),
        "{e}"
    );
    let e = spoilt(&|b| b[636..640].copy_from_slice(&6u32.to_le_bytes()));
    assert!(e.contains("Vec3f values"), "{e}");
    let e = spoilt(&|b| b.truncate(b.len() / 2));
    assert!(
        e.contains("the grid's size") && e.contains("past the grid's"),
        "{e}"
    );
    let e = spoilt(&|b| b[672 + 8..672 + 16].copy_from_slice(&u64::MAX.to_le_bytes()));
    assert!(
        e.contains("the lower nodes") && e.contains("past the grid's"),
        "{e}"
    );
    // The root's offset off the 32-byte grid every node lies on.
    let e = spoilt(&|b| {
        let root = u64::from_le_bytes(b[672 + 24..672 + 32].try_into().unwrap());
        b[672 + 24..672 + 32].copy_from_slice(&(root + 4).to_le_bytes());
    });
    assert!(
        e.contains("the root is at byte") && e.contains("32-byte boundary"),
        "{e}"
    );
    // Root tile keys: a bit past the coordinates, and one key twice.
    let root = 672 + u64::from_le_bytes(good[672 + 24..672 + 32].try_into().unwrap()) as usize;
    let key = |t: usize| root + 64 + 32 * t;
    let e = spoilt(&|b| b[key(0) + 7] |= 0x80);
    assert!(
        e.contains("root tile 0's key") && e.contains("outside its three 20-bit"),
        "{e}"
    );
    let e = spoilt(&|b| b.copy_within(key(0)..key(0) + 8, key(1)));
    assert!(
        e.contains("root tile 1's key") && e.contains("another tile's too"),
        "{e}"
    );
    let (lower, first, second) = first_children(&good);
    // A child pointing at its own node: a cycle.
    let e = spoilt(&|b| b[first..first + 8].copy_from_slice(&0u64.to_le_bytes()));
    assert!(
        e.contains(&format!("the lower node at byte {lower}"))
            && e.contains("not a node of the level below"),
        "{e}"
    );
    // Two entries with one child.
    let e = spoilt(&|b| b.copy_within(first..first + 8, second));
    assert!(e.contains("another entry reached already"), "{e}");
    // Not UINT8.
    let mut h = Host::new();
    let data = h.array(
        DataType::ARRAY1D,
        DataType::FLOAT32,
        [4, 1, 1],
        &bytes(&[0f32; 4]),
    );
    let f = h.d.new_object(DataType::SPATIAL_FIELD, "nanovdb");
    h.set_object(f, "data", DataType::ARRAY1D, data);
    h.d.commit(Subject::Object(f));
    let errors = h.errors();
    assert!(
        errors[0]
            .1
            .contains("'data' holds ANARI_FLOAT32; it needs UINT8"),
        "{errors:?}"
    );
}

#[test]
fn cubic_reads_as_linear_and_says_so() {
    let Some(written) = common::nanovdb::grids() else {
        return;
    };
    let mut h = Host::new();
    let cubic = h.nanovdb_field(&written.blob("fog8"), Some("cubic"));
    let warnings = h.messages(Severity::Warning);
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("'cubic' is not implemented") && w.contains("linear")),
        "{warnings:?}"
    );
    let linear = h.nanovdb_field(&written.blob("fog8"), None);
    let (a, b) = (image(&mut h, cubic), image(&mut h, linear));
    common::device::same(&a, &b).unwrap();
}
