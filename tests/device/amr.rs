//! `amr` fields as hosts send them, through the device model on the CPU
//! reference: OpenCOVER's form and anari-visionaray's give the same
//! image; bad block tables are
//! refused by name and leave the device rendering.

use crate::common;

use anari_library_caveray::device::{DataType, Severity, Subject};
use common::device::{bytes, centre, same, Host};

fn image(h: &mut Host, field: u64) -> Vec<u8> {
    let v = h.volume(field);
    h.set(v, "opacity", DataType::FLOAT32, bytes(&[0.5f32]));
    h.render(v)
}

#[test]
fn both_forms_give_the_same_image() {
    let mut h = Host::new();
    let ramp = |x: u32| x as f32 / 3.0;
    let opencover = h.amr_field(ramp, true);
    let visionaray = h.amr_field(ramp, false);
    let grid = h.field(ramp, None);
    let a = image(&mut h, opencover);
    let b = image(&mut h, visionaray);
    let g = image(&mut h, grid);
    assert!(h.messages(Severity::Error).is_empty());
    same(&a, &b).unwrap();
    // The fine level's centres are the grid's vertices; the AMR field
    // reaches half a fine cell further, so rays cross a little more.
    let (ca, cg) = (centre(&a), centre(&g));
    assert!(cg[0] > 40 && ca[0] >= cg[0], "{ca:?} vs {cg:?}");
}

/// Commits an `amr` field with one array changed by `spoil`, and returns
/// the error it was refused with.
fn refused(spoil: impl Fn(&mut Host, u64)) -> String {
    let mut h = Host::new();
    let f = h.amr_field(|x| x as f32, true);
    assert!(h.errors().is_empty());
    spoil(&mut h, f);
    h.d.commit(Subject::Object(f));
    let errors = h.errors();
    assert_eq!(errors.len(), 1, "{errors:?}");
    // The device renders on: a good field after the bad one.
    let good = h.amr_field(|x| x as f32 / 3.0, false);
    let pixels = image(&mut h, good);
    assert!(centre(&pixels)[0] > 40);
    errors[0].1.clone()
}

fn set_list(h: &mut Host, f: u64, name: &str, element: DataType, n: u64, data: Vec<u8>) {
    let a = h.array(DataType::ARRAY1D, element, [n, 1, 1], &data);
    h.set_object(f, name, DataType::ARRAY1D, a);
    h.d.release(a);
}

#[test]
fn bad_block_tables_are_refused_by_name() {
    let e = refused(|h, f| {
        set_list(h, f, "block.level", DataType::INT32, 2, bytes(&[0i32, 5]));
    });
    assert!(
        e.contains("block 1 is at level 5") && e.contains("2 levels"),
        "{e}"
    );
    let e = refused(|h, f| {
        set_list(h, f, "block.level", DataType::INT32, 1, bytes(&[0i32]));
    });
    assert!(
        e.contains("'block.bounds' has 2 blocks and 'block.level' 1"),
        "{e}"
    );
    let e = refused(|h, f| {
        let bounds: [i32; 12] = [0, 0, 0, 3, 3, 3, 0, 0, 0, 2, 1, 1];
        set_list(
            h,
            f,
            "block.bounds",
            DataType::INT32_BOX3,
            2,
            bytes(&bounds),
        );
    });
    assert!(
        e.contains("'block.data' element 1 is 2x2x2") && e.contains("3x2x2 cells"),
        "{e}"
    );
    let e = refused(|h, f| {
        let bounds: [i32; 12] = [0, 0, 0, 3, 3, 3, 1, 1, 1, 0, 0, 0];
        set_list(
            h,
            f,
            "block.bounds",
            DataType::INT32_BOX3,
            2,
            bytes(&bounds),
        );
    });
    assert!(
        e.contains("block 1's bounds") && e.contains("hold no cell"),
        "{e}"
    );
    let e = refused(|h, f| {
        set_list(
            h,
            f,
            "cellWidth",
            DataType::FLOAT32,
            2,
            bytes(&[1.0f32, -2.0]),
        );
    });
    assert!(e.contains("level 1's cell width is -2"), "{e}");
    let e = refused(|h, f| {
        h.d.unset_param(Subject::Object(f), "block.data");
    });
    assert!(e.contains("needs 'block.data'"), "{e}");
}
