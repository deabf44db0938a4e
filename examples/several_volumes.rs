//! Several volumes in one scene on the CAVE's front wall: a CT head with a
//! phantom turned and pushed into it, each with its own transfer function,
//! composited per sample. Writes out/examples/several_volumes/several_volumes.png
//! and prints the cost of 1, 2, 4 and 8 overlapping volumes against one.
//! Run: cargo run --release --example several_volumes [-- cpu|gpu]

use std::sync::Arc;
use std::time::Instant;

use anari_library_caveray::cave::{Eye, Rig};
use anari_library_caveray::data::{preset, shepp_logan, Manifest};
use anari_library_caveray::geometry::PrimaryRays;
use anari_library_caveray::output::write_png;
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{Backend, FrameDesc, RenderSettings, Renderer, Shading};
use anari_library_caveray::scene::{ObjectIds, PlacedVolume, Scene, SpatialField, MAX_VOLUMES};
use glam::{Mat4, UVec2, Vec3};

/// Each example writes into its own folder, never over the demo's files.
const OUT: &str = "out/examples/several_volumes";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let backend: Backend = std::env::args().nth(1).unwrap_or("auto".into()).parse()?;
    let rig = Rig::load("cave_configs/cologne_5wall.toml".as_ref())?;
    let (centre, size) = (rig.scene.centre.as_vec3(), rig.scene.size as f32);
    let manifest = Manifest::locate(None, &["../shared/data/volumes/volumes.toml".into()])?;
    let head = Arc::new(SpatialField::from(
        manifest.load_volume("cthead")?.placed(centre, size),
    ));
    let phantom = Arc::new(SpatialField::from(shepp_logan(96).placed(centre, size)));
    // The CT's values fill only part of UINT16's range: stretch the preset
    // over them, as `caveray render` does.
    let (lo, hi) = head.value_range();
    let skin = Arc::new(
        preset("ct-skin-bone")?
            .with_value_range(lo, hi)?
            .with_unit_distance(size / 2.0)?,
    );
    let glow = Arc::new(preset("phantom")?.with_unit_distance(size / 4.0)?);
    // The k-th extra volume: the phantom, half size, turned about y and
    // pushed off the centre, so each overlaps the head differently.
    let extra = |k: usize| {
        let angle = 0.6 + k as f32;
        let offset = Mat4::from_rotation_y(angle).transform_vector3(Vec3::X * 0.25 * size);
        PlacedVolume {
            volume: Arc::clone(&phantom),
            transfer_function: Arc::clone(&glow),
            transform: Mat4::from_translation(centre + offset)
                * Mat4::from_rotation_y(angle)
                * Mat4::from_scale(Vec3::splat(0.5))
                * Mat4::from_translation(-centre),
            ids: ObjectIds::NONE,
        }
    };
    let scene_of = |n: usize| {
        let mut volumes = vec![PlacedVolume {
            volume: Arc::clone(&head),
            transfer_function: Arc::clone(&skin),
            transform: Mat4::IDENTITY,
            ids: ObjectIds::NONE,
        }];
        volumes.extend((1..n).map(extra));
        Scene::placed(volumes)
    };

    let (mut renderer, cpu_because) = Renderer::choose(backend)?;
    if let Some(reason) = cpu_because {
        eprintln!("{reason}");
    }
    let wall = rig.wall("front").ok_or("no front wall")?;
    let view = rig.view(wall, Eye::Left, &rig.head_pose(None, None))?;
    let image = UVec2::new(320, 320);
    let rays = view.matrix_camera()?.ray_gen(image);
    let settings = RenderSettings {
        shading: Shading::Shadows,
        ..Default::default()
    };
    let desc = FrameDesc::new(image);
    std::fs::create_dir_all(OUT)?;
    println!(
        "{} at {}x{}, shadows, on {}",
        wall.name,
        image.x,
        image.y,
        renderer.describe()
    );
    println!("volumes       ms   Msamples  Msamples/s  ms vs one");
    let mut one = 0.0;
    for n in [1, 2, 4, MAX_VOLUMES] {
        let scene = scene_of(n)?;
        renderer.upload(&scene)?;
        renderer.render(&scene, &rays, &settings, &desc)?;
        let start = Instant::now();
        let frame = renderer.render(&scene, &rays, &settings, &desc)?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        if n == 1 {
            one = ms;
        }
        let msamples = frame.samples as f64 / 1e6;
        println!(
            "{n:>7} {ms:>8.1} {msamples:>10.2} {:>11.1} {:>10.2}",
            msamples / ms * 1e3,
            ms / one
        );
        if n == 2 {
            write_png(&frame, format!("{OUT}/several_volumes.png").as_ref())?;
        }
    }
    println!("wrote {OUT}/several_volumes.png (the head and one phantom)");
    Ok(())
}
