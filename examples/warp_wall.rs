//! The front wall of the Cologne CAVE rendered for one eye position, then
//! shown from an eye 100 mm to the right by each warp, against the frame
//! rendered there: prints DSSIM per warp and writes
//! out/examples/warp_wall/warp_<mode>.png.
//! Run: cargo run --release --example warp_wall

use std::sync::atomic::AtomicBool;

use anari_library_caveray::cave::{Eye, Rig};
use anari_library_caveray::data::{preset, shepp_logan};
use anari_library_caveray::geometry::PrimaryRays;
use anari_library_caveray::output::write_png;
use anari_library_caveray::render::warp::{WarpMode, WarpSettings};
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{dssim, Backend, FrameDesc, RenderSettings, Renderer};
use anari_library_caveray::scene::Scene;
use glam::{DVec3, UVec2};

/// Each example writes into its own folder, never over the demo's files.
const OUT: &str = "out/examples/warp_wall";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rig = Rig::load("cave_configs/cologne_5wall.toml".as_ref())?;
    let size = rig.scene.size as f32;
    let volume = shepp_logan(96).placed(rig.scene.centre.as_vec3(), size);
    let scene = Scene::new(volume, preset("phantom")?.with_unit_distance(size / 2.0)?);
    let (mut renderer, _cpu_because) = Renderer::choose(Backend::Auto)?;
    let settings = RenderSettings::default();
    let wall = rig.wall("front").ok_or("no front wall")?;
    let image = UVec2::new(256, 256);
    let head = rig.head_pose(None, None);
    let moved = rig.head_pose(Some(head.position + DVec3::new(100.0, 0.0, 0.0)), None);
    let rays = |head| -> Result<_, Box<dyn std::error::Error>> {
        Ok(rig.view(wall, Eye::Mono, head)?.camera.ray_gen(image))
    };
    let (old, new) = (rays(&head)?, rays(&moved)?);

    // What warps need of the old view: color, first-hit depth, 4 layers.
    let stop = AtomicBool::new(false);
    let (source, ms) = renderer.capture(&scene, &old, &settings, image, 4, &stop)?;
    println!("captured the old view in {ms:.1} ms");
    let desc = FrameDesc::new(image);
    let ideal = renderer.render(&scene, &new, &settings, &desc)?;
    std::fs::create_dir_all(OUT)?;
    for mode in WarpMode::ALL {
        let warp = WarpSettings::new(mode, scene.bounds());
        let (warped, ms) = renderer.warp(&source, &new, image, &warp)?;
        let frame = warped.frame(&desc, settings.background)?;
        let d = dssim(&frame, &ideal)?;
        println!(
            "{:<7} {ms:7.2} ms  DSSIM {d:.4} against the new view",
            mode.name()
        );
        write_png(&frame, format!("{OUT}/warp_{}.png", mode.name()).as_ref())?;
    }
    Ok(())
}
