//! Both eyes of the Cologne CAVE's front wall from one ray casting pass:
//! the left eye is ray cast, the right one re-projected from it.
//! Writes out/examples/stereo_wall/stereo_front_<eye>.png. Needs a Vulkan
//! adapter (lavapipe will do). Run: cargo run --release --example stereo_wall

use anari_library_caveray::cave::{Eye, Rig};
use anari_library_caveray::data::{preset, shepp_logan};
use anari_library_caveray::geometry::PrimaryRays;
use anari_library_caveray::output::write_png;
use anari_library_caveray::render::stereo::{Bounds, LayerFormat, Reprojection};
use anari_library_caveray::render::{FrameDesc, GpuRenderer, RenderSettings};
use anari_library_caveray::scene::Scene;
use glam::UVec2;

/// Each example writes into its own folder, never over the demo's files.
const OUT: &str = "out/examples/stereo_wall";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rig = Rig::load("cave_configs/cologne_5wall.toml".as_ref())?;
    let size = rig.scene.size as f32;
    let volume = shepp_logan(96).placed(rig.scene.centre.as_vec3(), size);
    let scene = Scene::new(volume, preset("phantom")?.with_unit_distance(size / 2.0)?);
    let wall = rig.wall("front").ok_or("no front wall")?;
    let head = rig.head_pose(None, None);
    let left = rig.view(wall, Eye::Left, &head)?.matrix_camera()?;
    let right = rig.view(wall, Eye::Right, &head)?.matrix_camera()?;
    let image = UVec2::new(400, 400);
    // Fails with the reason (e.g. a baseline not parallel to the wall's
    // rows) when the pair must be rendered in two passes instead.
    let plan = Reprojection::new(
        &left,
        &right,
        image,
        Bounds::of(&scene),
        None,
        LayerFormat::Rgba16F,
    )?;
    let mut gpu = GpuRenderer::new()?;
    let frames = gpu.render_reprojected(
        &scene,
        &left.ray_gen(image),
        &plan,
        &RenderSettings::default(),
        &FrameDesc::new(image),
    )?;
    std::fs::create_dir_all(OUT)?;
    write_png(
        &frames.left,
        format!("{OUT}/stereo_front_left.png").as_ref(),
    )?;
    write_png(
        &frames.right,
        format!("{OUT}/stereo_front_right.png").as_ref(),
    )?;
    println!(
        "{} layers ({:.1} MiB); left eye + layers {:.1} ms, compositing {:.1} ms",
        plan.layers,
        plan.memory() as f64 / (1024.0 * 1024.0),
        frames.times.left_ms,
        frames.times.composite_ms
    );
    Ok(())
}
