//! A data-parallel frame (the device's `caveray.mpi`): each rank's world
//! holds its part of the volumes and owns a box of world space (the
//! world's `caveray.region`). Every rank renders the samples in its box of
//! the steps one renderer of all the boxes together would take, over a
//! clear background; the partial images are composited by direct-send
//! (each rank blends one band of rows, in the order each pixel's ray
//! enters the boxes) and every rank gets the whole frame.
//!
//! No rank may leave another waiting in a collective, so every rank makes
//! every collective whatever happened to it. Where a rank cannot render
//! (its snapshot failed, its render failed or panicked), it says so in the
//! first exchange or with its band, and every rank fails the frame.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Arc;

use glam::{UVec2, Vec3, Vec4};

use super::inputs::{EyeView, Inputs, Share, Views};
use super::job::RenderJob;
use super::status::panic_message;
use crate::cluster::{band, bands_of, composite, floats_of, Partial, Ranks, Region};
use crate::geometry::RayGen;
use crate::render::Render as _;
use crate::render::{
    Backend, ColorData, ColorFormat, Frame, FrameDesc, RenderSettings, Renderer, StreamWait,
};
use crate::scene::PlacedVolume;

/// What a rank that cannot render this frame sends as its region.
pub const CANNOT_RENDER: (Vec3, Vec3) = (Vec3::NAN, Vec3::NAN);

/// What a rank renders for a frame it cannot render (its snapshot failed):
/// nothing, taking its part in the frame's collectives to say so.
pub fn cannot_render(ranks: Arc<Ranks>, backend: Backend) -> Inputs {
    Inputs {
        scene: None,
        surfaces: Vec::new(),
        views: Views::Mono(EyeView {
            rays: RayGen::default(),
            offset: UVec2::ZERO,
            size: UVec2::ONE,
            matrix: None,
        }),
        settings: RenderSettings::default(),
        desc: FrameDesc::new(UVec2::ONE),
        backend,
        gpu_budget: None,
        stream_wait: StreamWait::Complete,
        accumulate: false,
        share: Some(Share {
            ranks,
            region: CANNOT_RENDER,
        }),
    }
}

/// This rank's share of `job`'s frame, rendered by `renderer` (or why it
/// could not be), composited with every other rank's.
pub fn render(
    renderer: Result<&mut Renderer, String>,
    job: &RenderJob,
    share: &Share,
) -> Result<Frame, String> {
    let inputs = &job.inputs;
    let ranks = &share.ranks;
    let _turn = ranks.turn();
    // First every rank's region and smallest cell (0: it has no volume).
    let cell = inputs
        .scene
        .iter()
        .flat_map(|s| s.volumes())
        .map(PlacedVolume::smallest_cell)
        .reduce(f32::min)
        .unwrap_or(0.0);
    let (lo, hi) = share.region;
    let mine: Vec<u8> = [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, cell]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    let said: Vec<Vec<f32>> = ranks
        .all_gather(&mine)?
        .iter()
        .map(|b| floats_of(b))
        .collect();
    let regions = agreed_regions(&said)?;
    let whole = regions
        .iter()
        .map(Region::corners)
        .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
        .and_then(|(lo, hi)| Region::world(lo, hi))
        .ok_or("the ranks' regions bound no box")?;
    let size = inputs.desc.size;
    let pixels = size.x as usize * size.y as usize;
    let settings = RenderSettings {
        background: Vec4::ZERO,
        background_image: None,
        part: Some(regions[ranks.rank()].part_of(&whole)),
        ..inputs.settings.clone()
    };
    let desc = FrameDesc::new(size).with_color(ColorFormat::Rgba32F);
    let rays = match &inputs.views {
        Views::Mono(view) => Ok(view.rays),
        _ => Err("a data-parallel frame takes a camera with one view".to_string()),
    };
    let local = match (renderer, &inputs.scene, &rays) {
        (Err(e), ..) => Err(e),
        (_, _, Err(e)) => Err(e.clone()),
        (Ok(_), None, _) => Ok((vec![0.0; 4 * pixels], 0)),
        (Ok(r), Some(scene), Ok(rays)) => catch_unwind(AssertUnwindSafe(|| {
            r.render_until(scene, rays, &settings, &desc, &job.slot.stop)
        }))
        .unwrap_or_else(|p| {
            Err(crate::render::RenderError::Gpu(format!(
                "render panicked: {}",
                panic_message(&p)
            )))
        })
        .map_err(|e| e.to_string())
        .and_then(|f| match f.color {
            ColorData::Rgba32F(c) => Ok((c, f.samples)),
            _ => Err("internal: a partial image not in floats".into()),
        }),
    };
    let clear;
    let partial: &[f32] = match &local {
        Ok((c, _)) if c.len() == 4 * pixels => c,
        _ => {
            clear = vec![0.0; 4 * pixels];
            &clear
        }
    };
    let n = ranks.size();
    let got = ranks.exchange(&bands_of(partial, size.x, n))?;
    let floats: Vec<Vec<f32>> = got.iter().map(|b| floats_of(b)).collect();
    let parts: Vec<Partial<'_>> = floats
        .iter()
        .zip(&regions)
        .map(|(color, region)| Partial { region, color })
        .collect();
    let rows = band(size.y, n, ranks.rank());
    let blended = rays.clone().and_then(|rays| {
        let linear = composite(
            &rays,
            size.x,
            rows.clone(),
            &parts,
            inputs.settings.background,
        )?;
        let band = FrameDesc::new(UVec2::new(size.x, rows.len() as u32));
        Frame::from_linear(&band.with_color(inputs.desc.color), linear, None)
            .map_err(|e| e.to_string())
    });
    // The band, after one byte that says whether this rank rendered and
    // blended its part.
    let ok = local.is_ok() && blended.is_ok();
    let mut bytes = vec![u8::from(ok)];
    if let Ok(band) = &blended {
        match &band.color {
            ColorData::Rgba8(b) | ColorData::Srgba8(b) => bytes.extend_from_slice(b),
            ColorData::Rgba32F(f) => bytes.extend(f.iter().flat_map(|x| x.to_le_bytes())),
        }
    }
    let bands = ranks.all_gather(&bytes)?;
    let (_, samples) = local?;
    blended?;
    if let Some(r) = bands.iter().position(|b| b.first() != Some(&1)) {
        return Err(format!(
            "rank {r} could not render or blend its part of this frame (its own errors say why), so no rank shows it"
        ));
    }
    let all: Vec<u8> = bands.iter().flat_map(|b| b[1..].iter().copied()).collect();
    let expected = pixels * inputs.desc.color.bytes_per_pixel() as usize;
    if all.len() != expected {
        return Err(format!(
            "the ranks' composited bands hold {} bytes where the frame has {expected}: do all ranks render frames of one size?",
            all.len()
        ));
    }
    let color = match inputs.desc.color {
        ColorFormat::Rgba8 => ColorData::Rgba8(all),
        ColorFormat::Srgba8 => ColorData::Srgba8(all),
        ColorFormat::Rgba32F => ColorData::Rgba32F(floats_of(&all)),
    };
    Ok(Frame {
        size,
        color,
        depth: None,
        hits: None,
        samples,
    })
}

/// The ranks' regions from what each said (its box, then its smallest
/// cell), or why the frame cannot be composited: every rank sees the same
/// list, so every rank refuses alike.
fn agreed_regions(said: &[Vec<f32>]) -> Result<Vec<Region>, String> {
    let mut regions = Vec::with_capacity(said.len());
    for (rank, f) in said.iter().enumerate() {
        let &[a, b, c, d, e, g, _] = f.as_slice() else {
            return Err(format!("rank {rank} sent no region"));
        };
        if [a, b, c, d, e, g].iter().all(|x| x.is_nan()) {
            return Err(format!(
                "rank {rank} cannot render this frame (its own errors say why), so no rank renders it"
            ));
        }
        let (lo, hi) = (Vec3::new(a, b, c), Vec3::new(d, e, g));
        regions.push(Region::world(lo, hi).ok_or_else(|| {
            format!("rank {rank}'s world region is not a box: {lo} to {hi} (set its world's caveray.region)")
        })?);
    }
    let cells: Vec<f32> = said
        .iter()
        .map(|f| f[6])
        .filter(|&c| c > 0.0 && c.is_finite())
        .collect();
    let (least, most) = cells
        .iter()
        .fold((f32::INFINITY, 0.0f32), |(a, b), &c| (a.min(c), b.max(c)));
    if most > least * (1.0 + 1e-4) {
        return Err(format!(
            "the ranks' volumes have smallest cells from {least} to {most}: the ranks of a data-parallel frame share one grid spacing, so that they step alike"
        ));
    }
    for (i, r) in regions.iter().enumerate() {
        for (j, s) in regions.iter().enumerate().skip(i + 1) {
            let ((a, b), (c, d)) = (r.corners(), s.corners());
            let shared = b.min(d) - a.max(c);
            let tolerance = 1e-6 * (b - a).max(d - c).max_element();
            if shared.cmpgt(Vec3::splat(tolerance)).all() {
                return Err(format!(
                    "the regions of ranks {i} and {j} overlap ({a} to {b} and {c} to {d}): each rank's world owns its own box (caveray.region; a brick stored with an apron owns less than its bounds)"
                ));
            }
        }
    }
    Ok(regions)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_are_refused_together_when_a_rank_cannot_render_or_they_overlap() {
        let said = |boxes: &[[f32; 7]]| boxes.iter().map(|b| b.to_vec()).collect::<Vec<_>>();
        let a = [0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 0.1];
        let b = [0.5, 0.0, 0.0, 1.0, 1.0, 1.0, 0.1];
        assert_eq!(agreed_regions(&said(&[a, b])).map(|r| r.len()), Ok(2));
        let nan = f32::NAN;
        let failed = [nan, nan, nan, nan, nan, nan, 0.0];
        assert!(agreed_regions(&said(&[a, failed]))
            .is_err_and(|e| e.starts_with("rank 1 cannot render this frame")));
        let apron = [0.45, 0.0, 0.0, 1.0, 1.0, 1.0, 0.1];
        assert!(agreed_regions(&said(&[a, apron]))
            .is_err_and(|e| e.starts_with("the regions of ranks 0 and 1 overlap")));
        let finer = [0.5, 0.0, 0.0, 1.0, 1.0, 1.0, 0.05];
        assert!(
            agreed_regions(&said(&[a, finer])).is_err_and(|e| e.contains("share one grid spacing"))
        );
        // A rank with an empty world (cell 0) steps as the others say.
        let empty = [0.5, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0];
        assert!(agreed_regions(&said(&[a, empty])).is_ok());
    }
}
