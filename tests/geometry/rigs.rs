//! The TOML rig format: the shipped rigs, head conventions, and errors that
//! name the file, the line and the field.

use crate::common;

use anari_library_caveray::cave::{ConfigError, Eye, Rig, Units};
use glam::{DVec3, UVec2};

#[test]
fn cologne_matches_its_specification() {
    let rig = common::rig("cologne_5wall");
    assert_eq!(rig.units, Units::Millimetres);
    assert_eq!(rig.viewer.ipd, 60.0);
    let names: Vec<&str> = rig.walls.iter().map(|w| w.name.as_str()).collect();
    assert_eq!(names, ["front", "left", "right", "ceiling", "floor"]);
    let corners = [
        (
            [-1500., 1500., -1500.],
            [1500., 1500., -1500.],
            [1500., 1500., 1500.],
        ),
        (
            [-1500., -1500., -1500.],
            [-1500., 1500., -1500.],
            [-1500., 1500., 1500.],
        ),
        (
            [1500., 1500., -1500.],
            [1500., -1500., -1500.],
            [1500., -1500., 1500.],
        ),
        (
            [-1500., 1500., 1500.],
            [1500., 1500., 1500.],
            [1500., -1500., 1500.],
        ),
        (
            [-1500., -1500., -1500.],
            [1500., -1500., -1500.],
            [1500., 1500., -1500.],
        ),
    ];
    for (wall, (ll, lr, ur)) in rig.walls.iter().zip(corners) {
        assert_eq!(wall.screen.ll(), DVec3::from(ll));
        assert_eq!(wall.screen.lr(), DVec3::from(lr));
        assert_eq!(wall.screen.ur(), DVec3::from(ur));
        assert_eq!(wall.resolution, UVec2::new(1600, 1600));
        assert_eq!(wall.eyes, [Eye::Left, Eye::Right]);
        // Every wall faces the centre of the cube.
        assert!(
            wall.screen.normal().dot(wall.screen.centre()) < 0.0,
            "{}",
            wall.name
        );
    }
}

#[test]
fn other_rigs_have_their_stated_sizes() {
    let four = common::rig("cave_4wall_3m");
    let names: Vec<&str> = four.walls.iter().map(|w| w.name.as_str()).collect();
    assert_eq!(names, ["front", "left", "right", "floor"]);
    for w in &four.walls {
        assert_eq!((w.screen.width(), w.screen.height()), (3.0, 3.0));
    }
    let pw = common::rig("powerwall");
    assert_eq!(pw.walls.len(), 1);
    assert_eq!(
        (pw.walls[0].screen.width(), pw.walls[0].screen.height()),
        (4.0, 2.25)
    );
    assert_eq!(pw.walls[0].resolution, UVec2::new(3840, 2160));
    let ft = common::rig("fishtank_desktop");
    let s = &ft.walls[0].screen;
    assert!((s.width() - 0.60).abs() < 1e-12 && (s.height() - 0.34).abs() < 1e-12);
    assert_eq!(ft.walls[0].resolution, UVec2::new(2560, 1440));
    let d = s.extents(ft.viewer.head.position).unwrap().distance;
    assert!((d - 0.6).abs() < 1e-12, "head is {d} m in front");
}

#[test]
fn eyes_sit_at_half_the_ipd_along_the_heads_right_axis() {
    let rig = common::rig("cologne_5wall");
    let head = rig.head_pose(None, None);
    assert_eq!(
        rig.eye_position(&head, Eye::Left),
        DVec3::new(-30.0, 0.0, 200.0)
    );
    assert_eq!(
        rig.eye_position(&head, Eye::Right),
        DVec3::new(30.0, 0.0, 200.0)
    );
    assert_eq!(
        rig.eye_position(&head, Eye::Mono),
        DVec3::new(0.0, 0.0, 200.0)
    );

    // Positive yaw turns left: facing -x, the right eye is towards +y.
    let turned = rig.head_pose(None, Some(DVec3::new(90.0, 0.0, 0.0)));
    let forward = turned.orientation * rig.viewer.frame.forward;
    assert!((forward - DVec3::NEG_X).length() < 1e-12, "{forward}");
    let right = rig.eye_position(&turned, Eye::Right);
    assert!(
        (right - DVec3::new(0.0, 30.0, 200.0)).length() < 1e-12,
        "{right}"
    );
    // Positive pitch looks up; positive roll drops the right eye.
    let up = rig.head_pose(None, Some(DVec3::new(0.0, 30.0, 0.0)));
    assert!((up.orientation * rig.viewer.frame.forward).z > 0.49);
    let rolled = rig.head_pose(None, Some(DVec3::new(0.0, 0.0, 90.0)));
    let r = rig.eye_position(&rolled, Eye::Right);
    assert!((r - DVec3::new(0.0, 0.0, 170.0)).length() < 1e-12, "{r}");
}

#[test]
fn eye_offset_is_applied_in_the_head_frame() {
    let rig = common::rig("cave_4wall_3m");
    // Offset (right 0, up -0.02, forward -0.05); forward is -z.
    let head = rig.head_pose(None, None);
    let mono = rig.eye_position(&head, Eye::Mono);
    assert!(
        (mono - DVec3::new(0.0, 1.68, 0.05)).length() < 1e-12,
        "{mono}"
    );
    let turned = rig.head_pose(None, Some(DVec3::new(-90.0, 0.0, 0.0)));
    let mono = rig.eye_position(&turned, Eye::Mono);
    assert!(
        (mono - DVec3::new(-0.05, 1.68, 0.0)).length() < 1e-12,
        "{mono}"
    );
}

#[test]
fn the_head_path_interpolates_and_holds_at_its_ends() {
    let rig = common::rig("cologne_5wall");
    let keys = &rig.viewer.path;
    assert_eq!(keys.len(), 3);
    assert_eq!(rig.head_at(-1.0), keys[0].pose);
    assert_eq!(rig.head_at(100.0), keys[2].pose);
    let mid = rig.head_at(2.0);
    assert!((mid.position - DVec3::new(-250.0, 150.0, 175.0)).length() < 1e-9);
    let want = keys[0]
        .pose
        .orientation
        .slerp(keys[1].pose.orientation, 0.5);
    assert!(mid.orientation.angle_between(want) < 1e-7);
    // Halfway in angle between the two keys, along the shortest arc.
    let (a, b) = (keys[0].pose.orientation, keys[1].pose.orientation);
    let half = a.angle_between(b) / 2.0;
    assert!((mid.orientation.angle_between(a) - half).abs() < 1e-7);
    assert!((mid.orientation.angle_between(b) - half).abs() < 1e-7);
}

const GOOD: &str = r#"name = "test rig"
units = "m"

[viewer]
ipd = 0.06
head = [0, 1.7, 0]

[[walls]]
name = "front"
ll = [-1, 0, -1]
lr = [1, 0, -1]
ur = [1, 2, -1]
resolution = [64, 64]

[[walls]]
name = "floor"
ll = [-1, 0, 1]
lr = [1, 0, 1]
ur = [1, 0, -1]
ul = [-1, 0, -1]
resolution = [64, 64]
eyes = ["left"]
"#;

fn parse(text: &str) -> Result<Rig, ConfigError> {
    Rig::from_toml(text, "rigs/test.toml")
}

/// Parses `GOOD` with `from` replaced by `to`, expecting an error at
/// `line` about `field` whose message contains `needle`.
fn expect_error(from: &str, to: &str, line: usize, field: &str, needle: &str) {
    assert!(GOOD.contains(from), "test text lacks {from:?}");
    let err = parse(&GOOD.replacen(from, to, 1)).expect_err("must fail");
    let text = err.to_string();
    assert_eq!(err.line(), Some(line), "{text}");
    assert_eq!(err.field(), Some(field), "{text}");
    assert!(
        text.starts_with(&format!("rigs/test.toml:{line}:")),
        "{text}"
    );
    assert!(text.contains(needle), "{text} lacks {needle:?}");
    assert_eq!(text.lines().count(), 1, "one-line message: {text}");
}

#[test]
fn the_reference_rig_parses() {
    let rig = parse(GOOD).unwrap();
    assert_eq!(rig.walls[1].eyes, [Eye::Left]);
    assert_eq!(rig.near, 0.01);
    assert_eq!(rig.far, 100.0);
    assert_eq!(rig.viewer.frame.forward, DVec3::NEG_Z);
}

#[test]
fn millimetre_rigs_get_defaults_in_millimetres() {
    let rig = parse(
        &GOOD
            .replace("units = \"m\"", "units = \"mm\"")
            .replace("ipd = 0.06\n", ""),
    )
    .unwrap();
    assert_eq!((rig.near, rig.far, rig.viewer.ipd), (10.0, 100_000.0, 63.0));
}

#[test]
fn missing_fields_are_named() {
    expect_error(
        "ll = [-1, 0, -1]\nlr = [1, 0, -1]",
        "lr = [1, 0, -1]",
        8,
        "walls[0].ll",
        "missing field `ll`",
    );
    expect_error(
        "head = [0, 1.7, 0]\n",
        "",
        4,
        "viewer.head",
        "missing field `head`",
    );
    expect_error(
        "resolution = [64, 64]\neyes",
        "eyes",
        15,
        "walls[1].resolution",
        "missing field `resolution`",
    );
}

#[test]
fn wrong_types_are_named() {
    expect_error(
        "ipd = 0.06",
        "ipd = \"sixty\"",
        5,
        "viewer.ipd",
        "invalid type",
    );
    expect_error(
        "ur = [1, 2, -1]",
        "ur = [1, \"2\", -1]",
        12,
        "walls[0].ur",
        "invalid type",
    );
    expect_error(
        "ur = [1, 2, -1]",
        "ur = [1, 2]",
        12,
        "walls[0].ur",
        "expected 3 numbers, got 2",
    );
    expect_error(
        "resolution = [64, 64]",
        "resolution = [64, -64]",
        13,
        "walls[0].resolution",
        "",
    );
    expect_error(
        "units = \"m\"",
        "units = \"inch\"",
        2,
        "units",
        "unknown variant `inch`",
    );
    expect_error(
        "eyes = [\"left\"]",
        "eyes = [\"middle\"]",
        22,
        "walls[1].eyes",
        "unknown variant `middle`",
    );
    expect_error(
        "ipd = 0.06",
        "ipd = 0.06\ncolor = 1",
        6,
        "viewer.color",
        "unknown field `color`",
    );
}

#[test]
fn invalid_walls_are_named() {
    // Distances computed from corners are shown without float tails
    // (-0.9 - -1 is 0.09999999999999998).
    expect_error(
        "ul = [-1, 0, -1]",
        "ul = [-0.9, 0, -1]",
        20,
        "walls[1].ul",
        "not a planar rectangle: UL is 0.1 away from LL + (UR - LR)",
    );
    expect_error(
        "ur = [1, 2, -1]",
        "ur = [1.5, 2, -1]",
        12,
        "walls[0].ur",
        "not a rectangle: edges LL-LR and LR-UR meet at 75.9638 degrees, not 90",
    );
    expect_error(
        "lr = [1, 0, -1]",
        "lr = [-1, 0, -1]",
        11,
        "walls[0].lr",
        "zero area: width 0, height 2.82843",
    );
    expect_error(
        "ur = [1, 2, -1]",
        "ur = [1, 0, -1]",
        12,
        "walls[0].ur",
        "zero area",
    );
    expect_error(
        "resolution = [64, 64]",
        "resolution = [0, 64]",
        13,
        "walls[0].resolution",
        "at least 1 x 1",
    );
    expect_error(
        "ll = [-1, 0, -1]",
        "ll = [nan, 0, -1]",
        10,
        "walls[0].ll",
        "finite",
    );
    expect_error(
        "name = \"floor\"",
        "name = \"Front\"",
        16,
        "walls[1].name",
        "duplicate wall name",
    );
    expect_error(
        "name = \"floor\"",
        "name = \"  \"",
        16,
        "walls[1].name",
        "must not be empty",
    );
    expect_error(
        "eyes = [\"left\"]",
        "eyes = [\"left\", \"left\"]",
        22,
        "walls[1].eyes",
        "at most once",
    );
    expect_error(
        "eyes = [\"left\"]",
        "eyes = []",
        22,
        "walls[1].eyes",
        "at most once",
    );
}

#[test]
fn invalid_viewers_and_clip_planes_are_named() {
    expect_error("ipd = 0.06", "ipd = -0.06", 5, "viewer.ipd", ">= 0");
    expect_error(
        "ipd = 0.06",
        "ipd = 0.06\nforward = [0, 1, 0]\nup = [0, 2, 0]",
        7,
        "viewer.up",
        "not parallel",
    );
    expect_error(
        "units = \"m\"",
        "units = \"m\"\nnear = 2\nfar = 1",
        4,
        "far",
        "greater than near",
    );
    expect_error("units = \"m\"", "units = \"m\"\nnear = 0", 3, "near", "> 0");
    expect_error(
        "ipd = 0.06",
        "ipd = 0.06\ntracked_space = { min = [0, 0, 0], max = [1, -1, 1] }",
        6,
        "viewer.tracked_space",
        "min must be below max",
    );
    expect_error(
        "head = [0, 1.7, 0]\n",
        "head = [0, 1.7, 0]\n[[viewer.path]]\nt = 1\nhead = [0, 1, 0]\n[[viewer.path]]\nt = 1\nhead = [0, 1, 0]\n",
        11,
        "viewer.path[1].t",
        "increasing",
    );
}

#[test]
fn an_empty_wall_list_and_syntax_errors_are_reported() {
    let no_walls =
        GOOD.split("[[walls]]")
            .next()
            .unwrap()
            .replacen("[viewer]", "walls = []\n\n[viewer]", 1);
    let err = parse(&no_walls).unwrap_err();
    assert_eq!(err.field(), Some("walls"), "{err}");
    assert!(err.to_string().contains("at least one wall"), "{err}");
    let err = parse("units = \"m\"\n[viewer\n").unwrap_err();
    assert_eq!(err.line(), Some(2), "{err}");
}

#[test]
fn an_unreadable_file_names_the_file() {
    let err = Rig::load(std::path::Path::new("/nonexistent/rig.toml")).unwrap_err();
    assert!(matches!(err, ConfigError::Io { .. }));
    assert!(
        err.to_string()
            .starts_with("/nonexistent/rig.toml: cannot read rig file"),
        "{err}"
    );
}

#[test]
fn extra_components_are_errors_naming_the_field() {
    expect_error(
        "ll = [-1, 0, -1]",
        "ll = [-1, 0, -1, 1]",
        10,
        "walls[0].ll",
        "expected 3 numbers, got 4",
    );
    expect_error(
        "resolution = [64, 64]",
        "resolution = [10, 10, 10]",
        13,
        "walls[0].resolution",
        "expected 2 numbers (width, height), got 3",
    );
    expect_error(
        "head = [0, 1.7, 0]",
        "head = [0, 1.7, 0, 0]",
        6,
        "viewer.head",
        "expected 3 numbers, got 4",
    );
}

#[test]
fn wall_names_cannot_leave_the_output_folder_or_take_the_contact_sheets() {
    for bad in [
        "../escape",
        "/etc/passwd",
        "a b",
        "wall.png",
        "x\\y",
        "caf\u{e9}",
    ] {
        let line = format!("name = \"{}\"", bad.replace('\\', "\\\\"));
        expect_error(
            "name = \"front\"",
            &line,
            9,
            "walls[0].name",
            "must be 1 to 64 letters",
        );
    }
    let long = format!("name = \"{}\"", "w".repeat(65));
    expect_error(
        "name = \"front\"",
        &long,
        9,
        "walls[0].name",
        "must be 1 to 64",
    );
    expect_error(
        "name = \"front\"",
        "name = \"Cave\"",
        9,
        "walls[0].name",
        "taken by the contact sheets",
    );
    expect_error(
        "name = \"floor\"",
        "name = \"FRONT\"",
        16,
        "walls[1].name",
        "duplicate wall name",
    );
}

#[test]
fn characters_of_several_bytes_near_an_equals_sign_are_located() {
    // Slicing the text inside the character would panic.
    let text = GOOD.replacen(
        "head = [0, 1.7, 0]",
        "head = [0, 1.7, 0]\neye_offset = { «x» = 1 }",
        1,
    );
    let err = parse(&text).unwrap_err();
    assert_eq!(err.line(), Some(7), "{err}");
    // A key of such characters is not TOML: a syntax error, no field.
    assert!(matches!(err, ConfigError::Syntax { .. }), "{err}");
    assert_eq!(
        err.to_string(),
        "rigs/test.toml:7:16: invalid unquoted key, expected letters, numbers, `-`, `_`"
    );
    let text = GOOD.replacen("ipd = 0.06", "ipd = \"é\" # ü = ß", 1);
    let err = parse(&text).unwrap_err();
    assert_eq!(err.field(), Some("viewer.ipd"), "{err}");
}

#[test]
fn a_missing_top_level_field_is_named_not_the_comment_above_it() {
    let text = format!(
        "# a rig: width = 3 m\n{}",
        GOOD.replacen("units = \"m\"\n", "", 1)
    );
    let err = parse(&text).unwrap_err();
    assert_eq!(err.field(), Some("units"), "{err}");
    assert!(err.to_string().contains("missing field `units`"), "{err}");
}

#[test]
fn devices_and_directories_are_not_read_as_rigs() {
    for special in ["/dev/zero", "/tmp"] {
        let err = Rig::load(std::path::Path::new(special)).unwrap_err();
        assert!(err.to_string().contains("not a regular file"), "{err}");
    }
}

#[test]
fn head_paths_load_in_the_rigs_units_and_bad_ones_name_the_line() {
    let rig = common::rig("cologne_5wall");
    let walk = rig
        .load_head_path(&common::config_dir().join("head_paths/cologne_walk.toml"))
        .unwrap();
    assert_eq!(walk.len(), 11);
    assert_eq!(walk[0].pose.position, DVec3::new(0.0, -300.0, 200.0));
    // Facing the left wall at t = 4: yaw 90 turns forward (+y) to -x.
    let forward = walk[2].pose.orientation * rig.viewer.frame.forward;
    assert!((forward - DVec3::NEG_X).length() < 1e-12, "{forward}");
    // A path in metres lands in the millimetre rig scaled.
    let metres = rig
        .head_path_from_toml(
            "units = \"m\"\n[[pose]]\nt = 0\nhead = [0.1, -0.3, 0.2]\n",
            "m.toml",
        )
        .unwrap();
    assert!((metres[0].pose.position - DVec3::new(100.0, -300.0, 200.0)).length() < 1e-9);
    for (text, field, line, needle) in [
        (
            "units = \"mm\"\n[[pose]]\nt = 0\nhead = [0, 0]\n",
            "pose[0].head",
            4,
            "expected 3 numbers",
        ),
        (
            "units = \"mm\"\n[[pose]]\nt = 0\nhead = [0, 0, 0]\nspeed = 2\n",
            "pose[0].speed",
            5,
            "unknown field `speed`",
        ),
        ("units = \"furlong\"\n", "units", 1, "unknown variant"),
    ] {
        let e = rig.head_path_from_toml(text, "p.toml").unwrap_err();
        assert_eq!(e.field(), Some(field), "{e}");
        assert_eq!(e.line(), Some(line), "{e}");
        assert!(e.to_string().contains(needle), "{e}");
    }
}

/// `GOOD` with a `[scene]` table of `lines` before its first wall, and the
/// line number of the table's first entry.
fn with_scene(lines: &str) -> (String, usize) {
    let at = GOOD.find("[[walls]]").unwrap();
    let line = GOOD[..at].lines().count() + 2;
    (
        format!("{}[scene]\n{lines}\n\n{}", &GOOD[..at], &GOOD[at..]),
        line,
    )
}

#[test]
fn the_scene_says_which_volume_axes_are_up_and_in_front() {
    use anari_library_caveray::geometry::VolumeAxis;
    let (text, _) = with_scene("volume_up = \"-z\"\nvolume_front = \"+X\"");
    let rig = parse(&text).unwrap();
    assert_eq!(rig.scene.up, Some(VolumeAxis::NegZ));
    assert_eq!(rig.scene.front, Some(VolumeAxis::PosX));
    assert_eq!(parse(GOOD).unwrap().scene.up, None);

    let (text, line) = with_scene("volume_up = \"upwards\"");
    let err = parse(&text).unwrap_err();
    assert_eq!(
        (err.line(), err.field()),
        (Some(line), Some("scene.volume_up"))
    );
    assert!(err.to_string().contains("+x, -x, +y, -y, +z, -z"), "{err}");

    let (text, line) = with_scene("volume_up = \"z\"\nvolume_front = \"-z\"");
    let err = parse(&text).unwrap_err();
    assert_eq!(
        (err.line(), err.field()),
        (Some(line + 1), Some("scene.volume_front"))
    );
    assert!(err.to_string().contains("must be different axes"), "{err}");
}

/// Parses `GOOD` with `from` replaced by `to`, expecting a syntax error:
/// exactly `message` at `line:column`, naming no field.
fn expect_syntax_error(from: &str, to: &str, line: usize, column: usize, message: &str) {
    assert!(GOOD.contains(from), "test text lacks {from:?}");
    let err = parse(&GOOD.replacen(from, to, 1)).expect_err("must fail");
    assert!(matches!(err, ConfigError::Syntax { .. }), "{err}");
    assert_eq!(err.field(), None, "{err}");
    assert_eq!(
        (err.line(), err.column()),
        (Some(line), Some(column)),
        "{err}"
    );
    assert_eq!(
        err.to_string(),
        format!("rigs/test.toml:{line}:{column}: {message}")
    );
}

#[test]
fn syntax_errors_point_at_their_cause_and_name_no_field() {
    // toml reports these at the next line, as a missing comma in walls[0].
    expect_syntax_error(
        "ll = [-1, 0, -1]",
        "ll = [-1, 0, -1",
        10,
        6,
        "unclosed '[': the array opened here is not closed before line 11 (expected `]`)",
    );
    expect_syntax_error(
        "name = \"front\"",
        "name = \"front",
        9,
        8,
        "unclosed string: the \" here is not closed on its line",
    );
    expect_syntax_error(
        "ipd = 0.06\n",
        "ipd = 0.06\nipd = 0.07\n",
        6,
        1,
        "duplicate key `ipd` (first set on line 5)",
    );
    expect_syntax_error(
        "ipd = 0.06",
        "ipd 0.06",
        5,
        5,
        "`ipd` has no value: expected `=` and a value after it",
    );
    expect_syntax_error(
        "ipd = 0.06",
        "ipd = 0.0.6",
        5,
        7,
        "`0.0.6` is not a number (invalid float)",
    );
    expect_syntax_error(
        "ipd = 0.06",
        "ipd = 0,06",
        5,
        8,
        "unexpected `,06`: expected the end of the line or a `#` comment (a decimal point is `.`)",
    );
    expect_syntax_error("ipd = 0.06", "ipd =", 5, 6, "missing value after `=`");
    expect_syntax_error(
        "[viewer]",
        "[viewer",
        4,
        8,
        "unclosed table header, expected `]`",
    );
    expect_syntax_error(
        "[[walls]]\nname = \"floor\"",
        "[[walls]\nname = \"floor\"",
        15,
        9,
        "unclosed table header, expected `]]`",
    );
    // Schema errors still name their field.
    expect_error("ipd = 0.06", "ipd = \"x\"", 5, "viewer.ipd", "invalid type");
}

#[test]
fn head_paths_and_displays_report_syntax_errors_alike() {
    let rig = parse(GOOD).unwrap();
    let err = rig
        .head_path_from_toml("units = \"m\"\n[[pose]]\nt = 0\nhead = [0, 1\n", "p.toml")
        .unwrap_err();
    assert_eq!(
        err.to_string(),
        "p.toml:4:8: unclosed '[': the array opened here is never closed (expected `]`)"
    );
    assert_eq!(err.field(), None);
    let err = anari_library_caveray::cave::MultiViewDisplay::from_toml(
        "units = \"m\"\nviews = 8\nviews = 9\n",
        "d.toml",
    )
    .unwrap_err();
    assert_eq!(
        err.to_string(),
        "d.toml:3:1: duplicate key `views` (first set on line 2)"
    );
}
