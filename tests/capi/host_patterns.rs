//! Host programs in C for the call patterns of VTK/ParaView, the SDK's
//! viewer and the conformance tests (tests/capi/c/{vtk,viewer,cts}_host.c), and
//! one using the perspective camera's stereo modes (stereo_host.c),
//! from what HOSTS.md says each sends. Each must render without a warning
//! or error, and its images must be the Rust API's for the same scene, or
//! the analytic answer.

use crate::common;

use std::path::Path;
use std::sync::Arc;

use anari_library_caveray::geometry::{ImageRegion, PinholeCamera, PrimaryRays};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ssim, BackgroundImage, ColorData, CpuRenderer, Frame, FrameDesc, RenderSettings,
};
use anari_library_caveray::scene::{
    Filter, ObjectIds, PlacedVolume, Scene, StructuredVolume, TransferFunction, Voxels,
};
use common::c::{
    compile, crop, describe, phantom, read_rgba, run_with, scratch, valgrind_available, wall_scene,
};
use common::missing;
use glam::{DVec3, Mat4, UVec2, UVec3, Vec3, Vec4};

fn floats(path: &Path) -> Vec<f32> {
    std::fs::read(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .chunks_exact(4)
        .map(|c| f32::from_ne_bytes(c.try_into().unwrap()))
        .collect()
}

fn float_frame(path: &Path, size: UVec2) -> Frame {
    Frame {
        size,
        color: ColorData::Rgba32F(floats(path)),
        depth: None,
        hits: None,
        samples: 0,
    }
}

/// Builds and runs `tests/capi/c/<name>.c` in a fresh directory; fails with
/// its output unless it exits 0.
fn run_host(
    name: &str,
    valgrind: bool,
    args: &dyn Fn(&Path) -> Vec<std::path::PathBuf>,
) -> std::path::PathBuf {
    let dir = scratch(&format!(
        "{name}{}",
        if valgrind { "_valgrind" } else { "" }
    ));
    let program = dir.join(name);
    compile(&[&format!("tests/capi/c/{name}.c")], &program, false, true);
    let args = args(&dir);
    let args: Vec<&Path> = args.iter().map(|p| p.as_path()).collect();
    let output = run_with(&program, &args, valgrind, &[("ANARI_LIBRARY", "caveray")]);
    assert!(output.status.success(), "{name}: {}", describe(&output));
    dir
}

/// VTK: two datasets, each in a group placed by a transform instance (one
/// shrunk about the scene's centre, one turned, shrunk and moved: they
/// overlap), a constant field with valueRange lo == hi, no unitDistance,
/// a 1 x 2 gradient background, `name` on every commit.
fn vtk(valgrind: bool) {
    let scratch_dir = scratch(if valgrind {
        "vtk_scene_valgrind"
    } else {
        "vtk_scene"
    });
    let wall = wall_scene(
        &scratch_dir,
        if valgrind { 32 } else { 64 },
        phantom(),
        false,
    );
    let first = &wall.scene.volumes()[0];
    let (lo, hi) = first.volume.bounds();
    let (centre, extent) = (0.5 * (lo + hi), (hi - lo).max_element());
    let shrink = Mat4::from_translation(centre)
        * Mat4::from_scale(Vec3::splat(0.7))
        * Mat4::from_translation(-centre);
    let turn = Mat4::from_translation(centre + Vec3::new(0.25 * extent, 0.0, 0.0))
        * Mat4::from_rotation_y(0.5)
        * Mat4::from_scale(Vec3::splat(0.45))
        * Mat4::from_translation(-centre);
    let transforms: Vec<String> = [shrink, turn]
        .iter()
        .flat_map(|m| m.to_cols_array())
        .map(|x| format!("{x:.9e}"))
        .collect();
    let transforms_file = scratch_dir.join("transforms.txt");
    std::fs::write(&transforms_file, transforms.join("\n")).unwrap();
    let dir = run_host("vtk_host", valgrind, &|dir| {
        vec![
            wall.file.clone(),
            transforms_file.clone(),
            dir.to_path_buf(),
        ]
    });

    // The same scene through the Rust API.
    let table = first.transfer_function.table();
    let (vlo, vhi) = first.transfer_function.value_range();
    let colors: Vec<Vec4> = table.iter().map(|c| c.truncate().extend(1.0)).collect();
    let alphas: Vec<f32> = table.iter().map(|c| c.w).collect();
    // No unitDistance: the default, 1.
    let phantom_tf = TransferFunction::new(colors, alphas, (vlo, vhi), 1.0).unwrap();
    let v = &first.volume;
    let cells = v.spacing() * (v.dims() - UVec3::ONE).as_vec3() / 3.0;
    let constant = StructuredVolume::new(
        UVec3::splat(4),
        Voxels::F32(vec![0.5; 64].into()),
        v.origin(),
        cells,
    )
    .unwrap();
    // lo == hi = 0.5 widened by 1e-3: the value maps to the middle.
    let haze_tf = TransferFunction::new(
        vec![Vec4::new(0.1, 0.4, 1.0, 1.0), Vec4::new(1.0, 0.8, 0.1, 1.0)],
        vec![0.002, 0.002],
        (0.499, 0.501),
        1.0,
    )
    .unwrap();
    let scene = Scene::placed(vec![
        PlacedVolume {
            volume: Arc::clone(v),
            transfer_function: Arc::new(phantom_tf),
            transform: shrink,
            ids: ObjectIds::NONE,
        },
        PlacedVolume {
            volume: Arc::new(constant.into()),
            transfer_function: Arc::new(haze_tf),
            transform: turn,
            ids: ObjectIds::NONE,
        },
    ])
    .unwrap();
    let gradient = BackgroundImage::new(
        UVec2::new(1, 2),
        vec![Vec4::new(0.1, 0.1, 0.3, 1.0), Vec4::new(0.0, 0.0, 0.0, 1.0)],
    )
    .unwrap();
    let settings = RenderSettings {
        background_image: Some(Arc::new(gradient)),
        ..Default::default()
    };
    let reference = CpuRenderer::new()
        .render(&scene, &wall.rays, &settings, &FrameDesc::new(wall.size))
        .unwrap();
    let image = read_rgba(&dir.join("vtk.rgba"), wall.size);
    let s = ssim(&image, &reference).unwrap();
    eprintln!("VTK-style host: SSIM {s:.5} against the Rust API");
    assert!(s > 0.98, "VTK-style host: SSIM {s:.4} against the Rust API");
    // Both datasets are there: without either, the image is another.
    for (i, alone) in scene.volumes().iter().enumerate() {
        let one = Scene::placed(vec![alone.clone()]).unwrap();
        let other = CpuRenderer::new()
            .render(&one, &wall.rays, &settings, &FrameDesc::new(wall.size))
            .unwrap();
        let s = ssim(&image, &other).unwrap();
        assert!(
            s < 0.97,
            "volume {i} alone is as close ({s:.4}): the other is missing"
        );
    }
    // The second update (every object named and committed again) renders
    // the same image.
    let again = std::fs::read(dir.join("vtk2.rgba")).unwrap();
    assert_eq!(again, std::fs::read(dir.join("vtk.rgba")).unwrap());
}

#[test]
fn vtk_style_host_renders_instanced_volumes_over_a_gradient() {
    vtk(false);
}

#[test]
fn vtk_style_host_is_clean_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    vtk(true);
}

/// The conformance tests' volume cases on an 8^3 ramp over [-1, 1]^3.
fn cts(valgrind: bool) {
    let dir = run_host("cts_host", valgrind, &|dir| vec![dir.to_path_buf()]);
    let bounds = std::fs::read_to_string(dir.join("cts.bounds")).unwrap();
    let bounds: Vec<f32> = bounds
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(bounds, [-1.0, -1.0, -1.0, 1.0, 1.0, 1.0]);
    let cam = floats(&dir.join("cts.camera"));
    let v3 = |i: usize| DVec3::new(cam[i].into(), cam[i + 1].into(), cam[i + 2].into());
    let camera = PinholeCamera::new(
        v3(0),
        v3(3),
        v3(6),
        cam[9].into(),
        cam[10].into(),
        ImageRegion::FULL,
    )
    .unwrap();
    let size = UVec2::splat(33);

    // One color (1, 0.5, 0.25), opacity 0.05 per 0.1 units: through the
    // centre, 2 units of box.
    let single = float_frame(&dir.join("cts_single.color"), size);
    let centre = single.pixel(16, 16);
    let alpha = 1.0 - 0.95f64.powf(2.0 / 0.1);
    assert!(
        (f64::from(centre.w) - alpha).abs() < 1e-3,
        "alpha {} vs {alpha}",
        centre.w
    );
    let want = Vec3::new(1.0, 0.5, 0.25) * centre.w;
    assert!(
        (centre.truncate() - want).abs().max_element() < 1e-4,
        "{centre} vs {want}"
    );
    assert_eq!(
        single.pixel(0, 0),
        Vec4::ZERO,
        "the corner sees only the background"
    );
    // Depth: where the accumulated opacity passes 0.5, after k steps of
    // 1/7 from the entry, sampled at their middles, measured from the eye.
    let step = 1.0 / 7.0;
    let a_s = 1.0 - 0.95f64.powf(step / 0.1);
    let k = (0.5f64.ln() / (1.0 - a_s).ln()).ceil();
    let entry = f64::from(cam[2]) - 1.0;
    let depth = floats(&dir.join("cts_single.depth"))[16 * 33 + 16];
    let want = entry + (k - 0.5) * step;
    assert!(
        (f64::from(depth) - want).abs() < 1e-3,
        "depth {depth}, want {want}"
    );

    // The color map, nearest then linear: each as the Rust API renders it,
    // and not each other.
    let ramp: Vec<f32> = (0..512).map(|i| (i % 8) as f32 / 7.0).collect();
    let tf = Arc::new(
        TransferFunction::new(
            vec![Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::new(0.0, 0.0, 1.0, 1.0)],
            vec![0.05, 0.05],
            (0.0, 1.0),
            0.1,
        )
        .unwrap(),
    );
    let rays = camera.ray_gen(size);
    let settings = RenderSettings {
        background: Vec4::ZERO,
        ..Default::default()
    };
    let desc = FrameDesc::new(size).with_color(anari_library_caveray::render::ColorFormat::Rgba32F);
    let mut images = Vec::new();
    for (filter, file) in [
        (Filter::Nearest, "cts_nearest.color"),
        (Filter::Linear, "cts_linear.color"),
    ] {
        let volume = StructuredVolume::new(
            UVec3::splat(8),
            Voxels::F32(ramp.clone().into()),
            Vec3::NEG_ONE,
            Vec3::splat(2.0 / 7.0),
        )
        .unwrap()
        .with_filter(filter);
        let reference = CpuRenderer::new()
            .render(
                &Scene::shared(Arc::new(volume.into()), Arc::clone(&tf)),
                &rays,
                &settings,
                &desc,
            )
            .unwrap();
        let image = float_frame(&dir.join(file), size);
        let worst = image
            .to_linear()
            .iter()
            .zip(reference.to_linear())
            .map(|(a, b)| (*a - b).abs().max_element())
            .fold(0.0, f32::max);
        assert!(
            worst < 2e-3,
            "{filter:?}: off the Rust API's image by {worst}"
        );
        images.push(image);
    }
    let apart = images[0]
        .to_linear()
        .iter()
        .zip(images[1].to_linear())
        .map(|(a, b)| (*a - b).abs().max_element())
        .fold(0.0, f32::max);
    assert!(apart > 0.02, "nearest and linear differ by {apart} only");
}

#[test]
fn cts_style_host_matches_the_analytic_answers() {
    cts(false);
}

#[test]
fn cts_style_host_is_clean_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    cts(true);
}

/// The SDK viewer: orthographic, accumulation, NO_WAIT polling, a discard
/// mid-render. Inside the box's shadow (the inner half of the image) every
/// ray sees 2 units of opacity 0.5: alpha 0.75 over the background.
fn viewer(valgrind: bool) {
    let dir = run_host("viewer_host", valgrind, &|dir| vec![dir.to_path_buf()]);
    let size = UVec2::splat(64);
    let bytes = std::fs::read(dir.join("viewer.rgba")).unwrap();
    let image = Frame {
        size,
        color: ColorData::Srgba8(bytes),
        depth: None,
        hits: None,
        samples: 0,
    };
    let (a, bg) = (0.75f32, Vec3::splat(0.1));
    let inside = Vec3::new(0.2, 0.8, 0.4) * a + bg * (1.0 - a);
    let srgb8 = |c: f32| {
        let s = if c <= 0.003_130_8 {
            12.92 * c
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0).round()
    };
    for (x, y, want) in [(32, 32, inside), (20, 40, inside), (2, 2, bg), (60, 33, bg)] {
        let i = 4 * (y * 64 + x) as usize;
        let got = match &image.color {
            ColorData::Srgba8(b) => &b[i..i + 4],
            _ => unreachable!(),
        };
        for c in 0..3 {
            let w = srgb8(want[c]);
            assert!(
                (f32::from(got[c]) - w).abs() <= 1.0,
                "pixel ({x}, {y}) channel {c}: {} vs {w}",
                got[c]
            );
        }
        assert_eq!(got[3], 255, "opaque over an opaque background");
    }
}

#[test]
fn viewer_style_host_polls_accumulates_and_discards() {
    viewer(false);
}

#[test]
fn viewer_style_host_is_clean_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    viewer(true);
}

/// `stereo_host.c`: a perspective camera's left and right eyes as frames
/// of their own, then side by side in one frame, through the C API.
fn stereo_pairs(backend: &str, valgrind: bool) -> (Frame, Frame, Frame) {
    let dir = scratch(&format!(
        "stereo_host_{backend}{}",
        if valgrind { "_valgrind" } else { "" }
    ));
    let program = dir.join("stereo_host");
    compile(&["tests/capi/c/stereo_host.c"], &program, false, true);
    let output = run_with(&program, &[&dir], valgrind, &[("CAVERAY_BACKEND", backend)]);
    assert!(
        output.status.success(),
        "stereo_host: {}",
        describe(&output)
    );
    let eye = UVec2::new(48, 48);
    let left = read_rgba(&dir.join("left.rgba"), eye);
    let right = read_rgba(&dir.join("right.rgba"), eye);
    let pair = read_rgba(&dir.join("pair.rgba"), UVec2::new(96, 48));
    (left, right, pair)
}

/// Columns `x0..x0 + 48` of a 96 x 48 frame.
fn half(pair: &Frame, x0: u32) -> Frame {
    crop(pair, UVec2::new(x0, 0), UVec2::new(48, 48))
}

#[test]
fn stereo_side_by_side_through_the_c_api_holds_both_eyes() {
    // The CPU reference renders the halves as two passes: each exactly
    // its eye's own image.
    let (left, right, pair) = stereo_pairs("cpu", false);
    assert_eq!(half(&pair, 0).color, left.color);
    assert_eq!(half(&pair, 48).color, right.color);
    // On the GPU, one re-projection pass: the left eye as its own pass,
    // the right within Buchacher & Erdt's DSSIM bound.
    let (left, right, pair) = stereo_pairs("gpu", false);
    let s = ssim(&half(&pair, 0), &left).unwrap();
    let d = anari_library_caveray::render::dssim(&half(&pair, 48), &right).unwrap();
    eprintln!("sideBySide through the C API on the GPU: left SSIM {s:.5}, right DSSIM {d:.4}");
    assert!(s > 0.98, "left eye SSIM {s}");
    assert!(d < 0.02, "right eye DSSIM {d}");
}

#[test]
fn stereo_side_by_side_is_clean_under_valgrind() {
    if !valgrind_available() {
        missing("valgrind is not installed");
        return;
    }
    let (left, right, pair) = stereo_pairs("cpu", true);
    assert_eq!(half(&pair, 0).color, left.color);
    assert_eq!(half(&pair, 48).color, right.color);
}
