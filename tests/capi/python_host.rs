//! A Python host through pynari (PyPI) and the SDK loader it bundles: the
//! scenes of `python/volume_host.py` (a grid) and
//! `python/unstructured_host.py` (one hexahedron) on each backend against
//! the Rust API's image of the same numbers. scripts/deps makes the virtual environment
//! (target/pynari); CAVERAY_PYTHON may name another interpreter with
//! pynari and numpy.

use std::path::{Path, PathBuf};

use anari_library_caveray::geometry::{ImageRegion, PinholeCamera, PrimaryRays};
use anari_library_caveray::render::{
    ssim, BackgroundImage, CpuRenderer, FrameDesc, Render as _, RenderSettings,
};
use anari_library_caveray::scene::{Scene, StructuredVolume, TransferFunction, Voxels};
use glam::{DVec3, UVec2, UVec3, Vec3, Vec4};
use serde_json::json;

use crate::common;
use crate::common::c::{crop, describe, host_command, read_rgba, root, scratch};

fn python() -> Option<PathBuf> {
    let path = std::env::var_os("CAVERAY_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target/pynari/bin/python"));
    path.exists().then_some(path)
}

/// Runs `tests/capi/python/SCRIPT` with the scene file and output path on
/// `backend`, and checks that it succeeded and that caveray said no error
/// or warning: its status messages reach the host's callback, which
/// pynari prints as "caveray: <severity>: ...".
fn run_host(python: &Path, script: &str, scene: &Path, out: &Path, backend: &str) {
    let output = host_command(python)
        .arg(root().join("tests/capi/python").join(script))
        .arg(scene)
        .arg(out)
        .env("ANARI_LIBRARY", "caveray")
        .env("CAVERAY_BACKEND", backend)
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .expect("python runs");
    let text = describe(&output);
    assert!(output.status.success(), "{script} on {backend}: {text}");
    for severity in ["Error", "Warning", "Fatal"] {
        assert!(
            !text.contains(&format!("caveray: {severity}")),
            "{script} on {backend}: {text}"
        );
    }
}

/// Two interlocking tori on [-1, 1]^3: 1 on the rings, 0 beyond `minor`.
fn tori(n: u32) -> Vec<f32> {
    let at = |i: u32| -1.0 + 2.0 * i as f32 / (n - 1) as f32;
    let (major, minor) = (0.5f32, 0.2f32);
    let mut v = Vec::with_capacity((n * n * n) as usize);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let (x, y, z) = (at(x), at(y), at(z));
                let a = (((x + 0.25).hypot(y) - major).hypot(z)).min(1.0);
                let b = (((x - 0.25).hypot(z) - major).hypot(y)).min(1.0);
                v.push((1.0 - a.min(b) / minor).clamp(0.0, 1.0));
            }
        }
    }
    v
}

#[test]
fn a_pynari_host_renders_what_the_rust_api_renders_on_each_backend() {
    let Some(python) = python() else {
        common::missing("pynari's virtual environment (target/pynari, made by scripts/deps)");
        return;
    };
    let dir = scratch("python_host");
    let n = 32;
    let voxels = tori(n);
    let raw = dir.join("tori.f32");
    std::fs::write(
        &raw,
        voxels
            .iter()
            .flat_map(|v| v.to_ne_bytes())
            .collect::<Vec<u8>>(),
    )
    .unwrap();
    let size = UVec2::new(96, 72);
    let colors = [
        [0.1f32, 0.2, 0.6, 0.0],
        [0.2, 0.6, 1.0, 0.3],
        [1.0, 0.7, 0.2, 1.0],
    ];
    let gradient = [[0.9f32, 0.9, 0.9, 1.0], [0.15, 0.25, 0.8, 1.0]];
    let (position, fovy, unit) = ([0.4f32, 0.8, 2.6], 0.8f32, 0.05f32);
    let spacing = 2.0 / (n - 1) as f32;
    let scene = json!({
        "voxels": raw,
        "dims": [n, n, n],
        "origin": [-1.0, -1.0, -1.0],
        "spacing": [spacing, spacing, spacing],
        "colors": colors,
        "unit_distance": unit,
        "position": position,
        "direction": position.map(|x| -x),
        "up": [0.0, 1.0, 0.0],
        "fovy": fovy,
        "size": [size.x, size.y],
        "gradient": gradient,
        // A scene of metres: the tori 2 m across, 3 m away, eyes 63.5 mm
        // apart.
        "stereo": {"ipd": 0.0635, "modes": ["left", "right", "sideBySide", "topBottom"]},
    });
    let scene_file = dir.join("scene.json");
    std::fs::write(&scene_file, scene.to_string()).unwrap();

    // The same numbers through the Rust API, on the CPU reference.
    let volume = StructuredVolume::new(
        UVec3::splat(n),
        Voxels::F32(voxels.into()),
        Vec3::splat(-1.0),
        Vec3::splat(spacing),
    )
    .unwrap();
    let tf = TransferFunction::new(
        colors.iter().map(|c| Vec4::from_array(*c)).collect(),
        vec![1.0],
        (0.0, 1.0),
        unit,
    )
    .unwrap();
    let eye = DVec3::from_array(position.map(f64::from));
    let camera = PinholeCamera::new(
        eye,
        -eye,
        DVec3::Y,
        f64::from(fovy),
        f64::from(size.x) / f64::from(size.y),
        ImageRegion::FULL,
    )
    .unwrap();
    let settings = RenderSettings {
        background_image: Some(std::sync::Arc::new(
            BackgroundImage::new(
                UVec2::new(1, 2),
                gradient.iter().map(|c| Vec4::from_array(*c)).collect(),
            )
            .unwrap(),
        )),
        ..RenderSettings::default()
    };
    let reference = CpuRenderer::new()
        .render(
            &Scene::new(volume, tf),
            &camera.ray_gen(size),
            &settings,
            &FrameDesc::new(size),
        )
        .unwrap();

    for backend in ["cpu", "gpu"] {
        let out = dir.join(format!("{backend}.rgba"));
        run_host(&python, "volume_host.py", &scene_file, &out, backend);
        let image = read_rgba(&out, size);
        let s = ssim(&image, &reference).unwrap();
        println!("{backend}: SSIM {s:.4} against the Rust API's image");
        assert!(
            s >= 0.99,
            "{backend}: SSIM {s:.4} against the Rust API's image"
        );
        // Not the background alone: the tori cover part of the frame.
        let differs = (0..size.x * size.y)
            .filter(|i| {
                let (x, y) = (i % size.x, i / size.x);
                (image.pixel(x, y) - settings.background_image.as_ref().unwrap().at(x, y, size))
                    .abs()
                    .max_element()
                    > 0.1
            })
            .count();
        assert!(
            differs > 500,
            "{backend}: the volume shows on {differs} pixels"
        );
        stereo_modes(&out, size, &settings, backend);
    }
}

/// The stereo modes the host rendered beside `out`: every eye shows the
/// tori, the eyes differ, and a sideBySide half is its eye's own image
/// (the vertical gradient is the same in both halves; exactly so on the
/// CPU, where the halves are two passes).
fn stereo_modes(out: &std::path::Path, size: UVec2, settings: &RenderSettings, backend: &str) {
    let background = settings.background_image.as_ref().unwrap();
    let read =
        |mode: &str, frame: UVec2| read_rgba(&out.with_extension(format!("{mode}.rgba")), frame);
    let modes = [
        ("left", size, vec![UVec2::ZERO]),
        ("right", size, vec![UVec2::ZERO]),
        (
            "sideBySide",
            UVec2::new(2 * size.x, size.y),
            vec![UVec2::ZERO, UVec2::new(size.x, 0)],
        ),
        (
            "topBottom",
            UVec2::new(size.x, 2 * size.y),
            vec![UVec2::new(0, size.y), UVec2::ZERO],
        ),
    ];
    let mut eyes = Vec::new();
    for (mode, frame, corners) in modes {
        let image = read(mode, frame);
        for corner in corners {
            // The tori against the background where the frame holds it.
            let differs = (0..size.x * size.y)
                .filter(|i| {
                    let (x, y) = (corner.x + i % size.x, corner.y + i / size.x);
                    (image.pixel(x, y) - background.at(x, y, frame))
                        .abs()
                        .max_element()
                        > 0.1
                })
                .count();
            assert!(
                differs > 500,
                "{backend} {mode} eye at {corner}: the volume shows on {differs} pixels"
            );
        }
        eyes.push(image);
    }
    assert_ne!(
        eyes[0].color, eyes[1].color,
        "{backend}: the eyes are equal"
    );
    let half = |x0: u32| crop(&eyes[2], UVec2::new(x0, 0), size);
    for (x0, eye) in [(0, &eyes[0]), (size.x, &eyes[1])] {
        let s = ssim(&half(x0), eye).unwrap();
        println!("{backend}: sideBySide half at x {x0}: SSIM {s:.5} against its eye alone");
        assert!(s > 0.98, "{backend}: sideBySide half at x {x0}: SSIM {s}");
        if backend == "cpu" {
            assert_eq!(
                half(x0).color,
                eye.color,
                "{backend}: sideBySide half at x {x0}"
            );
        }
    }
}

/// pynari's host of one unstructured hexahedron (python/unstructured_host.py),
/// `cell.type` as UINT32, on each backend, against the Rust API's image of
/// the same cell.
#[test]
fn a_pynari_host_renders_an_unstructured_hexahedron() {
    use anari_library_caveray::scene::{MeshInput, MeshValues, UnstructuredVolume};
    let Some(python) = python() else {
        common::missing("pynari's virtual environment (target/pynari, made by scripts/deps)");
        return;
    };
    let dir = scratch("python_unstructured_host");
    // A skewed hexahedron, so that its inverse map needs Newton's steps.
    let corners: [[f32; 3]; 8] = [
        [-1.0, -1.0, -1.0],
        [1.0, -0.8, -1.0],
        [0.9, 1.0, -0.9],
        [-1.0, 0.8, -1.0],
        [-0.9, -1.0, 1.0],
        [1.0, -1.0, 0.8],
        [1.0, 1.0, 1.0],
        [-0.8, 1.0, 1.0],
    ];
    let values = [0.0f32, 0.2, 1.0, 0.4, 0.3, 0.6, 0.9, 0.1];
    let size = UVec2::new(64, 64);
    let colors = [[0.1f32, 0.2, 0.6, 0.0], [1.0, 0.7, 0.2, 1.0]];
    let (position, fovy, unit) = ([1.2f32, 1.6, 3.8], 0.8f32, 0.5f32);
    let scene = json!({
        "corners": corners,
        "values": values,
        "colors": colors,
        "unit_distance": unit,
        "position": position,
        "direction": position.map(|x| -x),
        "up": [0.0, 1.0, 0.0],
        "fovy": fovy,
        "size": [size.x, size.y],
    });
    let scene_file = dir.join("scene.json");
    std::fs::write(&scene_file, scene.to_string()).unwrap();

    let mesh = UnstructuredVolume::new(
        MeshInput {
            positions: corners.iter().map(|c| Vec3::from_array(*c)).collect(),
            index: (0..8).collect(),
            cell_index: vec![0],
            cell_type: vec![12],
        },
        MeshValues::PerVertex(values.to_vec()),
    )
    .unwrap();
    let tf = TransferFunction::new(
        colors.iter().map(|c| Vec4::from_array(*c)).collect(),
        vec![1.0],
        (0.0, 1.0),
        unit,
    )
    .unwrap();
    let eye = DVec3::from_array(position.map(f64::from));
    let camera = PinholeCamera::new(
        eye,
        -eye,
        DVec3::Y,
        f64::from(fovy),
        f64::from(size.x) / f64::from(size.y),
        ImageRegion::FULL,
    )
    .unwrap();
    let reference = CpuRenderer::new()
        .render(
            &Scene::new(mesh, tf),
            &camera.ray_gen(size),
            &RenderSettings::default(),
            &FrameDesc::new(size),
        )
        .unwrap();
    let lit = |f: &anari_library_caveray::render::Frame| {
        (0..size.x * size.y)
            .filter(|i| f.pixel(i % size.x, i / size.x).truncate().max_element() > 0.1)
            .count()
    };
    assert!(lit(&reference) > 300, "the cell covers part of the frame");
    for backend in ["cpu", "gpu"] {
        let out = dir.join(format!("{backend}.rgba"));
        run_host(&python, "unstructured_host.py", &scene_file, &out, backend);
        let image = read_rgba(&out, size);
        let s = ssim(&image, &reference).unwrap();
        println!(
            "{backend}: SSIM {s:.4} against the Rust API's image, {} pixels lit",
            lit(&image)
        );
        assert!(
            s >= 0.99,
            "{backend}: SSIM {s:.4} against the Rust API's image"
        );
    }
}

/// The directory of the ANARI SDK loader (libanari.so.0) pynari bundles.
fn sdk_loader_dir(python: &std::path::Path) -> Option<PathBuf> {
    let out = std::process::Command::new(python)
        .args([
            "-c",
            "import os, pynari; print(os.path.dirname(pynari.__file__))",
        ])
        .output()
        .ok()?;
    let dir = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
    dir.join("libanari.so.0").exists().then_some(dir)
}

/// The OpenCOVER-style host of `c/unstructured_host.c`, linked to the SDK's
/// own loader instead of to caveray: `anariLoadLibrary("caveray")` then
/// finds the device library by name, and every call goes through the
/// loader's dispatch.
#[test]
fn the_unstructured_host_renders_through_the_sdk_loader() {
    let Some(python) = python() else {
        common::missing("pynari's virtual environment (target/pynari, made by scripts/deps)");
        return;
    };
    let Some(loader) = sdk_loader_dir(&python) else {
        panic!("pynari has no libanari.so.0 beside it: the SDK loader it bundles moved");
    };
    let dir = scratch("unstructured_host_sdk_loader");
    let program = dir.join("unstructured_host");
    let output = std::process::Command::new("cc")
        .current_dir(root())
        .args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-g", "-Iinclude"])
        .arg("tests/capi/c/unstructured_host.c")
        .arg("-o")
        .arg(&program)
        .arg(format!("-L{}", loader.display()))
        .arg("-l:libanari.so.0")
        .arg(format!("-Wl,-rpath,{}", loader.display()))
        .output()
        .expect("a C compiler (cc) is installed");
    assert!(output.status.success(), "cc: {}", describe(&output));
    let linked = std::process::Command::new("ldd")
        .arg(&program)
        .output()
        .expect("ldd runs");
    let linked = String::from_utf8_lossy(&linked.stdout);
    assert!(
        linked.contains("libanari.so.0") && !linked.contains("libanari_library_caveray"),
        "the host is linked to the loader alone:\n{linked}"
    );
    let output = host_command(&program).output().expect("the host runs");
    let text = describe(&output);
    assert!(output.status.success(), "unstructured host: {text}");
    assert!(!text.contains("FAIL"), "unstructured host: {text}");
    assert!(
        text.matches("PASS").count() >= 8,
        "unstructured host: {text}"
    );
}
