//! `caveray inspect` as a user runs it.

use crate::common;

use common::caveray;

use anari_library_caveray::cave::Eye;
use glam::{DVec2, DVec3};
use serde_json::Value;

fn json(args: &[&str]) -> Value {
    let out = caveray(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("valid JSON")
}

fn v3(v: &Value) -> DVec3 {
    DVec3::from_slice(&floats(v, 3))
}

fn floats(v: &Value, n: usize) -> Vec<f64> {
    let a: Vec<f64> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(a.len(), n);
    a
}

const COLOGNE: &str = "cave_configs/cologne_5wall.toml";

#[test]
fn json_lists_every_wall_and_eye_with_all_strategies() {
    let doc = json(&["inspect", "--config", COLOGNE, "--rays", "5", "--json"]);
    let rig = common::rig("cologne_5wall");
    let head = rig.head_pose(None, None);
    let views = doc["views"].as_array().unwrap();
    assert_eq!(views.len(), 10);
    for v in views {
        let wall = rig.wall(v["wall"].as_str().unwrap()).unwrap();
        let eye = match v["eye"].as_str().unwrap() {
            "left" => Eye::Left,
            "right" => Eye::Right,
            other => panic!("eye {other}"),
        };
        let view = rig.view(wall, eye, &head).unwrap();
        assert_eq!(v3(&v["eye_position"]), view.eye_position);
        assert_eq!(
            floats(&v["matrix"]["view"], 16),
            view.projection.view.to_cols_array()
        );
        assert_eq!(
            floats(&v["matrix"]["proj"], 16),
            view.projection.proj.to_cols_array()
        );
        let pinhole = view.pinhole().unwrap();
        let p = &v["pinhole"];
        assert_eq!(v3(&p["position"]), view.eye_position);
        assert_eq!(v3(&p["direction"]), -wall.screen.normal());
        assert_eq!(v3(&p["up"]), wall.screen.y_axis());
        assert_eq!(p["fovy"].as_f64().unwrap(), pinhole.fovy());
        assert_eq!(p["aspect"].as_f64().unwrap(), pinhole.aspect());
        assert_eq!(
            floats(&p["image_region"], 4),
            pinhole.image_region().to_array()
        );
        let recovered = v3(&v["from_matrices"]["recovered_eye"]);
        assert!(
            (recovered - view.eye_position).length() < 1e-6,
            "{recovered}"
        );
        assert!(v["from_matrices"]["fovy"].as_f64().unwrap() > 0.0);
        let disagreement = v["max_ray_disagreement"].as_f64().unwrap();
        assert!((0.0..1e-6).contains(&disagreement), "{disagreement} mm");

        // Rays start at the eye and pass through their pixel on the wall.
        let rays = v["rays"].as_array().unwrap();
        assert_eq!(rays.len(), 5);
        for r in rays {
            let px = floats(&r["pixel"], 2);
            assert_eq!(v3(&r["origin"]), view.eye_position);
            let dir = v3(&r["direction"]);
            assert!((dir.length() - 1.0).abs() < 1e-12);
            let s = DVec2::new((px[0] + 0.5) / 1600.0, (px[1] + 0.5) / 1600.0);
            let target = wall.screen.point(s);
            let miss = (target - view.eye_position).normalize() - dir;
            assert!(miss.length() < 1e-12, "{} pixel {px:?}", wall.name);
        }
    }
    // Corner and centre pixels are among five spread rays.
    let px: Vec<Vec<f64>> = views[0]["rays"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| floats(&r["pixel"], 2))
        .collect();
    assert_eq!(px[0], [0.0, 0.0]);
    assert!(px.contains(&vec![1599.0, 0.0]));
}

#[test]
fn head_and_orientation_flags_move_the_eyes() {
    let doc = json(&[
        "inspect",
        "--config",
        COLOGNE,
        "--head",
        "-100,200,-50",
        "--head-ypr",
        "90,0,0",
        "--wall",
        "front",
        "--eye",
        "right",
        "--json",
    ]);
    let views = doc["views"].as_array().unwrap();
    assert_eq!(views.len(), 1);
    assert_eq!(views[0]["wall"], "front");
    assert_eq!(views[0]["eye"], "right");
    // Facing -x after a 90 degree yaw, the right eye is 30 mm towards +y.
    let eye = v3(&views[0]["eye_position"]);
    assert!(
        (eye - DVec3::new(-100.0, 230.0, -50.0)).length() < 1e-9,
        "{eye}"
    );
    assert_eq!(
        v3(&doc["head"]["position"]),
        DVec3::new(-100.0, 200.0, -50.0)
    );
}

#[test]
fn the_head_path_drives_the_pose_at_a_time() {
    // The Cologne rig's path reaches (-500, 300, 150), yaw 40, pitch -10 at 4 s.
    let doc = json(&[
        "inspect", "--config", COLOGNE, "--time", "4", "--wall", "front", "--json",
    ]);
    assert_eq!(
        v3(&doc["head"]["position"]),
        DVec3::new(-500.0, 300.0, 150.0)
    );
    let rig = common::rig("cologne_5wall");
    let pose = rig.head_at(4.0);
    let left = v3(&doc["views"][0]["eye_position"]);
    assert!((left - rig.eye_position(&pose, Eye::Left)).length() < 1e-9);
    // --head overrides the path's position but keeps its orientation.
    let doc = json(&[
        "inspect", "--config", COLOGNE, "--time", "4", "--head", "0,0,0", "--json",
    ]);
    assert_eq!(v3(&doc["head"]["position"]), DVec3::ZERO);
    let q = floats(&doc["head"]["orientation"], 4);
    assert_eq!(q, pose.orientation.to_array());
}

#[test]
fn an_eye_behind_a_wall_is_reported_for_that_view_only() {
    let doc = json(&[
        "inspect", "--config", COLOGNE, "--head", "0,1700,0", "--json",
    ]);
    let views = doc["views"].as_array().unwrap();
    assert_eq!(views.len(), 10);
    for v in views {
        if v["wall"] == "front" {
            let err = v["error"].as_str().unwrap();
            assert!(err.contains("on or behind the wall"), "{err}");
            assert!(v.get("matrix").is_none());
        } else {
            assert!(v.get("error").is_none(), "{v}");
            assert!(v["max_ray_disagreement"].as_f64().unwrap() < 1e-6);
        }
    }
}

#[test]
fn text_output_shows_all_three_strategies_per_view() {
    let out = caveray(&["inspect", "--config", COLOGNE, "--rays", "2"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    for wall in ["front", "left", "right", "ceiling", "floor"] {
        for eye in ["left", "right"] {
            assert!(
                text.contains(&format!("== {wall} / {eye} eye")),
                "{wall} {eye}"
            );
        }
    }
    assert_eq!(text.matches("strategy 1, matrix camera").count(), 10);
    assert_eq!(
        text.matches("strategy 2, pinhole + image region").count(),
        10
    );
    assert_eq!(text.matches("strategy 3, pinhole recovered").count(), 10);
    assert_eq!(text.matches("largest disagreement").count(), 10);
}

#[test]
fn bad_arguments_give_one_line_and_exit_code_2() {
    let cases: [(&[&str], &str); 11] = [
        (
            &["inspect"],
            "required arguments were not provided: --config <CONFIG>",
        ),
        (
            &["inspect", "--config", COLOGNE, "--eye", "mono"],
            "no wall",
        ),
        (&["inspect", "--config", COLOGNE, "--time", "nan"], "finite"),
        (&["inspect", "--config", COLOGNE, "--head", "1,2"], "three"),
        (
            &["inspect", "--config", COLOGNE, "--head", "1,x,2"],
            "three",
        ),
        (
            &["inspect", "--config", COLOGNE, "--head-ypr", "nan,0,0"],
            "finite",
        ),
        (
            &["inspect", "--config", COLOGNE, "--wall", "attic"],
            "no wall 'attic'",
        ),
        (&["inspect", "--config", COLOGNE, "--eye", "third"], "third"),
        (&["inspect", "--config", COLOGNE, "--rays", "-3"], "-3"),
        (
            &["inspect", "--config", "cave_configs/missing.toml"],
            "missing.toml: cannot read",
        ),
        (&["frobnicate"], "frobnicate"),
    ];
    for (args, needle) in cases {
        let out = caveray(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("caveray: "), "{err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(out.stdout.is_empty());
    }
}

#[test]
fn a_malformed_rig_is_reported_with_file_line_and_field() {
    let dir = std::env::temp_dir().join(format!("caveray-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.toml");
    let text = std::fs::read_to_string(common::config_dir().join("powerwall.toml")).unwrap();
    std::fs::write(
        &path,
        text.replace("resolution = [3840, 2160]", "resolution = [3840, 0]"),
    )
    .unwrap();
    let line = 1 + text
        .lines()
        .position(|l| l.contains("resolution = [3840, 2160]"))
        .unwrap();
    let out = caveray(&["inspect", "--config", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(
        err.contains(&format!("bad.toml:{line}:")) && err.contains("walls[0].resolution"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
