//! A data-parallel frame (the device's `caveray.mpi`): each rank's world
//! holds its part of the volumes and owns a box of world space (the
//! world's `caveray.region`). Every rank renders the samples in its box of
//! the steps one renderer of all the boxes together would take, over a
//! clear background; the partial images are composited by direct-send
//! (each rank blends one band of rows, in the order each pixel's ray
//! enters the boxes) and every rank gets the whole frame. The collectives
//! are made whatever happened here (a failed render sends a clear image
//! and fails afterwards), so that no rank waits for another forever.

use glam::{UVec2, Vec3, Vec4};

use super::inputs::{Share, Views};
use super::job::RenderJob;
use crate::cluster::{band, composite, Partial, Region};
use crate::render::Render as _;
use crate::render::{ColorData, ColorFormat, Frame, FrameDesc, RenderSettings, Renderer};

/// This rank's share of `job`'s frame, rendered by `renderer` (or why it
/// could not be), composited with every other rank's.
pub fn render(
    renderer: Result<&mut Renderer, String>,
    job: &RenderJob,
    share: &Share,
) -> Result<Frame, String> {
    let inputs = &job.inputs;
    let Views::Mono(view) = &inputs.views else {
        return Err("a data-parallel frame takes a camera with one view".into());
    };
    let ranks = &share.ranks;
    let _turn = ranks.turn();
    let (lo, hi) = share.region;
    let mine: Vec<u8> = lo
        .to_array()
        .into_iter()
        .chain(hi.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let regions = ranks
        .all_gather(&mine)?
        .iter()
        .enumerate()
        .map(|(rank, b)| {
            let f: Vec<f32> = b
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect();
            match f.as_slice() {
                &[a, b, c, d, e, g] => Region::world(Vec3::new(a, b, c), Vec3::new(d, e, g)),
                _ => None,
            }
            .ok_or_else(|| format!("rank {rank}'s world region is not a box: {f:?}"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let (wlo, whi) = regions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), r| {
            let (a, b) = r.corners();
            (lo.min(a), hi.max(b))
        });
    let whole = Region::world(wlo, whi).ok_or("the ranks' regions bound no box")?;
    let size = inputs.desc.size;
    let pixels = size.x as usize * size.y as usize;
    let settings = RenderSettings {
        background: Vec4::ZERO,
        background_image: None,
        part: Some(regions[ranks.rank()].part_of(&whole)),
        ..inputs.settings.clone()
    };
    let desc = FrameDesc::new(size).with_color(ColorFormat::Rgba32F);
    let local = match (renderer, &inputs.scene) {
        (Err(e), _) => Err(e),
        (Ok(_), None) => Ok((vec![0.0; 4 * pixels], 0)),
        (Ok(r), Some(scene)) => r
            .render_until(scene, &view.rays, &settings, &desc, &job.slot.stop)
            .map_err(|e| e.to_string())
            .and_then(|f| match f.color {
                ColorData::Rgba32F(c) => Ok((c, f.samples)),
                _ => Err("internal: a partial image not in floats".into()),
            }),
    };
    let clear;
    let partial: &[f32] = match &local {
        Ok((c, _)) => c,
        Err(_) => {
            clear = vec![0.0; 4 * pixels];
            &clear
        }
    };
    let n = ranks.size();
    let row = 4 * size.x as usize;
    let to: Vec<Vec<u8>> = (0..n)
        .map(|j| {
            let rows = band(size.y, n, j);
            bytemuck::cast_slice(&partial[row * rows.start as usize..row * rows.end as usize])
                .to_vec()
        })
        .collect();
    let got = ranks.exchange(&to)?;
    let floats: Vec<Vec<f32>> = got
        .iter()
        .map(|b| {
            b.chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect()
        })
        .collect();
    let parts: Vec<Partial<'_>> = floats
        .iter()
        .zip(&regions)
        .map(|(color, region)| Partial { region, color })
        .collect();
    let rows = band(size.y, n, ranks.rank());
    let linear = composite(
        &view.rays,
        size.x,
        rows.clone(),
        &parts,
        inputs.settings.background,
    );
    // A band that cannot be blended is sent empty: the frame then fails
    // on every rank by its length, after the gather.
    let bytes = match linear.and_then(|l| {
        Frame::from_linear(
            &FrameDesc::new(UVec2::new(size.x, rows.len() as u32)).with_color(inputs.desc.color),
            l,
            None,
        )
        .map_err(|e| e.to_string())
    }) {
        Ok(band) => match band.color {
            ColorData::Rgba8(b) | ColorData::Srgba8(b) => b,
            ColorData::Rgba32F(f) => bytemuck::cast_slice(&f).to_vec(),
        },
        Err(_) => Vec::new(),
    };
    let all = ranks.all_gather(&bytes)?.concat();
    let (_, samples) = local?;
    let expected = pixels * inputs.desc.color.bytes_per_pixel() as usize;
    if all.len() != expected {
        return Err(format!(
            "the ranks' composited bands hold {} bytes where the frame has {expected}",
            all.len()
        ));
    }
    let color = match inputs.desc.color {
        ColorFormat::Rgba8 => ColorData::Rgba8(all),
        ColorFormat::Srgba8 => ColorData::Srgba8(all),
        ColorFormat::Rgba32F => ColorData::Rgba32F(
            all.chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect(),
        ),
    };
    Ok(Frame {
        size,
        color,
        depth: None,
        hits: None,
        samples,
    })
}
