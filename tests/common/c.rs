//! Building and running the C host programs of `tests/capi/c/` against the
//! library cargo built, and the scene they render.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use anari_library_caveray::cave::Eye;
use anari_library_caveray::data::{preset, shepp_logan};
use anari_library_caveray::geometry::PrimaryRays;
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{CpuRenderer, Frame, FrameDesc, RenderSettings};
use anari_library_caveray::scene::{Scene, StructuredVolume, TransferFunction};
use glam::UVec2;

use super::rig;

/// `target/<profile>/deps`: `cargo test` builds the library there next to
/// the test binaries (only `cargo build` copies it up to `target/<profile>`,
/// so a copy there may be stale).
pub fn lib_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let dir = exe.parent().unwrap().to_path_buf();
    assert!(
        dir.join("libanari_library_caveray.so").exists(),
        "{} has no libanari_library_caveray.so",
        dir.display()
    );
    dir
}

pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A scratch directory for one test, emptied first.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Compiles `sources` (C, or C++ when `cxx`) into `out`, with warnings as
/// errors, against `include/` and linked to the library when `link`.
pub fn compile(sources: &[&str], out: &Path, cxx: bool, link: bool) {
    let lib = lib_dir();
    let mut cmd = Command::new(if cxx { "c++" } else { "cc" });
    cmd.current_dir(root())
        .args(if cxx {
            &["-std=c++11"][..]
        } else {
            &["-std=c99"][..]
        })
        .args(["-Wall", "-Wextra", "-Werror", "-g", "-Iinclude"])
        .args(sources)
        .arg("-o")
        .arg(out);
    if link {
        cmd.arg(format!("-L{}", lib.display()))
            .arg("-lanari_library_caveray")
            .arg(format!("-Wl,-rpath,{}", lib.display()));
    }
    cmd.arg("-ldl").arg("-lm");
    let output = cmd.output().expect("a C compiler (cc/c++) is installed");
    assert!(
        output.status.success(),
        "compiling {sources:?} failed:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

pub fn valgrind_available() -> bool {
    Command::new("valgrind")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// A command for a host program linked to the library: `cargo test` puts
/// `target/<profile>` on LD_LIBRARY_PATH, which outranks the program's
/// RUNPATH, so a stale copy there would be loaded instead of the library
/// just built; the library's own directory goes first.
pub fn host_command(program: impl AsRef<std::ffi::OsStr>) -> Command {
    let mut cmd = Command::new(program);
    let mut path = std::ffi::OsString::from(lib_dir());
    if let Some(rest) = std::env::var_os("LD_LIBRARY_PATH") {
        path.push(":");
        path.push(rest);
    }
    cmd.env("LD_LIBRARY_PATH", path);
    cmd
}

/// Runs a host program, under valgrind memcheck when asked (then on the
/// CPU reference: valgrind checks our code, not Mesa's JIT).
pub fn run(program: &Path, args: &[&Path], valgrind: bool) -> Output {
    run_with(program, args, valgrind, &[])
}

/// `run`, with extra environment variables.
pub fn run_with(program: &Path, args: &[&Path], valgrind: bool, env: &[(&str, &str)]) -> Output {
    let mut cmd = if valgrind {
        let mut c = host_command("valgrind");
        c.args([
            "--error-exitcode=99",
            "--leak-check=full",
            "--errors-for-leak-kinds=definite",
            "--show-leak-kinds=definite",
        ])
        .arg(program)
        .env("CAVERAY_BACKEND", "cpu");
        c
    } else {
        host_command(program)
    };
    cmd.args(args)
        .envs(env.iter().copied())
        .output()
        .expect("the host program runs")
}

pub fn describe(output: &Output) -> String {
    format!(
        "exit {:?}\nstdout:\n{}\nstderr:\n{}",
        output.status.code(),
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}

/// The scene of the C host tests: a volume placed in the Cologne CAVE as
/// `caveray render` places it, seen on the front wall by the default head's
/// left eye.
pub struct WallScene {
    pub file: PathBuf,
    pub size: UVec2,
    /// The Rust API's image of the same view (CPU reference, RGBA8).
    pub reference: Frame,
    /// The scene and rays it was made from, for other references.
    pub scene: Scene,
    pub rays: anari_library_caveray::geometry::RayGen,
}

/// The Shepp-Logan phantom at 32³ with its preset.
pub fn phantom() -> (StructuredVolume, TransferFunction) {
    (shepp_logan(32), preset("phantom").unwrap())
}

/// `longest`: the frame's longer side in pixels. A preset `tf` is stretched
/// over the data's value range when `stretch` is set (as for CT presets).
pub fn wall_scene(
    dir: &Path,
    longest: u32,
    (volume, tf): (StructuredVolume, TransferFunction),
    stretch: bool,
) -> WallScene {
    let rig = rig("cologne_5wall");
    let wall = rig.wall("front").unwrap();
    let head = rig.viewer.head;
    let view = rig.view(wall, Eye::Left, &head).unwrap();
    let scale = f64::from(longest) / f64::from(wall.resolution.max_element());
    let size = (wall.resolution.as_dvec2() * scale).round().as_uvec2();

    let (centre, extent) = (rig.scene.centre.as_vec3(), rig.scene.size as f32);
    let volume = volume.placed(centre, extent);
    let mut tf = tf.with_unit_distance(0.5 * extent).unwrap();
    if stretch {
        let (lo, hi) = volume.value_range();
        tf = tf.with_value_range(lo, hi).unwrap();
    }

    let raw = dir.join("phantom.f32");
    let voxels: Vec<u8> = (0..volume.voxels().len())
        .flat_map(|i| volume.value(i).to_ne_bytes())
        .collect();
    std::fs::write(&raw, voxels).unwrap();

    let table = tf.table();
    let join = |v: &[f32]| {
        v.iter()
            .map(|x| format!("{x:.9e}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let rgb: Vec<f32> = table.iter().flat_map(|c| [c.x, c.y, c.z, 1.0]).collect();
    let alpha: Vec<f32> = table.iter().map(|c| c.w).collect();
    let v3 = |v: glam::DVec3| join(&v.as_vec3().to_array());
    let (lo, hi) = tf.value_range();
    let d = volume.dims();
    let text = format!(
        "dims {} {} {} {}\norigin {}\nspacing {}\nrange {}\ncolors {}\nrgba {}\nopacities {}\nalpha {}\nunit {}\nsize {} {}\nll {}\nlr {}\nur {}\neye {}\nview {}\nproj {}\n",
        d.x, d.y, d.z, raw.display(),
        join(&volume.origin().to_array()),
        join(&volume.spacing().to_array()),
        join(&[lo, hi]),
        table.len(), join(&rgb),
        table.len(), join(&alpha),
        join(&[tf.unit_distance()]),
        size.x, size.y,
        v3(wall.screen.ll()), v3(wall.screen.lr()), v3(wall.screen.ur()),
        v3(view.eye_position),
        join(&view.projection.view.as_mat4().to_cols_array()),
        join(&view.projection.proj.as_mat4().to_cols_array()),
    );
    let file = dir.join("scene.txt");
    std::fs::write(&file, text).unwrap();

    let scene = Scene::new(volume, tf);
    let rays = view.camera.ray_gen(size);
    let reference = CpuRenderer::new()
        .render(
            &scene,
            &rays,
            &RenderSettings::default(),
            &FrameDesc::new(size),
        )
        .unwrap();
    let lit = reference
        .to_linear()
        .iter()
        .filter(|p| p.truncate().max_element() > 0.05)
        .count();
    assert!(
        lit * 20 > (size.x * size.y) as usize,
        "the volume covers only {lit} pixels of the wall; the test would prove little"
    );
    WallScene {
        file,
        size,
        reference,
        scene,
        rays,
    }
}

/// A raw RGBA8 image a host wrote (lower-left first) as a frame.
pub fn read_rgba(path: &Path, size: UVec2) -> Frame {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert_eq!(
        bytes.len() as u32,
        4 * size.x * size.y,
        "{}",
        path.display()
    );
    Frame {
        size,
        color: anari_library_caveray::render::ColorData::Rgba8(bytes),
        depth: None,
        hits: None,
        samples: 0,
    }
}

/// The `size` pixels of RGBA8 frame `frame` from `origin` on: one eye of
/// a split stereo frame.
pub fn crop(frame: &Frame, origin: UVec2, size: UVec2) -> Frame {
    let anari_library_caveray::render::ColorData::Rgba8(bytes) = &frame.color else {
        panic!("RGBA8 expected");
    };
    let pixels = (origin.y..origin.y + size.y)
        .flat_map(|y| {
            let start = 4 * (y * frame.size.x + origin.x) as usize;
            bytes[start..start + 4 * size.x as usize].to_vec()
        })
        .collect();
    Frame {
        size,
        color: anari_library_caveray::render::ColorData::Rgba8(pixels),
        depth: None,
        hits: None,
        samples: 0,
    }
}
