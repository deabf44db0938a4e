//! NanoVDB grids written by the NanoVDB library at test time, on both
//! renderers: every voxel reads as the library reads it, whatever the
//! value type; the grids render as the same values on a structured grid
//! placed by the grid's map (Float, Fp16, Fp8, Fp4 and a level set,
//! linear and nearest); the GPU reads the tree as the CPU does; skipping
//! leaps over what the tree holds empty and leaves the image alone.

use crate::common;

use anari_library_caveray::geometry::{OffAxisCamera, PrimaryRays};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{ssim, Frame, FrameDesc, RenderSettings, Renderer, Shading};
use anari_library_caveray::scene::{Filter, Scene, TransferFunction};
use common::render::{off_axis_wall, renderers};
use glam::{IVec3, UVec2, Vec3, Vec4};

const SIZE: UVec2 = UVec2::new(48, 48);

fn render(r: &mut Renderer, scene: &Scene, settings: &RenderSettings) -> Frame {
    let (screen, eye) = off_axis_wall();
    let rays = OffAxisCamera::new(screen, eye).unwrap().ray_gen(SIZE);
    r.render(scene, &rays, settings, &FrameDesc::new(SIZE))
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The fog's density: clear below 0.05, denser towards the core.
fn fog_table() -> TransferFunction {
    TransferFunction::new(
        vec![
            Vec4::new(0.2, 0.4, 0.9, 1.0),
            Vec4::new(0.9, 0.8, 0.3, 1.0),
            Vec4::new(0.9, 0.2, 0.1, 1.0),
        ],
        vec![0.0, 0.4, 1.0],
        (0.05, 1.0),
        0.3,
    )
    .unwrap()
}

/// The level set's narrow band: opaque near the surface (0), clear
/// outside.
fn band_table() -> TransferFunction {
    TransferFunction::new(
        vec![
            Vec4::new(0.9, 0.6, 0.2, 1.0),
            Vec4::new(0.3, 0.7, 0.9, 1.0),
            Vec4::new(0.1, 0.1, 0.1, 1.0),
        ],
        vec![1.0, 0.6, 0.0],
        (-1.5, 1.5),
        0.3,
    )
    .unwrap()
}

#[test]
fn every_voxel_reads_as_the_library_reads_it() {
    let Some(written) = common::nanovdb::grids() else {
        return;
    };
    for name in ["fog", "fog16", "fog8", "fog4", "torus"] {
        let grid = written.grid(name, Filter::Linear);
        let dense = written.dense(name);
        let info = &written.grids[name];
        assert_eq!(grid.values().name(), info["type"].as_str().unwrap());
        assert_eq!(grid.active_voxels(), info["active"].as_u64().unwrap());
        assert_eq!(grid.lattice().0, dense.dims(), "{name}");
        let (lo, hi) = grid.bounds();
        let (dlo, dhi) = dense.bounds();
        assert!(
            lo.abs_diff_eq(dlo, 1e-6) && hi.abs_diff_eq(dhi, 1e-6),
            "{name}: {lo} {hi} against {dlo} {dhi}"
        );
        let first = grid.active_box().0;
        let d = dense.dims();
        let mut worst = 0.0f32;
        for z in 0..d.z {
            for y in 0..d.y {
                for x in 0..d.x {
                    let i = (x + d.x * (y + d.y * z)) as usize;
                    let got = grid.value(first + IVec3::new(x as i32, y as i32, z as i32));
                    worst = worst.max((got - dense.value(i)).abs());
                }
            }
        }
        eprintln!(
            "{name}: {} voxels, largest difference {worst}",
            d.x * d.y * d.z
        );
        assert_eq!(worst, 0.0, "{name}");
    }
}

#[test]
fn grids_render_as_their_values_on_a_structured_grid() {
    let Some(written) = common::nanovdb::grids() else {
        return;
    };
    let mut gpu_cpu = Vec::new();
    for (name, mut r) in renderers() {
        let mut frames = Vec::new();
        for (grid, filter, table) in [
            ("fog", Filter::Linear, fog_table()),
            ("fog16", Filter::Linear, fog_table()),
            ("fog8", Filter::Linear, fog_table()),
            ("fog", Filter::Nearest, fog_table()),
            ("torus", Filter::Linear, band_table()),
        ] {
            let vdb = written.grid(grid, filter);
            let dense = written.dense(grid).with_filter(filter);
            let settings = RenderSettings {
                shading: Shading::Shadows,
                ..RenderSettings::default()
            };
            let got = render(
                &mut r,
                &common::nanovdb::scene(vdb, table.clone()),
                &settings,
            );
            let want = render(&mut r, &common::nanovdb::scene(dense, table), &settings);
            let s = ssim(&got, &want).unwrap();
            eprintln!("{name} {grid} {filter:?}: SSIM {s:.5} against the structured grid");
            assert!(s >= 0.999, "{name} {grid} {filter:?}: SSIM {s}");
            frames.push(got);
        }
        gpu_cpu.push(frames);
    }
    for (k, (g, c)) in gpu_cpu[0].iter().zip(&gpu_cpu[1]).enumerate() {
        let s = ssim(g, c).unwrap();
        eprintln!("case {k}: GPU against CPU SSIM {s:.5}");
        assert!(s >= 0.999, "case {k}: GPU against CPU SSIM {s}");
    }
}

#[test]
fn skipping_leaps_over_the_empty_tree_and_leaves_the_image_alone() {
    let Some(written) = common::nanovdb::grids() else {
        return;
    };
    // The fog's edge alone, where the density ramps up: its core (tiles
    // of 1) and the space around it (tiles of 0) are clear.
    let edge = TransferFunction::new(
        vec![Vec4::new(0.9, 0.6, 0.2, 1.0); 5],
        vec![0.0, 0.0, 1.0, 0.0, 0.0],
        (0.0, 1.0),
        0.3,
    )
    .unwrap();
    let vdb = written.grid("fog_fine", Filter::Linear);
    let scene = common::nanovdb::scene(vdb, edge);
    let mut results = Vec::new();
    for (name, mut r) in renderers() {
        let on = render(&mut r, &scene, &RenderSettings::default());
        let off = render(
            &mut r,
            &scene,
            &RenderSettings {
                skipping: false,
                ..RenderSettings::default()
            },
        );
        let s = ssim(&on, &off).unwrap();
        eprintln!(
            "{name}: skipping on/off SSIM {s:.5}, samples {} against {}",
            on.samples, off.samples
        );
        results.push((name, s, on.samples, off.samples));
    }
    for (name, s, on, off) in results {
        assert!(s >= 0.999, "{name}: SSIM {s}");
        assert!(
            on * 3 < off * 2,
            "{name}: {on} samples with skipping, {off} without"
        );
    }
}

/// A part of a grid (what a data-parallel brick holds) keeps only the
/// nodes its samples read, and samples there as the whole does.
#[test]
fn a_part_of_a_grid_holds_its_nodes_and_samples_as_the_whole() {
    let Some(written) = common::nanovdb::grids() else {
        return;
    };
    let mut rng = common::Rng::new(7);
    for name in ["fog_fine", "fog8", "torus"] {
        let whole = written.grid(name, Filter::Linear);
        let dims = whole.lattice().0;
        let lo = dims / 4;
        let hi = dims / 2;
        let part = whole.window_of(lo, hi).unwrap();
        assert_eq!(part.lattice().0, hi - lo + glam::UVec3::ONE);
        let extent = (hi - lo).as_vec3();
        let mut worst = 0.0f32;
        for _ in 0..20_000 {
            let g = Vec3::new(
                rng.uniform(0.0, 1.0) as f32,
                rng.uniform(0.0, 1.0) as f32,
                rng.uniform(0.0, 1.0) as f32,
            ) * extent;
            worst = worst.max((part.sample(g) - whole.sample(g + lo.as_vec3())).abs());
        }
        eprintln!(
            "{name}: part {lo}..{hi} holds {} of {} bytes, nodes {:?} of {:?}; largest difference {worst}",
            part.bytes(),
            whole.bytes(),
            part.node_counts(),
            whole.node_counts()
        );
        // The same voxels, the point rounded once more (lo added apart).
        assert!(worst < 1e-5, "{name}: {worst}");
        assert!(part.node_counts()[2] < whole.node_counts()[2], "{name}");
        assert!(part.bytes() < whole.bytes(), "{name}");
    }
}
