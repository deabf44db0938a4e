//! Load a rig, place the head, and get every wall's cameras and rays.
//! Run: cargo run --example wall_rays

use anari_library_caveray::cave::Rig;
use anari_library_caveray::geometry::PrimaryRays;
use glam::DVec3;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rig = Rig::load("cave_configs/cologne_5wall.toml".as_ref())?;
    // Tracked head 20 cm left of centre, turned 30 degrees to the left.
    let head = rig.head_pose(
        Some(DVec3::new(-200.0, 0.0, 200.0)),
        Some(DVec3::new(30.0, 0.0, 0.0)),
    );
    for (wall, eye, view) in rig.views(&head) {
        let view = view?;
        // Strategy 1: the OpenGL matrices a host would load; the third
        // column of the projection holds the frustum's off-axis shift.
        let shift = view.projection.proj.z_axis;
        // Strategy 2: the ANARI perspective camera plus imageRegion.
        let pinhole = view.pinhole()?;
        // The centre pixel's primary ray, from the native off-axis camera.
        let ray = view.camera.pixel_ray(800, 800, view.resolution);
        println!(
            "{:>7} {eye:>5}: shift ({:+.3}, {:+.3}), fovy {:6.2} deg, region {:.3?}, centre ray {:.3}",
            wall.name,
            shift.x,
            shift.y,
            pinhole.fovy().to_degrees(),
            pinhole.image_region().to_array(),
            ray.direction,
        );
    }
    Ok(())
}
