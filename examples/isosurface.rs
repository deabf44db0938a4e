//! The CT head's bone isosurface (the CPU reference caster), shaded
//! flat and colored by curvature: iso_flat.png and iso_curvature.png in
//! out/examples/isosurface/.
//! Run: cargo run --release --example isosurface [VOLUMES_TOML]

use std::path::PathBuf;

use anari_library_caveray::data::Manifest;
use anari_library_caveray::geometry::{ImageRegion, PinholeCamera, PrimaryRays};
use anari_library_caveray::output::write_png;
use anari_library_caveray::render::iso::{cast, Coloring, IsoSettings};
use anari_library_caveray::render::FrameDesc;
use anari_library_caveray::scene::{PlacedVolume, Scene};
use glam::{DVec3, UVec2};

/// Each example writes into its own folder, never over the demo's files.
const OUT: &str = "out/examples/isosurface";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let manifest = std::env::args().nth(1).map_or_else(
        || PathBuf::from("../shared/data/volumes/volumes.toml"),
        PathBuf::from,
    );
    let manifest = Manifest::locate(Some(&manifest), &[])?;
    let volume = manifest
        .load_volume("cthead")?
        .placed(glam::Vec3::ZERO, 2.0);
    let scene = Scene::new(volume, anari_library_caveray::data::preset("grey")?);
    let placed: &PlacedVolume = &scene.volumes()[0];
    let (lo, hi) = placed.volume.value_range();
    // Bone in the 12-bit CT head: about 40% of its range.
    let isovalue = lo + 0.4 * (hi - lo);
    let size = UVec2::new(256, 256);
    let eye = DVec3::new(1.2, -2.8, -0.6);
    let rays =
        PinholeCamera::new(eye, -eye, DVec3::NEG_Z, 0.8, 1.0, ImageRegion::FULL)?.ray_gen(size);
    std::fs::create_dir_all(OUT)?;
    for (name, coloring) in [
        ("flat", Coloring::Flat(glam::Vec3::new(0.9, 0.85, 0.75))),
        ("curvature", Coloring::Curvature { radius: 0.03 }),
    ] {
        let settings = IsoSettings {
            coloring,
            light: Some(glam::Vec3::new(0.4, -0.6, 0.7)),
            ..IsoSettings::new(isovalue)
        };
        let start = std::time::Instant::now();
        let (frame, hits) = cast(placed, &rays, &FrameDesc::new(size), &settings)?;
        let hit = hits.iter().flatten().count();
        println!(
            "{name}: {hit} of {} pixels hit, {:.2} s",
            hits.len(),
            start.elapsed().as_secs_f64()
        );
        write_png(&frame, format!("{OUT}/iso_{name}.png").as_ref())?;
    }
    Ok(())
}
