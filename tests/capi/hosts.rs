//! C and C++ host programs (tests/capi/c/) built with the system compiler
//! against include/ and the library cargo built: a CAVE wall through three
//! cameras, every misuse the C API must survive, and the ANARI SDK
//! loader's virtual dispatch. The first two also run under valgrind
//! memcheck when it is installed.

use crate::common;

use anari_library_caveray::data::{preset, Manifest};
use anari_library_caveray::render::ssim;
use anari_library_caveray::render::Render as _;
use common::c::{
    compile, describe, phantom, read_rgba, run, scratch, valgrind_available, wall_scene, WallScene,
};
use common::{missing, shared_manifest};

/// Test (a): each camera's image from the C API matches the Rust API's.
fn render_wall(dir: &std::path::Path, scene: &WallScene, valgrind: bool) {
    let program = dir.join("render_wall");
    compile(&["tests/capi/c/render_wall.c"], &program, false, true);
    let output = run(&program, &[&scene.file, dir], valgrind);
    assert!(
        output.status.success(),
        "render_wall: {}",
        describe(&output)
    );
    for camera in ["perspective", "matrix", "offAxis"] {
        let image = read_rgba(&dir.join(format!("{camera}.rgba")), scene.size);
        let s = ssim(&image, &scene.reference).unwrap();
        eprintln!("{camera}: SSIM {s:.6} against the Rust API");
        assert!(
            s > 0.98,
            "{camera} camera through the C API: SSIM {s:.4} against the Rust API's image"
        );
    }
}

#[test]
fn c_host_renders_a_cave_wall_with_each_camera() {
    let dir = scratch("c_render_wall");
    render_wall(&dir, &wall_scene(&dir, 96, phantom(), false), false);
}

/// What a CAVE host needs most: a C program renders a CT volume through the matrix
/// camera (and the other two). Needs the shared data (a failure in CI).
#[test]
fn c_host_renders_a_ct_volume() {
    let loaded = Manifest::locate(None, &[shared_manifest()]).and_then(|m| m.load_volume("cthead"));
    let volume = match loaded {
        Ok(v) => v,
        Err(e) => {
            missing(&format!("the CT head is not available ({e})"));
            return;
        }
    };
    let dir = scratch("c_render_ct");
    let tf = preset("ct-skin-bone").unwrap();
    render_wall(&dir, &wall_scene(&dir, 96, (volume, tf), true), false);
}

#[test]
fn c_host_render_is_clean_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    let dir = scratch("c_render_wall_valgrind");
    render_wall(&dir, &wall_scene(&dir, 32, phantom(), false), true);
}

/// Test (b): every misuse reaches the status callback with the right
/// severity, code and message, and the device still renders afterwards.
fn misuse(valgrind: bool) {
    let dir = scratch(if valgrind {
        "c_misuse_valgrind"
    } else {
        "c_misuse"
    });
    let program = dir.join("misuse");
    compile(&["tests/capi/c/misuse.c"], &program, false, true);
    let output = run(&program, &[], valgrind);
    let text = describe(&output);
    assert!(output.status.success(), "misuse: {text}");
    assert!(!text.contains("FAIL"), "misuse: {text}");
    let passed = text.matches("PASS").count();
    assert!(passed >= 30, "only {passed} misuse checks ran: {text}");
}

#[test]
fn misuse_reaches_the_status_callback() {
    misuse(false);
}

#[test]
fn misuse_is_clean_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    misuse(true);
}

/// Runs tests/capi/c/NAME.c, a host that prints PASS/FAIL per check
/// (under valgrind if asked): it must pass at least `checks` of them and
/// fail none.
fn checking_host(name: &str, checks: usize, valgrind: bool) {
    checking_host_of(name, checks, valgrind, &[]);
}

/// `checking_host`, the program given `args`.
fn checking_host_of(name: &str, checks: usize, valgrind: bool, args: &[&std::path::Path]) {
    let dir = scratch(&format!(
        "c_{name}{}",
        if valgrind { "_valgrind" } else { "" }
    ));
    let program = dir.join(name);
    compile(&[&format!("tests/capi/c/{name}.c")], &program, false, true);
    let output = run(&program, args, valgrind);
    let text = describe(&output);
    assert!(output.status.success(), "{name}: {text}");
    assert!(!text.contains("FAIL"), "{name}: {text}");
    assert!(text.matches("PASS").count() >= checks, "{name}: {text}");
}

/// Surfaces beside a volume as visualization hosts send them.
fn mesh_host(valgrind: bool) {
    checking_host("mesh_host", 10, valgrind);
}

/// An `amr` field as OpenCOVER sends one, then in anari-visionaray's form.
fn amr_host(valgrind: bool) {
    checking_host("amr_host", 9, valgrind);
}

#[test]
fn a_host_renders_an_amr_field_in_both_forms() {
    amr_host(false);
}

#[test]
fn the_amr_host_is_clean_under_valgrind() {
    amr_host(true);
}

/// A `nanovdb` field of a grid the NanoVDB library wrote, from the host's
/// memory.
fn nanovdb_host(valgrind: bool) {
    let Some(written) = crate::common::nanovdb::grids() else {
        return;
    };
    checking_host_of(
        "nanovdb_host",
        10,
        valgrind,
        &[&written.dir.join("fog.blob")],
    );
}

#[test]
fn a_host_renders_a_nanovdb_grid_from_its_memory() {
    nanovdb_host(false);
}

#[test]
fn the_nanovdb_host_is_clean_under_valgrind() {
    nanovdb_host(true);
}

/// An unstructured field as OpenCOVER sends one, then with cell data.
fn unstructured_host(valgrind: bool) {
    checking_host("unstructured_host", 8, valgrind);
}

#[test]
fn a_host_renders_every_cell_kind_with_vertex_and_cell_data() {
    unstructured_host(false);
}

#[test]
fn the_unstructured_host_is_clean_under_valgrind() {
    unstructured_host(true);
}

#[test]
fn a_host_sees_its_meshes_and_glyphs_through_its_volume() {
    mesh_host(false);
}

#[test]
fn meshes_and_glyphs_are_clean_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    mesh_host(true);
}

/// Test (c): a C++ host that, like the SDK's libanari, dlopens the library,
/// calls `anari_library_caveray_new_library` and drives the returned
/// objects through their virtual tables only.
#[test]
fn sdk_loader_protocol_renders_the_wall() {
    let dir = scratch("c_loader");
    let scene = wall_scene(&dir, 128, phantom(), false);
    let program = dir.join("loader");
    compile(&["tests/capi/c/loader.cpp"], &program, true, false);
    let lib = common::c::lib_dir().join("libanari_library_caveray.so");
    let rig = common::rig("cologne_5wall");
    let head = rig.viewer.head;
    let b = rig.eye_position(&head, anari_library_caveray::cave::Eye::Right)
        - rig.eye_position(&head, anari_library_caveray::cave::Eye::Left);
    let baseline = format!("{},{},{}", b.x, b.y, b.z);
    let output = common::c::run_with(
        &program,
        &[&lib, &scene.file, &dir, std::path::Path::new(&baseline)],
        false,
        &[("CAVERAY_BACKEND", "gpu")],
    );
    assert!(output.status.success(), "loader: {}", describe(&output));
    let image = read_rgba(&dir.join("loader.rgba"), scene.size);
    let s = ssim(&image, &scene.reference).unwrap();
    assert!(
        s > 0.98,
        "matrix camera through the loader protocol: SSIM {s:.4}"
    );
    // Both eyes: a per-eye pair and a sideBySide frame, each right eye
    // within the re-projection's bound of the right eye rendered alone.
    use anari_library_caveray::render::{dssim, ColorData, Frame};
    let eye = |name: &str| read_rgba(&dir.join(format!("{name}.rgba")), scene.size);
    let alone = eye("alone_right");
    let (w, h) = (scene.size.x as usize, scene.size.y as usize);
    let wide = read_rgba(
        &dir.join("side_by_side.rgba"),
        glam::UVec2::new(2 * scene.size.x, scene.size.y),
    );
    let half = |x0: usize| {
        let ColorData::Rgba8(bytes) = &wide.color else {
            panic!("RGBA8 expected")
        };
        Frame {
            color: ColorData::Rgba8(
                (0..h)
                    .flat_map(|y| bytes[4 * (y * 2 * w + x0)..4 * (y * 2 * w + x0 + w)].to_vec())
                    .collect(),
            ),
            ..alone.clone()
        }
    };
    let unmoved = dssim(&eye("pair_left"), &alone).unwrap();
    for (what, right) in [
        ("stereoPartner", eye("pair_right")),
        ("sideBySide", half(w)),
    ] {
        let d = dssim(&right, &alone).unwrap();
        eprintln!("{what} through the loader protocol: right eye DSSIM {d:.4} (left as right {unmoved:.4})");
        assert!(
            d < 0.03 && d < 0.5 * unmoved,
            "{what}: DSSIM {d} vs {unmoved}"
        );
    }
    let s = ssim(&half(0), &eye("pair_left")).unwrap();
    assert!(
        s > 0.99,
        "sideBySide left eye against the left frame: SSIM {s:.4}"
    );
}

/// The mesh benchmark's host (docs/benchmarks.md) builds against caveray's
/// headers and times it: one JSON line, its million triangles and 1024
/// spheres from the host's own memory, no error, the scene on screen, its
/// peak memory.
#[test]
fn mesh_benchmark_host_times_a_million_triangles() {
    let dir = scratch("c_mesh_bench");
    let program = dir.join("mesh_bench");
    compile(&["examples/c/mesh_bench.c"], &program, false, true);
    let output = common::c::host_command(&program)
        .args(["caveray", "2"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(output.status.success(), "mesh_bench: {}", describe(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    let line = stdout.lines().last().unwrap_or_default();
    let report: serde_json::Value =
        serde_json::from_str(line).unwrap_or_else(|e| panic!("not one JSON line ({e}): {stdout}"));
    assert_eq!(report["triangles"], 1_001_112, "{line}");
    assert_eq!(report["spheres"], 1024, "{line}");
    assert_eq!(report["anari_errors"], 0, "{line}");
    assert!(report["frame_ms_median"].as_f64().unwrap() > 0.0, "{line}");
    // The bumpy sphere of radius about 1 and the shell of small spheres
    // around it (radius 1.35), from 3.5 away under a 60 degree field of
    // view: the reference device covers 228,150 pixels.
    let hit = report["hit_pixels"].as_u64().unwrap();
    assert!((220_000..236_000).contains(&hit), "{line}");
    // The host's own arrays (26 MB) are part of the process.
    let rss = report["peak_rss_mb"].as_f64().unwrap();
    assert!(rss > report["host_arrays_mb"].as_f64().unwrap(), "{line}");
}

/// The README's C example builds with one cc command and renders both eyes.
#[test]
fn cave_wall_example_renders_both_eyes() {
    let dir = scratch("c_example");
    let program = dir.join("cave_wall");
    compile(&["examples/c/cave_wall.c"], &program, false, true);
    let output = common::c::host_command(&program)
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(output.status.success(), "cave_wall: {}", describe(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    let mut images = Vec::new();
    for eye in ["left", "right"] {
        let file = format!("cave_wall_{eye}.png");
        let image = image::open(dir.join(&file))
            .unwrap_or_else(|e| panic!("{file} is not a PNG: {e}"))
            .to_rgb8();
        assert_eq!(image.dimensions(), (256, 256));
        let lit = image
            .pixels()
            .filter(|p| p.0.iter().any(|&c| c > 20))
            .count();
        assert!(
            lit > 3000,
            "{eye} image shows almost no volume ({lit} lit pixels)"
        );
        let line = format!("wrote {file}: 256x256, the volume on {lit} pixels");
        assert!(stdout.contains(&line), "{stdout} lacks {line:?}");
        images.push(image);
    }
    assert_ne!(
        images[0], images[1],
        "the two eyes see the wall from the same place"
    );
}

/// Runs the cells benchmark host at 48^2 for two frames with `args`:
/// its JSON report and how many pixels of its first frame show.
fn bench_cells_small(name: &str, args: &[&std::ffi::OsStr]) -> (serde_json::Value, usize) {
    let dir = scratch(&format!("c_bench_cells_{name}"));
    let program = dir.join("bench_cells");
    compile(&["examples/c/bench_cells.c"], &program, false, true);
    let (json, ppm) = (dir.join("report.json"), dir.join("first.ppm"));
    let output = common::c::host_command(&program)
        .args(["--backend", "cpu", "--size", "48", "--frames", "2"])
        .args(args)
        .arg("--json")
        .arg(&json)
        .arg("--ppm")
        .arg(&ppm)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "bench_cells: {}",
        describe(&output)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["ms"].as_array().unwrap().len(), 2);
    let ppm = std::fs::read(&ppm).unwrap();
    // Past the header "P6\n48 48\n255\n": pixels not the background.
    let lit = ppm[ppm.len() - 48 * 48 * 3..]
        .chunks(3)
        .filter(|p| p.iter().any(|&c| c > 40))
        .count();
    (report, lit)
}

/// The benchmark host's AMR field (anari-visionaray's form) runs small
/// and shows the shells.
#[test]
fn the_cells_benchmark_host_reports_an_amr_field() {
    let args = ["--field", "amr", "--vertices", "17"].map(std::ffi::OsStr::new);
    let (report, lit) = bench_cells_small("amr", &args);
    assert_eq!(report["field"], "amr");
    assert!(lit > 48 * 48 / 10, "{lit} pixels show the shells");
}

/// The benchmark host's NanoVDB field (a grid the library wrote) runs
/// small, reports the grid's bytes and shows the fog.
#[test]
fn the_cells_benchmark_host_reports_a_nanovdb_grid() {
    let Some(written) = common::nanovdb::grids() else {
        return;
    };
    let blob = written.dir.join("fog16.blob");
    let args = [
        std::ffi::OsStr::new("--field"),
        "nanovdb".as_ref(),
        "--nvdb".as_ref(),
        blob.as_os_str(),
    ];
    let (report, lit) = bench_cells_small("nanovdb", &args);
    assert_eq!(report["field"], "nanovdb");
    assert_eq!(
        report["grid_bytes"].as_u64(),
        Some(std::fs::metadata(&blob).unwrap().len())
    );
    assert!(lit > 48 * 48 / 10, "{lit} pixels show the fog");
}

/// The unstructured benchmark host runs small: the grid and its
/// tetrahedra report their frames, first frame and peak memory, take
/// about the same samples and show about the same picture.
#[test]
fn the_cells_benchmark_host_reports_both_fields() {
    let dir = scratch("c_bench_cells");
    let program = dir.join("bench_cells");
    compile(&["examples/c/bench_cells.c"], &program, false, true);
    let mut runs = Vec::new();
    for field in ["structured", "unstructured"] {
        let args = ["--field", field, "--vertices", "12"].map(std::ffi::OsStr::new);
        let (report, lit) = bench_cells_small(field, &args);
        assert_eq!(report["benchmark"], "capi-cells");
        assert_eq!(report["field"], field);
        assert!(report["first_frame_ms"].as_f64().unwrap() > 0.0);
        assert!(report["peak_rss_mib"].as_f64().unwrap() > 1.0);
        let tets = report["tetrahedra"].as_u64().unwrap();
        assert_eq!(
            tets,
            if field == "structured" {
                0
            } else {
                6 * 11 * 11 * 11
            }
        );
        runs.push((report["last_frame_samples"].as_u64().unwrap(), lit));
    }
    let ((grid, grid_lit), (mesh, mesh_lit)) = (runs[0], runs[1]);
    eprintln!("samples {grid} / {mesh}, lit pixels {grid_lit} / {mesh_lit}");
    assert!(grid > 0 && grid_lit > 100, "the grid shows: {runs:?}");
    assert!(
        (mesh as f64 / grid as f64 - 1.0).abs() < 0.1,
        "the same samples: {runs:?}"
    );
    assert!(
        (mesh_lit as f64 / grid_lit as f64 - 1.0).abs() < 0.1,
        "the same picture: {runs:?}"
    );

    // Held still, the camera gives the same frame again, and the frames
    // at powers of two are written where a peer's accumulation is judged.
    let frames = dir.join("still");
    std::fs::create_dir_all(&frames).unwrap();
    let output = common::c::host_command(&program)
        .args(["--backend", "cpu", "--size", "32", "--vertices", "8"])
        .args(["--frames", "3", "--still", "1", "--renderer", "default"])
        .arg("--ppm-dir")
        .arg(&frames)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "bench_cells: {}",
        describe(&output)
    );
    let read = |n: u32| std::fs::read(frames.join(format!("frame_{n:04}.ppm"))).unwrap();
    assert_eq!(read(1), read(2), "a still camera renders the same frame");
    assert!(!frames.join("frame_0003.ppm").exists());
}

/// The benchmark host of examples/c/ runs small, writes its JSON with the
/// samples the device counted, and skipping changes the samples, not the
/// picture.
#[test]
fn the_shells_benchmark_host_reports_what_it_measured() {
    let dir = scratch("c_bench_shells");
    let program = dir.join("bench_shells");
    compile(&["examples/c/bench_shells.c"], &program, false, true);
    let mut runs = Vec::new();
    for skipping in ["1", "0"] {
        let json = dir.join(format!("skipping_{skipping}.json"));
        let ppm = dir.join(format!("skipping_{skipping}.ppm"));
        let output = common::c::host_command(&program)
            .args([
                "--backend",
                "cpu",
                "--size",
                "48",
                "--voxels",
                "32",
                "--frames",
                "2",
            ])
            .args(["--skipping", skipping, "--json"])
            .arg(&json)
            .arg("--ppm")
            .arg(&ppm)
            .output()
            .unwrap();
        assert!(
            output.status.success(),
            "bench_shells: {}",
            describe(&output)
        );
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(report["benchmark"], "capi-shells");
        assert_eq!(report["ms"].as_array().unwrap().len(), 2);
        assert!(report["machine"]["cpu"]
            .as_str()
            .is_some_and(|c| !c.is_empty()));
        assert_eq!(report["skipping"], skipping == "1");
        runs.push((
            report["last_frame_samples"].as_u64().unwrap(),
            std::fs::read(&ppm).unwrap(),
        ));
    }
    let ((on, on_image), (off, off_image)) = (&runs[0], &runs[1]);
    assert!(
        *on > 0 && on < off,
        "samples with skipping {on}, without {off}"
    );
    assert_eq!(on_image, off_image, "skipping changed the picture");
    let usage = common::c::host_command(&program)
        .args(["--frames", "0"])
        .output()
        .unwrap();
    assert_eq!(usage.status.code(), Some(2), "{}", describe(&usage));
}

/// The SDK test scenes' pattern: arrays on host memory are released, and
/// the memory overwritten and freed, before the objects using them are
/// committed. The device must have copied them at release; the image must
/// be the one the intact scene gives.
fn release_then_free(valgrind: bool) {
    let dir = scratch(if valgrind {
        "c_release_then_free_valgrind"
    } else {
        "c_release_then_free"
    });
    let scene = wall_scene(&dir, if valgrind { 32 } else { 64 }, phantom(), false);
    let program = dir.join("release_then_free");
    compile(&["tests/capi/c/release_then_free.c"], &program, false, true);
    let output = run(&program, &[&scene.file, &dir], valgrind);
    assert!(
        output.status.success(),
        "release_then_free: {}",
        describe(&output)
    );
    let image = read_rgba(&dir.join("freed.rgba"), scene.size);
    let s = ssim(&image, &scene.reference).unwrap();
    assert!(
        s > 0.98,
        "arrays freed after release: SSIM {s:.4} against the intact scene"
    );
}

#[test]
fn arrays_freed_after_release_still_render() {
    release_then_free(false);
}

#[test]
fn arrays_freed_after_release_are_never_read_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    release_then_free(true);
}

/// A volume read from the host's memory in place (tests/capi/c/in_place_host.c):
/// not copied while the host holds it (the field holds no bytes, and the
/// process grows by less than half the voxels), copied once when the host
/// releases the array while a frame renders it, and every image, before
/// and after the host frees its memory, the intact scene's.
fn in_place(valgrind: bool) {
    let dir = scratch(if valgrind {
        "c_in_place_valgrind"
    } else {
        "c_in_place"
    });
    // 160^3 floats (16 MB): large enough that a copy shows in the RSS.
    let n = if valgrind { 32 } else { 160 };
    let volume = (
        anari_library_caveray::data::shepp_logan(n),
        preset("phantom").unwrap(),
    );
    let scene = wall_scene(&dir, if valgrind { 32 } else { 64 }, volume, false);
    let program = dir.join("in_place_host");
    compile(&["tests/capi/c/in_place_host.c"], &program, false, true);
    let output = run(&program, &[&scene.file, &dir], valgrind);
    assert!(
        output.status.success(),
        "in_place_host: {}",
        describe(&output)
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("copies 1"), "{stdout}");
    let held = read_rgba(&dir.join("held.rgba"), scene.size);
    for name in ["held", "freed", "again"] {
        let image = read_rgba(&dir.join(format!("{name}.rgba")), scene.size);
        let s = ssim(&image, &scene.reference).unwrap();
        assert!(s > 0.98, "{name}: SSIM {s:.4} against the intact scene");
        assert_eq!(
            image.color, held.color,
            "{name} differs from the first image"
        );
    }
    if !valgrind {
        let numbers = |line: &str| -> Vec<i64> {
            line.split_whitespace()
                .filter_map(|w| w.parse().ok())
                .collect()
        };
        let line = stdout.lines().find(|l| l.starts_with("grew")).unwrap();
        let [grew, voxels] = numbers(line)[..] else {
            panic!("{line}")
        };
        assert!(
            grew < voxels / 2,
            "the process grew by {grew} KB for {voxels} KB of voxels: they were copied"
        );
    }
}

#[test]
fn a_shared_volume_is_read_in_place_and_copied_only_when_released() {
    in_place(false);
}

#[test]
fn a_shared_volume_freed_after_release_is_never_read_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    in_place(true);
}

/// A triangle mesh from the host's memory (tests/capi/c/in_place_mesh.c):
/// positions, indices and colors read in place (the geometry holds no
/// bytes), each copied once when the host releases it mid-render, and
/// the same image before, during and after.
fn in_place_mesh(valgrind: bool) {
    let dir = scratch(if valgrind {
        "c_in_place_mesh_valgrind"
    } else {
        "c_in_place_mesh"
    });
    let volume = (
        anari_library_caveray::data::shepp_logan(16),
        preset("phantom").unwrap(),
    );
    let scene = wall_scene(&dir, if valgrind { 32 } else { 64 }, volume, false);
    let program = dir.join("in_place_mesh");
    compile(&["tests/capi/c/in_place_mesh.c"], &program, false, true);
    let n = if valgrind { "12" } else { "96" };
    let output = run(
        &program,
        &[&scene.file, &dir, std::path::Path::new(n)],
        valgrind,
    );
    assert!(
        output.status.success(),
        "in_place_mesh: {}",
        describe(&output)
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("copies 3"), "{stdout}");
    let covered: u32 = stdout
        .lines()
        .find_map(|l| l.strip_prefix("covered "))
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or_else(|| panic!("no coverage in {stdout}"));
    assert!(covered >= 10, "the mesh covers {covered}% of the frame");
    let held = read_rgba(&dir.join("mesh_held.rgba"), scene.size);
    for name in ["mesh_freed", "mesh_again"] {
        let image = read_rgba(&dir.join(format!("{name}.rgba")), scene.size);
        assert_eq!(
            image.color, held.color,
            "{name} differs from the first image"
        );
    }
}

#[test]
fn a_shared_mesh_is_read_in_place_and_copied_only_when_released() {
    in_place_mesh(false);
}

#[test]
fn a_shared_mesh_freed_after_release_is_never_read_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    in_place_mesh(true);
}

/// Object parameters a commit refuses for their kind, each closing a loop
/// back to its own object (tests/capi/c/refused_cycle.c): the refusal says
/// the parameter was unset, every refused array's deleter runs once its
/// handle goes, and the group renders with a valid array afterwards.
fn refused_cycle(valgrind: bool) {
    let dir = scratch(if valgrind {
        "c_refused_cycle_valgrind"
    } else {
        "c_refused_cycle"
    });
    let program = dir.join("refused_cycle");
    compile(&["tests/capi/c/refused_cycle.c"], &program, false, true);
    let output = run(&program, &[], valgrind);
    let text = describe(&output);
    assert!(output.status.success(), "refused_cycle: {text}");
    assert!(!text.contains("FAIL"), "refused_cycle: {text}");
    let passed = text.matches("PASS").count();
    assert!(
        passed >= 20,
        "only {passed} refused_cycle checks ran: {text}"
    );
}

#[test]
fn refused_object_parameters_keep_nothing_alive() {
    refused_cycle(false);
}

#[test]
fn refused_object_parameters_leak_nothing_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    refused_cycle(true);
}

/// An OpenCOVER-style host (tests/capi/c/opencover_host.c): the call sequence
/// its plug-in makes, rendered 64 times unchanged; color (sRGB) and depth
/// must be the Rust API's for the same wall and eye.
fn opencover(valgrind: bool) {
    use anari_library_caveray::render::{
        ColorData, ColorFormat, CpuRenderer, Frame, FrameDesc, RenderSettings,
    };
    let dir = scratch(if valgrind {
        "c_opencover_valgrind"
    } else {
        "c_opencover"
    });
    let scene = wall_scene(&dir, if valgrind { 32 } else { 64 }, phantom(), false);
    let program = dir.join("opencover_host");
    compile(&["tests/capi/c/opencover_host.c"], &program, false, true);
    let output = common::c::run_with(
        &program,
        &[&scene.file, &dir],
        valgrind,
        &[("ANARI_LIBRARY", "caveray")],
    );
    assert!(
        output.status.success(),
        "opencover_host: {}",
        describe(&output)
    );

    let desc = FrameDesc::new(scene.size)
        .with_color(ColorFormat::Srgba8)
        .with_depth();
    let reference = CpuRenderer::new()
        .render(&scene.scene, &scene.rays, &RenderSettings::default(), &desc)
        .unwrap();
    let bytes = std::fs::read(dir.join("opencover.rgba")).unwrap();
    let image = Frame {
        size: scene.size,
        color: ColorData::Srgba8(bytes),
        depth: None,
        hits: None,
        samples: 0,
    };
    let s = ssim(&image, &reference).unwrap();
    assert!(
        s > 0.98,
        "OpenCOVER-style sRGB image: SSIM {s:.4} against the Rust API's"
    );

    let depth: Vec<f32> = std::fs::read(dir.join("opencover.depth"))
        .unwrap()
        .chunks_exact(4)
        .map(|c| f32::from_ne_bytes(c.try_into().unwrap()))
        .collect();
    let want = reference.depth.as_ref().unwrap();
    let (mut hits, mut disagree, mut worst) = (0, 0, 0.0f32);
    for (a, b) in depth.iter().zip(want) {
        match (a.is_finite(), b.is_finite()) {
            (true, true) => {
                hits += 1;
                worst = worst.max((a - b).abs() / b);
            }
            (false, false) => {}
            _ => disagree += 1,
        }
    }
    // The phantom is translucent: only its denser parts pass the depth
    // threshold (0.5 accumulated opacity), but those must agree.
    assert!(hits >= 20, "only {hits} pixels have a depth");
    assert!(
        disagree * 100 < depth.len(),
        "{disagree} pixels disagree on hitting anything"
    );
    assert!(
        worst < 0.02,
        "depth differs by {:.2}% from the Rust API's",
        100.0 * worst
    );
    // And as OpenCOVER uses it (eye + unit ray * depth), every depth is a
    // point inside the volume's box, past the first sample.
    let (lo, hi) = scene.scene.bounds();
    let slack = 1e-3 * (hi - lo).max_element();
    for (i, d) in depth.iter().enumerate().filter(|(_, d)| d.is_finite()) {
        let (x, y) = (i as u32 % scene.size.x, i as u32 / scene.size.x);
        let (origin, dir) = scene.rays.pixel_ray(x, y);
        let p = origin + dir * *d;
        assert!(
            p.cmpge(lo - slack).all() && p.cmple(hi + slack).all(),
            "pixel ({x}, {y}): depth {d} puts the volume at {p}, outside {lo}..{hi}"
        );
    }
}

#[test]
fn opencover_style_host_renders_a_wall_channel() {
    opencover(false);
}

#[test]
fn opencover_style_host_is_clean_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    opencover(true);
}

/// OpenCOVER's two channels of one wall (tests/capi/c/pair_host.c): each eye
/// a frame of its own, rendered one after the other, without and then
/// with the device pairing them into one re-projection pass.
fn pair_host(valgrind: bool) -> std::path::PathBuf {
    use anari_library_caveray::cave::Eye;
    let dir = scratch(if valgrind {
        "c_pair_host_valgrind"
    } else {
        "c_pair_host"
    });
    let scene = wall_scene(&dir, if valgrind { 24 } else { 128 }, phantom(), true);
    let rig = common::rig("cologne_5wall");
    let head = rig.viewer.head;
    let baseline = rig.eye_position(&head, Eye::Right) - rig.eye_position(&head, Eye::Left);
    let baseline = format!("{},{},{}", baseline.x, baseline.y, baseline.z);
    let program = dir.join("pair_host");
    compile(&["tests/capi/c/pair_host.c"], &program, false, true);
    let backend = if valgrind { "cpu" } else { "gpu" };
    let output = common::c::run_with(
        &program,
        &[&scene.file, &dir, std::path::Path::new(&baseline)],
        valgrind,
        &[("ANARI_LIBRARY", "caveray"), ("CAVERAY_BACKEND", backend)],
    );
    assert!(output.status.success(), "pair_host: {}", describe(&output));
    eprint!("{}", String::from_utf8_lossy(&output.stdout));
    dir
}

#[test]
fn opencover_style_eyes_as_two_frames_come_from_one_pass() {
    use anari_library_caveray::render::dssim;
    let dir = pair_host(false);
    let size = glam::UVec2::splat(128);
    let image = |name: &str| read_rgba(&dir.join(format!("{name}.rgba")), size);
    let (left, right) = (image("alone_left"), image("alone_right"));
    // The first eye is the image it renders alone, byte for byte; the
    // second within the re-projection's bound (DSSIM 0.02).
    assert_eq!(image("paired_left").color, left.color);
    assert_eq!(image("named_left").color, left.color);
    let unmoved = dssim(&left, &right).unwrap();
    for name in ["paired_right", "named_right"] {
        let d = dssim(&image(name), &right).unwrap();
        eprintln!("{name}: DSSIM {d:.4} against its own pass (left as right {unmoved:.4})");
        assert!(
            d < 0.02 && d < 0.5 * unmoved,
            "{name}: DSSIM {d} vs {unmoved}"
        );
    }
}

#[test]
fn opencover_style_paired_frames_are_clean_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    // The CPU reference renders each eye alone; what counts here is that
    // frames naming each other as partners are freed.
    let dir = pair_host(true);
    let size = glam::UVec2::splat(24);
    let image = |name: &str| read_rgba(&dir.join(format!("{name}.rgba")), size);
    assert_eq!(image("named_right").color, image("alone_right").color);
}

/// Inputs that would abort or hang the host without the budgets
/// (tests/capi/c/budgets.c): a
/// 100000 x 100000 frame, step factors of 1e-6 and 1e-30, eyes at
/// infinity and NaN, an array of strings, and releasing a frame or the
/// device while a minutes-long render runs.
fn budgets(valgrind: bool) {
    let dir = scratch(if valgrind {
        "c_budgets_valgrind"
    } else {
        "c_budgets"
    });
    let program = dir.join("budgets");
    compile(&["tests/capi/c/budgets.c"], &program, false, true);
    // The CPU reference, where a release must interrupt a running render.
    let output = common::c::run_with(&program, &[], valgrind, &[("CAVERAY_BACKEND", "cpu")]);
    let text = describe(&output);
    assert!(output.status.success(), "budgets: {text}");
    assert!(!text.contains("FAIL"), "budgets: {text}");
    assert!(text.matches("PASS").count() >= 14, "budgets: {text}");
    assert!(
        text.contains("the released device's render stopped"),
        "budgets: {text}"
    );
}

#[test]
fn inputs_beyond_the_budgets_are_errors_not_aborts() {
    budgets(false);
}

#[test]
fn inputs_beyond_the_budgets_are_clean_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    budgets(true);
}

/// Every data type the ANARI SDK's header declares is in caveray's, with
/// the SDK's number, and the device takes or refuses each by its name.
#[test]
fn every_sdk_data_type_is_declared_and_named() {
    let dir = scratch("c_data_types");
    let program = dir.join("data_types");
    compile(&["tests/capi/c/data_types.c"], &program, false, true);
    let output = run(&program, &[], false);
    let text = describe(&output);
    assert!(output.status.success(), "data types: {text}");
    assert!(!text.contains("FAIL"), "data types: {text}");
    let passed = text.matches("PASS").count();
    assert!(passed > 134 + 2 * 100, "only {passed} checks ran: {text}");
}
