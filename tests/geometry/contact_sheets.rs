//! Contact sheet layouts: CAVE walls as an unfolded cube, other rigs in a row.

use crate::common;

use anari_library_caveray::output::{contact_sheet, SheetLayout};
use glam::UVec2;
use image::{Rgba, RgbaImage};

fn cells(stem: &str) -> (UVec2, Vec<(String, UVec2)>) {
    let rig = common::rig(stem);
    let layout = SheetLayout::for_rig(&rig);
    let names = rig.walls.iter().map(|w| w.name.clone());
    (layout.grid, names.zip(layout.cells).collect())
}

#[test]
fn cave_walls_unfold_around_the_front_wall() {
    let u = UVec2::new;
    let (grid, c) = cells("cologne_5wall");
    assert_eq!(grid, u(3, 3));
    let expect = [
        ("front", u(1, 1)),
        ("left", u(0, 1)),
        ("right", u(2, 1)),
        ("ceiling", u(1, 0)),
        ("floor", u(1, 2)),
    ];
    for (name, cell) in expect {
        assert!(c.contains(&(name.to_string(), cell)), "{name}: {c:?}");
    }
    // No ceiling: the cross loses its top row.
    let (grid, c) = cells("cave_4wall_3m");
    assert_eq!(grid, u(3, 2));
    assert!(c.contains(&("front".into(), u(1, 0))), "{c:?}");
    assert!(c.contains(&("floor".into(), u(1, 1))), "{c:?}");
    let (grid, _) = cells("powerwall");
    assert_eq!(grid, u(1, 1));
}

#[test]
fn a_sheet_places_scaled_images_in_their_cells() {
    let rig = common::rig("cave_4wall_3m");
    let layout = SheetLayout::for_rig(&rig);
    let color = |i: usize| Rgba([50 * i as u8, 255 - 50 * i as u8, 7, 255]);
    // Images of different sizes; the sheet uses the largest as its cell.
    let images: Vec<Option<RgbaImage>> = (0..rig.walls.len())
        .map(|i| {
            let side = if i == 0 { 20 } else { 10 };
            (i != 2).then(|| RgbaImage::from_pixel(side, side, color(i)))
        })
        .collect();
    let sheet = contact_sheet(&layout, &images);
    let gap = 4;
    assert_eq!(sheet.dimensions(), (3 * 20 + 4 * gap, 2 * 20 + 3 * gap));
    for (i, cell) in layout.cells.iter().enumerate() {
        let centre = *cell * (20 + gap) + UVec2::splat(gap + 10);
        let got = *sheet.get_pixel(centre.x, centre.y);
        let want = if i == 2 {
            Rgba([0, 0, 0, 255])
        } else {
            color(i)
        };
        assert_eq!(got, want, "wall {} at {cell}", rig.walls[i].name);
    }
}
