//! `caveray render` end to end: files, timings and one-line errors.

use crate::common;

use common::caveray;

use std::path::{Path, PathBuf};

use anari_library_caveray::render::GpuRenderer;
use serde_json::Value;

fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caveray-render-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn render(out: &Path, extra: &[&str]) -> Value {
    let mut args = vec![
        "render",
        "--config",
        "cave_configs/cologne_5wall.toml",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let result = caveray(&args);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let text = std::fs::read_to_string(out.join("timings.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn png(path: &Path) -> image::RgbaImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8()
}

/// Mean absolute difference of two 8-bit images, in levels.
fn mean_difference(a: &image::RgbaImage, b: &image::RgbaImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let sum: u64 = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(x, y)| u64::from(x.abs_diff(*y)))
        .sum();
    sum as f64 / a.as_raw().len() as f64
}

#[test]
fn every_wall_and_eye_of_the_cologne_cave_is_rendered() {
    let out = scratch("cologne");
    let report = render(&out, &["--scale", "0.02", "--volume", "phantom:48"]);
    let views = report["views"].as_array().unwrap();
    assert_eq!(views.len(), 10);
    for v in views {
        let file = v["file"].as_str().unwrap();
        assert_eq!(
            file,
            format!(
                "{}_{}.png",
                v["wall"].as_str().unwrap(),
                v["eye"].as_str().unwrap()
            )
        );
        let image = png(&out.join(file));
        assert_eq!(image.dimensions(), (32, 32));
        assert!(v["ms"].as_f64().unwrap() > 0.0);
        assert!(v["rays_per_s"].as_f64().unwrap() > 0.0);
        // A wall that sees only air takes no sample: its bricks are clear.
        let samples = v["samples_per_s"].as_f64().unwrap();
        assert!(samples >= 0.0);
        if file == "front_left.png" {
            assert!(samples > 0.0, "the front wall sampled nothing");
        }
    }
    // The volume floats in front of the viewer: the front wall shows it.
    let front = png(&out.join("front_left.png"));
    let lit = front.pixels().filter(|p| p.0[0] > 40).count();
    assert!(lit > 50, "front wall shows only {lit} lit pixels");
    // Left and right eyes differ (stereo), but only a little.
    let right = png(&out.join("front_right.png"));
    let d = mean_difference(&front, &right);
    assert!(d > 0.0 && d < 20.0, "eyes differ by {d} levels");
    for eye in ["left", "right"] {
        let sheet = png(&out.join(format!("cave_{eye}.png")));
        // Unfolded cube of 5 walls: 3 x 3 cells of 32 px plus 4 px gaps.
        assert_eq!(sheet.dimensions(), (3 * 32 + 4 * 4, 3 * 32 + 4 * 4));
    }
    // `auto` takes a hardware GPU, and the CPU over a software adapter.
    let adapter = GpuRenderer::probe().unwrap();
    if adapter.device_type == wgpu::DeviceType::Cpu {
        assert_eq!(report["renderer"]["backend"], "cpu");
    } else {
        assert_eq!(report["renderer"]["backend"], "gpu");
        assert_eq!(report["renderer"]["api"], "Vulkan");
    }
    assert_eq!(report["strategy"], "offaxis");
    assert_eq!(report["volume"]["dims"], serde_json::json!([48, 48, 48]));
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn strategies_and_backends_give_the_same_pictures() {
    let base = scratch("strategies");
    let common = [
        "--scale",
        "0.04",
        "--volume",
        "phantom:32",
        "--shading",
        "ao",
    ];
    let run = |name: &str, extra: &[&str]| {
        let out = base.join(name);
        let mut args = common.to_vec();
        args.extend_from_slice(extra);
        let report = render(&out, &args);
        (out, report)
    };
    let (reference, _) = run("offaxis", &[]);
    for (name, extra) in [
        ("matrix", vec!["--strategy", "matrix"]),
        ("pinhole", vec!["--strategy", "pinhole"]),
        ("from-matrices", vec!["--strategy", "from-matrices"]),
        ("cpu", vec!["--backend", "cpu"]),
    ] {
        let (out, report) = run(name, &extra);
        if name == "cpu" {
            assert_eq!(report["renderer"]["backend"], "cpu");
        }
        for file in [
            "front_left.png",
            "left_right.png",
            "floor_left.png",
            "cave_right.png",
        ] {
            let d = mean_difference(&png(&reference.join(file)), &png(&out.join(file)));
            assert!(d < 0.5, "{name} {file}: differs by {d} levels on average");
        }
    }
    std::fs::remove_dir_all(&base).unwrap();
}

#[test]
fn a_wall_the_eye_is_behind_is_reported_and_the_rest_rendered() {
    let out = scratch("behind");
    // Outside the CAVE, beyond the left wall.
    let report = render(
        &out,
        &[
            "--scale",
            "0.02",
            "--volume",
            "phantom:16",
            "--head=-2000,0,200",
        ],
    );
    let views = report["views"].as_array().unwrap();
    let errors: Vec<&Value> = views.iter().filter(|v| v.get("error").is_some()).collect();
    assert_eq!(errors.len(), 2, "{views:?}");
    for e in errors {
        assert_eq!(e["wall"], "left");
        assert!(e["error"].as_str().unwrap().contains("behind"), "{e}");
    }
    assert!(out.join("front_left.png").is_file());
    assert!(!out.join("left_left.png").exists());
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn bad_arguments_are_one_line_errors() {
    let out = scratch("errors");
    let raw = out.join("short.raw");
    std::fs::write(&raw, [0u8; 100]).unwrap();
    let o = out.to_str().unwrap();
    let r = raw.to_str().unwrap();
    let config = "cave_configs/cologne_5wall.toml";
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--scale", "0"], "--scale must be in (0, 4], got 0"),
        (vec!["--shading", "phong"], "unknown shading mode \"phong\""),
        (
            vec!["--volume", r],
            "is a raw file: give its size with --dims",
        ),
        (
            vec!["--volume", r, "--dims", "8,8,8"],
            "has 100 bytes, but 8x8x8 uint8 needs 512 bytes",
        ),
        (
            vec!["--volume", "phantom:1"],
            "must be a whole number in 2..=1024",
        ),
        (
            vec!["--tf", "rainbow"],
            "unknown transfer function preset 'rainbow'",
        ),
        (vec!["--strategy", "fisheye"], "invalid value 'fisheye'"),
        (
            vec!["--stereo", "reprojection", "--layers", "0"],
            "--layers must be at least 1",
        ),
        (
            vec!["--layer-format", "rgb8"],
            "[possible values: rgba16f, rgba32f]",
        ),
        (vec!["--stereo", "anaglyph"], "invalid value 'anaglyph'"),
        // Inputs that would hang, abort or read forever without the budgets.
        (
            vec!["--step-factor", "1e-30"],
            "step factor must be in [0.015625, 64], got 1e-30",
        ),
        (
            vec!["--head", "1e300,0,0"],
            "expected three finite numbers X,Y,Z, got '1e300,0,0'",
        ),
        (
            vec!["--step-factor", "0"],
            "step factor must be in [0.015625, 64], got 0.0",
        ),
        (
            vec!["--volume", "/dev/zero", "--dims", "8,8,8"],
            "not a regular file",
        ),
        (
            vec!["--volume", r, "--dims", "4294967295,4294967295,4294967295"],
            "more than caveray loads (4294967296 voxels at most)",
        ),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["render", "--config", config, "--out", o];
        args.extend_from_slice(&extra);
        let result = caveray(&args);
        let err = String::from_utf8(result.stderr).unwrap();
        assert_eq!(result.status.code(), Some(2), "{extra:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{extra:?}: {err}");
        assert!(
            err.starts_with("caveray: ") && err.contains(needle),
            "{extra:?}: {err}"
        );
    }
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn reprojection_renders_every_wall_and_says_why_when_it_cannot() {
    let common = [
        "--scale",
        "0.05",
        "--volume",
        "phantom:48",
        "--step-factor",
        "0.5",
        "--backend",
        "gpu",
    ];
    let two = scratch("two-pass");
    render(&two, &common);
    let one = scratch("reprojection");
    let mut args = common.to_vec();
    args.extend_from_slice(&["--stereo", "reprojection"]);
    let report = render(&one, &args);
    assert_eq!(report["stereo"], "reprojection");
    let views = report["views"].as_array().unwrap();
    let view = |wall: &str, eye: &str| {
        views
            .iter()
            .find(|v| v["wall"] == wall && v["eye"] == eye)
            .unwrap_or_else(|| panic!("{wall} {eye} missing"))
    };
    for eye in ["left", "right"] {
        // Facing the front wall with a level head: one pass.
        let front = view("front", eye);
        assert!(
            front["path"]
                .as_str()
                .unwrap()
                .starts_with("reprojection ("),
            "{front}"
        );
        assert!(front["layers"].as_u64().unwrap() >= 2);
        assert_eq!(front["families"], 1, "{front}");
        // The side walls' baseline points into them: lines radiate from
        // the epipole, both families, still one pass.
        for wall in ["left", "right"] {
            let side = view(wall, eye);
            assert!(
                side["path"].as_str().unwrap().starts_with("reprojection ("),
                "{side}"
            );
            assert_eq!(side["families"], 2, "{side}");
        }
    }
    // The left eye is ray cast either way; the right one is re-projected.
    let (a, b) = (
        png(&two.join("front_left.png")),
        png(&one.join("front_left.png")),
    );
    assert_eq!(mean_difference(&a, &b), 0.0);
    let (a, b) = (
        png(&two.join("front_right.png")),
        png(&one.join("front_right.png")),
    );
    let d = mean_difference(&a, &b);
    assert!(d < 1.5, "mean difference {d} levels");
    assert!(one.join("cave_right.png").is_file());

    // Too few layers for the front wall: it falls back and says so.
    let few = scratch("few-layers");
    let mut args = common.to_vec();
    args.extend_from_slice(&["--stereo", "reprojection", "--layers", "1"]);
    let report = render(&few, &args);
    let front = report["views"]
        .as_array()
        .unwrap()
        .iter()
        .find(|v| v["wall"] == "front" && v["eye"] == "right")
        .unwrap()
        .clone();
    assert_eq!(front["path"], "two-pass");
    assert!(
        front["fallback"]
            .as_str()
            .unwrap()
            .contains("1 layers are too few"),
        "{front}"
    );
    for dir in [two, one, few] {
        std::fs::remove_dir_all(dir).unwrap();
    }
}

/// Rigs that would write outside the output folder, over the contact
/// sheets, or frames beyond memory: refused before anything is written.
#[test]
fn rigs_that_would_escape_or_overflow_are_refused() {
    let out = scratch("rig_errors");
    let good = std::fs::read_to_string("cave_configs/powerwall.toml").unwrap();
    let first_name = good
        .lines()
        .skip_while(|l| !l.starts_with("[[walls]]"))
        .find(|l| l.trim_start().starts_with("name"))
        .unwrap()
        .to_string();
    let resolution = good
        .lines()
        .find(|l| l.trim_start().starts_with("resolution"))
        .unwrap()
        .to_string();
    let cases = [
        (
            good.replacen(&first_name, "name = \"../escape\"", 1),
            "must be 1 to 64 letters, digits",
        ),
        (
            good.replacen(&first_name, "name = \"/tmp/abs\"", 1),
            "must be 1 to 64 letters, digits",
        ),
        (
            good.replacen(&first_name, "name = \"cave\"", 1),
            "taken by the contact sheets",
        ),
        (
            good.replacen(&resolution, "resolution = [100000, 100000]", 1),
            "is 10000000000 pixels; caveray renders up to 268435456",
        ),
        // Numbers beyond f32, which every view would fail on at render.
        (
            good.replacen("ipd = 0.063", "ipd = 0.063\neye_offset = [0, 1e308, 0]", 1),
            "viewer.eye_offset: 1e308 is beyond single precision",
        ),
        (
            good.replacen("ipd = 0.063", "ipd = 1e39", 1),
            "viewer.ipd: 1e39 is beyond single precision",
        ),
        (
            good.replacen("ipd = 0.063", "ipd = 0.063\neye_offset = [3e38, 0, 0]", 1)
                .replacen("head = [0, 1.7, 3.0]", "head = [3e38, 1.7, 3.0]", 1),
            "viewer: the left eye lies at [",
        ),
    ];
    for (i, (text, needle)) in cases.iter().enumerate() {
        let rig = out.join(format!("rig{i}.toml"));
        std::fs::write(&rig, text).unwrap();
        let dest = out.join(format!("out{i}"));
        let result = caveray(&[
            "render",
            "--config",
            rig.to_str().unwrap(),
            "--out",
            dest.to_str().unwrap(),
        ]);
        let err = String::from_utf8(result.stderr).unwrap();
        assert_eq!(result.status.code(), Some(2), "{needle}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{err}");
        assert!(!dest.exists(), "nothing is written for a refused rig");
    }
    assert!(!out.join("../escape_left.png").exists());
    std::fs::remove_dir_all(&out).unwrap();
}

/// Run as the README shows, without `scripts/env`: no runtime directory and
/// no Vulkan driver chosen. Whatever adapter `auto` and `gpu` find, stderr
/// holds only caveray's own lines.
#[test]
fn a_plain_shell_run_prints_only_caveray_lines() {
    let out = scratch("plain-shell");
    for backend in ["auto", "gpu"] {
        if backend == "gpu" && GpuRenderer::probe().is_err() {
            continue;
        }
        let result = std::process::Command::new(env!("CARGO_BIN_EXE_caveray"))
            .args(["render", "--config", "cave_configs/powerwall.toml"])
            .args(["--scale", "0.02", "--backend", backend, "--out"])
            .arg(&out)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .env_remove("XDG_RUNTIME_DIR")
            .env_remove("NODEVICE_SELECT")
            .env_remove("VK_ICD_FILENAMES")
            .output()
            .expect("caveray runs");
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(result.status.success(), "{backend}: {stderr}");
        for line in stderr.lines() {
            let line = line.rsplit('\r').next().unwrap_or(line);
            assert!(
                line.is_empty() || line.starts_with("caveray: ") || line.starts_with('['),
                "{backend}: a line that is not caveray's: {line:?}\n{stderr}"
            );
        }
    }
}

/// A 16³ raw volume, opaque only in its first four z slices: a marker for
/// which way the volume's -z end ends up.
fn marked_volume(dir: &Path) -> PathBuf {
    let voxels: Vec<u8> = (0..16 * 16 * 16)
        .map(|i| if i / 256 < 4 { 255 } else { 0 })
        .collect();
    let file = dir.join("marked.raw");
    std::fs::write(&file, voxels).unwrap();
    file
}

/// The mean image row of the lit pixels, 0 the top and 1 the bottom.
fn lit_height(image: &image::RgbaImage) -> f64 {
    let (mut sum, mut n) = (0.0, 0.0);
    for (_, y, p) in image.enumerate_pixels() {
        let w = f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2]);
        sum += w * f64::from(y);
        n += w;
    }
    assert!(n > 0.0, "nothing lit");
    sum / n / f64::from(image.height() - 1)
}

/// The powerwall with a volume placed by `extra`, from `rig` (default: the
/// shipped powerwall): how high the marked end is on the wall.
fn marker_height(dir: &Path, rig: &str, extra: &[&str]) -> f64 {
    let raw = marked_volume(dir);
    let out = dir.join(format!("out{}", extra.join("").replace(['-', ','], "_")));
    let mut args = vec!["render", "--config", rig, "--backend", "cpu"];
    args.extend([
        "--scale",
        "0.04",
        "--tf",
        "grey",
        "--out",
        out.to_str().unwrap(),
    ]);
    args.extend(["--volume", raw.to_str().unwrap(), "--dims", "16,16,16"]);
    args.extend_from_slice(extra);
    let result = caveray(&args);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{extra:?}: {stderr}");
    lit_height(&png(&out.join("wall_left.png")))
}

#[test]
fn the_volume_is_placed_and_turned_as_asked() {
    let dir = scratch("placement");
    let rig = "cave_configs/powerwall.toml";
    // On the y-up powerwall the volume's -z end faces the viewer unless
    // it is told which axis is up.
    let level = marker_height(&dir, rig, &[]);
    assert!((level - 0.5).abs() < 0.08, "marker at {level}");
    let top = marker_height(&dir, rig, &["--volume-up=-z"]);
    let bottom = marker_height(&dir, rig, &["--volume-up", "+z"]);
    assert!(top < 0.4 && bottom > 0.6, "up -z: {top}, up +z: {bottom}");
    // Up and front together, and the centre moved up the wall.
    let both = marker_height(&dir, rig, &["--volume-up=-z", "--volume-front", "+x"]);
    assert!((both - top).abs() < 0.05, "{both} against {top}");
    let higher = marker_height(
        &dir,
        rig,
        &[
            "--volume-up=-z",
            "--volume-centre",
            "0,2.2,0.3",
            "--volume-size",
            "0.6",
        ],
    );
    assert!(higher < top - 0.1, "moved up: {higher} against {top}");

    // A rig's [scene] says which way up volumes go that do not say; the
    // command line wins over it.
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(rig)).unwrap();
    let turned = dir.join("turned.toml");
    let text = text.replace("size = 1.2", "size = 1.2\nvolume_up = \"-z\"");
    std::fs::write(&turned, text).unwrap();
    let turned = turned.to_str().unwrap();
    let rig_top = marker_height(&dir, turned, &[]);
    assert!((rig_top - top).abs() < 0.02, "{rig_top} against {top}");
    let overridden = marker_height(&dir, turned, &["--volume-up=+z"]);
    assert!(
        (overridden - bottom).abs() < 0.02,
        "{overridden} against {bottom}"
    );
}

#[test]
fn placement_options_that_cannot_hold_are_refused() {
    for (extra, needle) in [
        (
            &["--volume-up", "+z", "--volume-front=-z"][..],
            "must be different axes",
        ),
        (&["--volume-up", "up"][..], "--volume-up"),
        (&["--volume-size", "0"][..], "expected a finite number > 0"),
        (&["--volume-centre", "1,2"][..], "three"),
    ] {
        let out = scratch("refused-placement");
        let mut args = vec!["render", "--config", "cave_configs/powerwall.toml"];
        args.extend(["--scale", "0.01", "--out", out.to_str().unwrap()]);
        args.extend_from_slice(extra);
        let result = caveray(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{extra:?}: {stderr}");
        assert!(stderr.contains(needle), "{extra:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{extra:?}: {stderr}");
    }
}

/// `caveray render` with `args`, stderr a pipe (not a terminal) and
/// in-view progress lines every `every` seconds.
fn render_logged(args: &[&str], every: &str) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_caveray"))
        .arg("render")
        .args(args)
        .env("CAVERAY_PROGRESS_EVERY", every)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("caveray runs")
}

/// The percentage an in-view progress line gives for `label`'s view.
fn view_percent(line: &str, label: &str) -> Option<f64> {
    let rest = line
        .strip_prefix('[')?
        .split_once(&format!("  {label} "))?
        .1;
    rest.strip_suffix('%')?.parse().ok()
}

#[test]
fn the_progress_moves_within_a_view_in_whole_lines_when_logged() {
    let out = scratch("progress");
    let result = render_logged(
        &[
            "--config",
            "cave_configs/fishtank_desktop.toml",
            "--backend",
            "cpu",
            "--volume",
            "phantom:48",
            "--shading",
            "shadows",
            "--scale",
            "0.15",
            "--out",
            out.to_str().unwrap(),
        ],
        "0.01",
    );
    let err = String::from_utf8(result.stderr).unwrap();
    assert!(result.status.success(), "{err}");
    // Not a terminal: whole lines, no carriage returns or escapes.
    assert!(!err.contains('\r') && !err.contains('\x1b'), "{err:?}");
    let within: Vec<(&str, f64)> = err
        .lines()
        .filter_map(|l| view_percent(l, "monitor_left").map(|p| (l, p)))
        .collect();
    assert!(
        !within.is_empty(),
        "no line within the left eye's view:\n{err}"
    );
    for (line, percent) in &within {
        assert!((0.0..=100.0).contains(percent), "{line}");
        assert!(line.contains(" 0/2 "), "{line}");
    }
    // Each eye's own line when it is done, the last one without an ETA.
    let last = err.lines().last().unwrap();
    assert!(
        last.contains("] 2/2 ") && last.contains("monitor_right 384x216"),
        "{last}"
    );
    assert!(!last.contains("ETA"), "{last}");
    assert!(
        err.lines()
            .any(|l| l.contains("] 1/2 ") && l.contains(", ETA ")),
        "{err}"
    );
    std::fs::remove_dir_all(&out).unwrap();

    // A multi-view display: the panel's image, then each view, as steps.
    let out = scratch("progress-display");
    let result = render_logged(
        &[
            "--config",
            "cave_configs/lenticular_8view.toml",
            "--volume",
            "phantom:24",
            "--scale",
            "0.03",
            "--iso",
            "0.2",
            "--out",
            out.to_str().unwrap(),
        ],
        "5",
    );
    let err = String::from_utf8(result.stderr).unwrap();
    assert!(result.status.success(), "{err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 9, "{err}");
    assert!(
        lines[0].contains("] 1/9 ") && lines[0].contains("interleaved 58x36"),
        "{err}"
    );
    assert!(
        lines[8].contains("] 9/9 ") && lines[8].contains("view 7 58x36"),
        "{err}"
    );
    std::fs::remove_dir_all(&out).unwrap();
}

/// An option the chosen kind of config would ignore is refused, naming it.
#[test]
fn options_that_would_do_nothing_are_refused() {
    let out = scratch("unused-options");
    let o = out.to_str().unwrap();
    let display = "cave_configs/lenticular_8view.toml";
    let cologne = "cave_configs/cologne_5wall.toml";
    for (config, extra, want) in [
        (
            display,
            &["--shading", "shadows", "--stereo", "reprojection"][..],
            "--shading and --stereo do not apply to a multi-view display",
        ),
        (
            display,
            &["--time", "2"][..],
            "--time does not apply to a multi-view display",
        ),
        (
            cologne,
            &["--iso", "0.3"][..],
            "--iso applies to multi-view displays only",
        ),
        (
            cologne,
            &["--iso", "0.3", "--iso-filter", "tricubic"][..],
            "--iso and --iso-filter apply to multi-view displays only",
        ),
        (
            cologne,
            &["--layer-format", "rgba32f"][..],
            "--layer-format applies to --stereo reprojection only",
        ),
        (
            cologne,
            &["--time", "100"][..],
            "--time 100 is outside the rig's head path (0 to 8 s)",
        ),
        (cologne, &["--time=-1"][..], "outside the rig's head path"),
        (
            "cave_configs/powerwall.toml",
            &["--time", "1"][..],
            "--time needs a head path",
        ),
    ] {
        let mut args = vec!["render", "--config", config, "--scale", "0.01", "--out", o];
        args.extend_from_slice(extra);
        let result = caveray(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{extra:?}: {stderr}");
        assert!(stderr.contains(want), "{extra:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{extra:?}: {stderr}");
    }
    // A rig takes its own options, a time at the path's very end included.
    let ok = caveray(&[
        "render", "--config", cologne, "--scale", "0.01", "--out", o, "--time", "8", "--stereo",
        "two-pass",
    ]);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
}

#[test]
fn a_mesh_of_the_volume_s_isosurface_shows_on_every_wall_alike_on_both_backends() {
    // The phantom's isosurface as triangles inside it, on the GPU and the
    // CPU, and re-projected: the mesh changes the picture, the backends
    // agree, and the re-projected right eyes are close to their own
    // passes.
    let base = scratch("mesh");
    let common = ["--scale", "0.04", "--volume", "phantom:24"];
    let run = |name: &str, extra: &[&str]| {
        let out = base.join(name);
        let mut args = common.to_vec();
        args.extend_from_slice(extra);
        render(&out, &args);
        out
    };
    let plain = run("plain", &[]);
    let mesh = ["--mesh", "0.4", "--mesh-color", "0.2,0.9,0.3"];
    let gpu = run("gpu", &[&mesh[..], &["--backend", "gpu"]].concat());
    let cpu = run("cpu", &[&mesh[..], &["--backend", "cpu"]].concat());
    let file = "front_left.png";
    let changed = mean_difference(&png(&plain.join(file)), &png(&gpu.join(file)));
    assert!(
        changed > 2.0,
        "the mesh changed {file} by {changed} levels only"
    );
    for file in ["front_left.png", "floor_right.png", "cave_left.png"] {
        let d = mean_difference(&png(&gpu.join(file)), &png(&cpu.join(file)));
        assert!(
            d < 0.5,
            "{file}: GPU and CPU differ by {d} levels on average"
        );
    }
    let out = base.join("reprojected");
    let result = caveray(&[
        "render",
        "--config",
        "cave_configs/cologne_5wall.toml",
        "--out",
        out.to_str().unwrap(),
        "--scale",
        "0.04",
        "--volume",
        "phantom:24",
        "--mesh",
        "0.4",
        "--mesh-color",
        "0.2,0.9,0.3",
        "--stereo",
        "reprojection",
        "--backend",
        "gpu",
    ]);
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&result.stdout),
        String::from_utf8_lossy(&result.stderr)
    );
    assert!(result.status.success(), "{said}");
    assert!(said.contains("reprojection ("), "{said}");
    for file in ["front_right.png", "floor_right.png"] {
        let d = mean_difference(&png(&out.join(file)), &png(&gpu.join(file)));
        assert!(
            d < 1.0,
            "{file}: re-projected and two passes differ by {d} levels on average"
        );
    }
    let bad = caveray(&[
        "render",
        "--config",
        "cave_configs/cologne_5wall.toml",
        "--mesh",
        "1.5",
    ]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("from 0 to 1"));
    std::fs::remove_dir_all(&base).unwrap();
}
