use glam::UVec2;
use image::{imageops, Rgba, RgbaImage};

use crate::cave::Rig;

/// Gap between cells, in pixels, filled with `GAP_COLOR`.
const GAP: u32 = 4;
const GAP_COLOR: Rgba<u8> = Rgba([48, 48, 48, 255]);

/// Where each wall goes on a contact sheet, as grid cells (x right, y
/// down). CAVE walls are laid out as an unfolded cube around the front
/// wall; rigs whose walls do not fit a cube get one row in file order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SheetLayout {
    pub grid: UVec2,
    /// Cell of each wall, in the rig's wall order.
    pub cells: Vec<UVec2>,
}

impl SheetLayout {
    pub fn for_rig(rig: &Rig) -> Self {
        let frame = rig.viewer.frame;
        // Which way the viewer looks to see each wall.
        let slots: Vec<UVec2> = rig
            .walls
            .iter()
            .map(|w| {
                let towards = -w.screen.normal();
                let axes = [
                    (frame.forward, UVec2::new(1, 1)),
                    (-frame.forward, UVec2::new(3, 1)),
                    (-frame.right, UVec2::new(0, 1)),
                    (frame.right, UVec2::new(2, 1)),
                    (frame.up, UVec2::new(1, 0)),
                    (-frame.up, UVec2::new(1, 2)),
                ];
                axes.iter()
                    .map(|&(axis, cell)| (towards.dot(axis), cell))
                    .fold((f64::NEG_INFINITY, UVec2::ZERO), |best, c| {
                        if c.0 > best.0 {
                            c
                        } else {
                            best
                        }
                    })
                    .1
            })
            .collect();
        let unique = slots
            .iter()
            .enumerate()
            .all(|(i, s)| !slots[..i].contains(s));
        if !unique {
            let n = rig.walls.len() as u32;
            return Self {
                grid: UVec2::new(n, 1),
                cells: (0..n).map(|i| UVec2::new(i, 0)).collect(),
            };
        }
        // Crop the cross to the cells in use.
        let lo = slots.iter().fold(UVec2::MAX, |a, &c| a.min(c));
        let hi = slots.iter().fold(UVec2::ZERO, |a, &c| a.max(c));
        Self {
            grid: hi - lo + UVec2::ONE,
            cells: slots.iter().map(|&c| c - lo).collect(),
        }
    }
}

/// One image of all walls: each wall's image scaled into a cell of the
/// largest image's size, at its place in `layout`; walls without an image
/// (e.g. an eye behind that wall) stay dark.
pub fn contact_sheet(layout: &SheetLayout, images: &[Option<RgbaImage>]) -> RgbaImage {
    let cell = images.iter().flatten().fold(UVec2::ONE, |a, im| {
        a.max(UVec2::new(im.width(), im.height()))
    });
    let size = layout.grid * cell + (layout.grid + UVec2::ONE) * GAP;
    let mut sheet = RgbaImage::from_pixel(size.x, size.y, GAP_COLOR);
    for (image, at) in images.iter().zip(&layout.cells) {
        let origin = *at * (cell + UVec2::splat(GAP)) + UVec2::splat(GAP);
        let fitted = match image {
            Some(im) if im.dimensions() == (cell.x, cell.y) => im.clone(),
            Some(im) => imageops::resize(im, cell.x, cell.y, imageops::FilterType::Triangle),
            None => RgbaImage::from_pixel(cell.x, cell.y, Rgba([0, 0, 0, 255])),
        };
        imageops::overlay(
            &mut sheet,
            &fitted,
            i64::from(origin.x),
            i64::from(origin.y),
        );
    }
    sheet
}
