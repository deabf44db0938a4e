//! `caveray view` end to end: headless frames with a screenshot, its
//! sidecar and the run's figures; in a window under Xvfb, synthetic keys
//! and a mouse drag move the head, and once every wall shows its own image
//! the screenshot equals `caveray render` for that head pose.

use crate::common;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

use common::caveray;
use serde_json::Value;

const RIG: &str = "cave_configs/cologne_5wall.toml";
/// Small walls (80 x 80) of a small volume: quick on the CPU.
const SCENE: [&str; 6] = [
    "--volume",
    "phantom:48",
    "--scale",
    "0.05",
    "--backend",
    "cpu",
];

fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caveray-view-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn json(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

fn png(path: &Path) -> image::RgbaImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgba8()
}

/// The colour of `image` inside `rect` (x, y, w, h), opaque.
fn crop(image: &image::RgbaImage, rect: &Value) -> image::RgbaImage {
    let r: Vec<u32> = rect
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as u32)
        .collect();
    let mut out = image::imageops::crop_imm(image, r[0], r[1], r[2], r[3]).to_image();
    opaque(&mut out);
    out
}

fn opaque(image: &mut image::RgbaImage) {
    for p in image.pixels_mut() {
        p.0[3] = 255;
    }
}

/// SSIM of two images' colour (the conformance tool's score).
fn ssim(a: &image::RgbaImage, b: &image::RgbaImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let (w, h) = a.dimensions();
    common::cts::score(a.as_raw(), b.as_raw(), w as usize, h as usize).0
}

#[test]
fn headless_frames_write_a_screenshot_its_sidecar_and_the_runs_figures() {
    let dir = scratch("headless");
    let shot = dir.join("shot.png");
    let report = dir.join("run.json");
    let mut args = vec![
        "view",
        "--config",
        RIG,
        "--headless-frames",
        "30",
        "--look",
        "flat",
        "--screenshot",
        shot.to_str().unwrap(),
        "--json",
        report.to_str().unwrap(),
    ];
    args.extend_from_slice(&SCENE);
    let out = caveray(&args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("caveray view: wrote"), "{stdout}");
    assert_eq!(png(&shot).dimensions(), (800, 600));
    let info = json(&shot.with_extension("json"));
    let walls = info["walls"].as_array().unwrap();
    let names: Vec<&str> = walls.iter().map(|w| w["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["front", "left", "right", "ceiling", "floor"]);
    for w in walls {
        // Laid flat at 1:1: each 1600-pixel wall at 0.05 is 80 pixels.
        let rect = w["rect"].as_array().unwrap();
        assert_eq!(rect[2].as_u64(), Some(80), "{w}");
        assert_eq!(rect[3].as_u64(), Some(80), "{w}");
    }
    let run = json(&report);
    // 30 frames: 29 intervals between them.
    assert_eq!(run["frames"].as_u64(), Some(29), "{run}");
    assert_eq!(run["window"], serde_json::json!([800, 600]));
    assert_eq!(run["eyes"], "left");
    let panes = run["walls"].as_array().unwrap();
    assert_eq!(panes.len(), 5, "one eye of each wall: {run}");
    for p in panes {
        assert!(p["frames"].as_u64().unwrap() > 0, "{p}");
        assert!(
            p["own"].as_u64().unwrap() <= p["frames"].as_u64().unwrap(),
            "{p}"
        );
    }
}

#[test]
fn bad_view_options_are_refused_with_their_reasons() {
    for (extra, want) in [
        (
            vec!["--headless-frames", "0"],
            "--headless-frames must be at least 1",
        ),
        (
            vec!["--strip", "4"],
            "--strip goes with --headless-frames and --screenshot",
        ),
        (
            vec!["--size", "20x10"],
            "expected WIDTHxHEIGHT, each 64 to 8192 pixels",
        ),
        (
            vec!["--eyes", "both"],
            "expected left, right, anaglyph or side-by-side",
        ),
        (vec!["--deadline", "0"], "--deadline must be 1 to 10000 ms"),
        (
            vec![
                "--config",
                "cave_configs/lenticular_8view.toml",
                "--eyes",
                "anaglyph",
                "--play",
            ],
            "--play and --eyes do not apply to a multi-view display",
        ),
    ] {
        let config = if extra.contains(&"--config") {
            &[][..]
        } else {
            &["--config", RIG][..]
        };
        let mut args = vec!["view"];
        args.extend_from_slice(config);
        args.extend_from_slice(&extra);
        let out = caveray(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {stderr}");
        assert!(stderr.contains(want), "{extra:?}: {stderr}");
    }
}

/// An X server of its own on a free display number, stopped when dropped.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Option<Self> {
        for n in 90 + std::process::id() % 50..200 {
            if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
                continue;
            }
            let display = format!(":{n}");
            let mut child = Command::new("Xvfb")
                .args([&display, "-screen", "0", "1024x768x24", "-nolisten", "tcp"])
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .ok()?;
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(10) {
                if let Ok(Some(_)) = child.try_wait() {
                    break;
                }
                if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
                    return Some(Self { child, display });
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = child.kill();
            let _ = child.wait();
        }
        None
    }

    fn xdotool(&self, args: &[&str]) -> String {
        let out = Command::new("timeout")
            .arg("60")
            .arg("xdotool")
            .args(args)
            .env("DISPLAY", &self.display)
            .output()
            .expect("xdotool runs");
        assert!(
            out.status.success(),
            "xdotool {args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).trim().to_string()
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The viewer's stdout, line by line.
fn lines_of(child: &mut Child) -> Receiver<String> {
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    rx
}

/// Waits for the line announcing `file`.
fn announced(lines: &Receiver<String>, file: &str) -> String {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(180) {
        if let Ok(line) = lines.recv_timeout(Duration::from_secs(1)) {
            if line.contains(file) {
                return line;
            }
        }
    }
    panic!("the viewer never wrote {file}");
}

#[test]
fn in_a_window_keys_and_a_drag_move_the_head_and_the_walls_converge_to_render() {
    let tools = ["Xvfb", "xdotool"];
    if let Some(tool) = tools.iter().find(|t| {
        Command::new("sh")
            .args(["-c", &format!("command -v {t}")])
            .output()
            .map_or(true, |o| !o.status.success())
    }) {
        common::missing(&format!("{tool} is not installed"));
        return;
    }
    let Some(x) = Xvfb::start() else {
        panic!("Xvfb did not start");
    };
    let dir = scratch("window");
    let shot = dir.join("shot.png");
    let mut args = vec![
        "view",
        "--config",
        RIG,
        "--look",
        "flat",
        "--warp",
        "quad",
        "--screenshot",
        shot.to_str().unwrap(),
    ];
    args.extend_from_slice(&SCENE);
    let mut viewer = Command::new(env!("CARGO_BIN_EXE_caveray"))
        .args(&args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("DISPLAY", &x.display)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("caveray view starts");
    let lines = lines_of(&mut viewer);
    let window = x.xdotool(&["search", "--sync", "--name", "caveray view"]);
    let window = window.lines().next().unwrap().to_string();
    x.xdotool(&["windowfocus", "--sync", &window]);

    // Before: every wall's own image of the rig's head.
    x.xdotool(&["key", "F12"]);
    let before_line = announced(&lines, "shot.png");
    assert!(before_line.contains("; converged)"), "{before_line}");

    // Walk forward for a while, then drag to the right to turn the head
    // (in the rig's viewport, right of the controls).
    // Held long enough for frames to see it however loaded the machine is.
    x.xdotool(&["keydown", "w"]);
    std::thread::sleep(Duration::from_millis(600));
    x.xdotool(&["keyup", "w"]);
    x.xdotool(&["mousemove", "--window", &window, "600", "400"]);
    x.xdotool(&["mousedown", "1"]);
    for dx in [10, 20, 30, 40] {
        x.xdotool(&[
            "mousemove",
            "--window",
            &window,
            &(600 + dx).to_string(),
            "400",
        ]);
        std::thread::sleep(Duration::from_millis(50));
    }
    x.xdotool(&["mouseup", "1"]);
    std::thread::sleep(Duration::from_millis(200));
    x.xdotool(&["key", "F12"]);
    let after_line = announced(&lines, "shot-2.png");
    assert!(after_line.contains("; converged)"), "{after_line}");
    x.xdotool(&["key", "Escape"]);
    let start = Instant::now();
    let status = loop {
        if let Some(s) = viewer.try_wait().unwrap() {
            break s;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the viewer did not quit on Escape"
        );
        std::thread::sleep(Duration::from_millis(100));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut viewer.stderr.take().unwrap(), &mut stderr).unwrap();
    assert!(status.success(), "{stderr}");

    let before = json(&shot.with_extension("json"));
    let after_png = dir.join("shot-2.png");
    let after = json(&after_png.with_extension("json"));
    let head = |v: &Value, key: &str| -> Vec<f64> {
        v[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    // The head walked forward (the rig's +y) and turned right (yaw down).
    let (h0, h1) = (head(&before, "head"), head(&after, "head"));
    assert!(h1[1] - h0[1] > 50.0, "{h0:?} -> {h1:?}");
    let (y0, y1) = (head(&before, "head_ypr"), head(&after, "head_ypr"));
    assert!(y1[0] < y0[0] - 2.0, "{y0:?} -> {y1:?}");

    // `caveray render` of the head the second screenshot shows.
    let triple = |v: &[f64]| format!("{},{},{}", v[0], v[1], v[2]);
    let rendered = dir.join("render");
    let (head_arg, ypr_arg) = (triple(&h1), triple(&y1));
    let mut args = vec![
        "render",
        "--config",
        RIG,
        "--out",
        rendered.to_str().unwrap(),
        "--head",
        &head_arg,
        "--head-ypr",
        &ypr_arg,
    ];
    args.extend_from_slice(&SCENE);
    let out = caveray(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let (shot_before, shot_after) = (png(&shot), png(&after_png));
    let mut changed = 0;
    for (w, wall) in after["walls"].as_array().unwrap().iter().enumerate() {
        let name = wall["name"].as_str().unwrap();
        let shown = crop(&shot_after, &wall["rect"]);
        let mut want = png(&rendered.join(format!("{name}_left.png")));
        opaque(&mut want);
        let score = ssim(&shown, &want);
        assert!(score >= 0.99, "{name}: SSIM {score} against render");
        let earlier = crop(&shot_before, &before["walls"][w]["rect"]);
        if earlier != shown {
            changed += 1;
        }
    }
    // The volume sits before the front wall: its image must have changed.
    let front_before = crop(&shot_before, &before["walls"][0]["rect"]);
    let front_after = crop(&shot_after, &after["walls"][0]["rect"]);
    assert!(
        ssim(&front_before, &front_after) < 0.99,
        "the front wall did not change after the move"
    );
    assert!(changed >= 1);
}

#[test]
fn a_multi_view_display_shows_its_panel_beside_one_view() {
    let dir = scratch("display");
    let shot = dir.join("display.png");
    let out = caveray(&[
        "view",
        "--config",
        "cave_configs/lenticular_8view.toml",
        "--volume",
        "phantom:24",
        "--scale",
        "0.1",
        "--headless-frames",
        "20",
        "--screenshot",
        shot.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let info = json(&shot.with_extension("json"));
    let walls = info["walls"].as_array().unwrap();
    let names: Vec<&str> = walls.iter().map(|w| w["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["panel", "view 0"]);
    // The panel and the view pixel for pixel, at the display's 1920 x 1200
    // times 0.1.
    for w in walls {
        assert_eq!(w["rect"][2].as_u64(), Some(192), "{w}");
        assert_eq!(w["rect"][3].as_u64(), Some(120), "{w}");
    }
}
