//! Render both eyes of one CAVE wall to out/examples/render_wall/front_<eye>.png,
//! on the GPU if there is one, else on the CPU reference.
//! Run: cargo run --release --example render_wall

use anari_library_caveray::cave::{Eye, Rig};
use anari_library_caveray::data::{preset, shepp_logan};
use anari_library_caveray::geometry::PrimaryRays;
use anari_library_caveray::output::write_png;
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{Backend, FrameDesc, RenderSettings, Renderer, Shading};
use anari_library_caveray::scene::Scene;
use glam::UVec2;

/// Each example writes into its own folder, never over the demo's files.
const OUT: &str = "out/examples/render_wall";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rig = Rig::load("cave_configs/cologne_5wall.toml".as_ref())?;
    let head = rig.head_pose(None, None);
    // The phantom where the rig puts volumes; opacities are tuned for a
    // volume two units across, so scale the unit distance with it.
    let size = rig.scene.size as f32;
    let volume = shepp_logan(96).placed(rig.scene.centre.as_vec3(), size);
    let tf = preset("phantom")?.with_unit_distance(size / 2.0)?;
    let scene = Scene::new(volume, tf);

    let (mut renderer, cpu_because) = Renderer::choose(Backend::Auto)?;
    if let Some(reason) = cpu_because {
        eprintln!("{reason}");
    }
    let settings = RenderSettings {
        shading: Shading::Shadows,
        ..Default::default()
    };
    let wall = rig.wall("front").ok_or("no front wall")?;
    std::fs::create_dir_all(OUT)?;
    for eye in [Eye::Left, Eye::Right] {
        let view = rig.view(wall, eye, &head)?;
        let image = UVec2::new(400, 400);
        // Any camera lowers to the same RayGen; strategy 1 shown here.
        let rays = view.matrix_camera()?.ray_gen(image);
        let frame = renderer.render(&scene, &rays, &settings, &FrameDesc::new(image))?;
        let file = format!("{OUT}/front_{}.png", eye.name());
        write_png(&frame, file.as_ref())?;
        println!(
            "{file}: {} samples on {}",
            frame.samples,
            renderer.describe()
        );
    }
    Ok(())
}
