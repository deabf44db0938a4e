//! Multi-view displays (the display model): the shipped 8-view
//! lenticular monitor assigns subpixels to views as a hand-computed table
//! says, its pattern repeats every 5 pixels across and 8 rows up, every
//! view gets its share, a [table] gives the same display as the lens that
//! made it, the eyes sit on their line, every view is an off-axis camera
//! on the panel, and bad files fail naming the field.

use crate::common;

use anari_library_caveray::cave::{MultiViewDisplay, Rig, ViewPattern};
use anari_library_caveray::geometry::PrimaryRays;
use glam::{DVec2, DVec3, UVec2};

fn shipped() -> MultiViewDisplay {
    MultiViewDisplay::load(&common::config_dir().join("lenticular_8view.toml"))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// By hand: a lens is 3.75 subpixels wide and 8 views share it, so
/// subpixel k of the bottom row shows view floor((k mod 3.75) * 8 / 3.75):
/// k = 0..14 give 0, 2.13, 4.27, 6.4, 0.53, 2.67, 4.8, 6.93, 1.07, 3.2,
/// 5.33, 7.47, 1.6, 3.73, 5.87, floored. Each row up moves the lens 0.46875
/// subpixels right, one view's width: every view drops by one.
const ROW0: [u32; 15] = [0, 2, 4, 6, 0, 2, 4, 6, 1, 3, 5, 7, 1, 3, 5];

fn by_hand(x: u32, y: u32, c: usize) -> u32 {
    let k = (3 * (x % 5)) as usize + c;
    (ROW0[k] + 8 - y % 8) % 8
}

#[test]
fn subpixels_belong_to_the_views_a_hand_computed_table_gives() {
    let d = shipped();
    assert_eq!((d.views, d.resolution), (8, UVec2::new(1920, 1200)));
    for y in 0..16 {
        for x in 0..10 {
            for c in 0..3 {
                assert_eq!(
                    d.view_of(x, y, c),
                    by_hand(x, y, c),
                    "pixel ({x}, {y}) channel {c}"
                );
            }
        }
    }
    // Far across the panel too: the pattern repeats every 5 x 8 pixels.
    for (x, y) in [(1919, 1199), (1234, 567), (5, 8), (640, 400)] {
        for c in 0..3 {
            assert_eq!(
                d.view_of(x, y, c),
                by_hand(x, y, c),
                "pixel ({x}, {y}) channel {c}"
            );
        }
    }
    // Every view gets the same share of a period's 120 subpixels.
    let mut count = [0; 8];
    for v in d.view_table(UVec2::new(5, 8)).iter().flatten() {
        count[*v as usize] += 1;
    }
    assert_eq!(count, [15; 8]);
}

#[test]
fn a_table_gives_the_same_display_as_the_lens_it_came_from() {
    let lens = shipped();
    let table = lens.view_table(UVec2::new(5, 8));
    let rows: Vec<String> = table
        .iter()
        .map(|[r, g, b]| format!("[{r}, {g}, {b}]"))
        .collect();
    let text = std::fs::read_to_string(common::config_dir().join("lenticular_8view.toml"))
        .unwrap()
        .replace(
            "[lens]\npitch = 3.75\nslant = 0.15625\noffset = 0.0",
            &format!("[table]\nperiod = [5, 8]\nviews = [{}]", rows.join(", ")),
        );
    let from_table = MultiViewDisplay::from_toml(&text, "table.toml").unwrap();
    assert!(matches!(from_table.pattern, ViewPattern::Table { .. }));
    let size = UVec2::new(37, 29);
    assert_eq!(from_table.view_table(size), lens.view_table(size));
}

#[test]
fn eyes_sit_on_their_line_and_every_view_sees_the_panel_off_axis() {
    let d = shipped();
    let centre = d.screen.centre();
    for v in 0..8 {
        let eye = d.eye(v);
        // 700 mm in front of the panel, on a line along its x axis, 32.5 mm
        // apart, centred, view 0 at the right end.
        assert!((eye.z - 700.0).abs() < 1e-9 && eye.y.abs() < 1e-9, "{eye}");
        let expected_x = (3.5 - f64::from(v)) * 32.5;
        assert!(
            (eye.x - (centre.x + expected_x)).abs() < 1e-9,
            "view {v}: {eye}"
        );
    }
    assert_eq!(d.subpixel_eye(0, 0, 1), d.eye(2));
    // Never toe-in: every view's image plane is the panel, so the same
    // pixel of every view passes through the same point of the panel.
    let size = UVec2::new(64, 40);
    for (x, y) in [(0, 0), (63, 39), (20, 31)] {
        let on_panel = d.screen.point(DVec2::new(
            (f64::from(x) + 0.5) / 64.0,
            (f64::from(y) + 0.5) / 40.0,
        ));
        for v in 0..8 {
            let ray = d.view_camera(v).unwrap().pixel_ray(x, y, size);
            let hit = ray.hit_plane(centre, DVec3::Z).unwrap();
            assert!(
                (hit - on_panel).length() < 1e-9,
                "view {v}, pixel ({x}, {y})"
            );
            assert!((ray.origin - d.eye(v)).length() < 1e-9);
        }
    }
}

#[test]
fn bad_display_files_fail_naming_the_field() {
    let good = std::fs::read_to_string(common::config_dir().join("lenticular_8view.toml")).unwrap();
    let cases = [
        ("views = 8", "views = 0", "views", "from 1 to 64"),
        ("views = 8", "views = 65", "views", "from 1 to 64"),
        (
            "resolution = [1920, 1200]",
            "resolution = [1920]",
            "resolution",
            "two whole numbers",
        ),
        (
            "viewing_distance = 700.0",
            "viewing_distance = -1.0",
            "viewing_distance",
            "> 0",
        ),
        (
            "view_spacing = 32.5",
            "view_spacing = 0.0",
            "view_spacing",
            "> 0",
        ),
        ("pitch = 3.75", "pitch = 0.0", "lens.pitch", "> 0"),
        // Eyes out of sight of the panel, or a panel in one view.
        (
            "viewing_distance = 700.0",
            "viewing_distance = 1e30",
            "viewing_distance",
            "must be from 0.01 to 100 panel widths",
        ),
        (
            "view_spacing = 32.5",
            "view_spacing = 1e30",
            "view_spacing",
            "the line of eyes) must be at most 100 panel widths",
        ),
        (
            "pitch = 3.75",
            "pitch = 1e-38",
            "lens.pitch",
            "must be from 0.015625 to 10000 subpixels, got 1e-38",
        ),
        (
            "pitch = 3.75",
            "pitch = 1e30",
            "lens.pitch",
            "must be from 0.015625 to 10000 subpixels",
        ),
        (
            "slant = 0.15625",
            "slant = 1e30",
            "lens.slant",
            "must be from -10 to 10",
        ),
        (
            "ur = [259.2, 162.0, 0.0]",
            "ur = [259.2, -162.0, 0.0]",
            "ll",
            "the panel's corners",
        ),
        (
            "[lens]\npitch = 3.75\nslant = 0.15625\noffset = 0.0",
            "",
            "lens",
            "needs [lens] (pitch, slant, offset) or [table]",
        ),
        (
            "offset = 0.0",
            "offset = 0.0\n[table]\nperiod = [1, 1]\nviews = [[0, 1, 2]]",
            "lens",
            "not both",
        ),
        (
            "[lens]\npitch = 3.75\nslant = 0.15625\noffset = 0.0",
            "[table]\nperiod = [2, 1]\nviews = [[0, 1, 2]]",
            "table.views",
            "needs 2 entries",
        ),
        (
            "[lens]\npitch = 3.75\nslant = 0.15625\noffset = 0.0",
            "[table]\nperiod = [1, 1]\nviews = [[0, 1, 8]]",
            "table.views[0]",
            "three views from 0 to 7",
        ),
    ];
    for (from, to, field, want) in cases {
        let text = good.replace(from, to);
        assert_ne!(text, good, "{from} is not in the file");
        let e = MultiViewDisplay::from_toml(&text, "d.toml").unwrap_err();
        assert_eq!(e.field(), Some(field), "{e}");
        assert!(e.to_string().contains(want), "{e}");
    }
    // A display is not a rig, and a rig not a display; each says so.
    let e = Rig::from_toml(&good, "d.toml").unwrap_err();
    assert!(
        e.to_string()
            .contains("multi-view display (views = 8), not a rig"),
        "{e}"
    );
    let rig = std::fs::read_to_string(common::config_dir().join("cologne_5wall.toml")).unwrap();
    let e = MultiViewDisplay::from_toml(&rig, "rig.toml").unwrap_err();
    assert!(e.to_string().contains("unknown field"), "{e}");
}

#[test]
fn a_lens_offset_is_taken_modulo_the_pitch() {
    // Added to the subpixels' positions as it is, an offset of 1e30 would
    // round every one of them to the same place, and so to one view.
    let far = ViewPattern::lens(3.75, 0.15625, 1e30);
    let ViewPattern::Lens { offset, .. } = far else {
        panic!("a lens")
    };
    assert!((0.0..3.75).contains(&offset), "{offset}");
    let near = ViewPattern::lens(3.75, 0.15625, 1e30f64.rem_euclid(3.75));
    assert_eq!(far, near);
    let display = MultiViewDisplay {
        pattern: far,
        ..shipped()
    };
    let size = UVec2::new(10, 8);
    let seen: std::collections::HashSet<u32> =
        display.view_table(size).into_iter().flatten().collect();
    assert_eq!(seen.len(), 8, "{seen:?}");
    assert_eq!(display.out_of_range(), None);
}
