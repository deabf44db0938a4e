//! `caveray render --parts N`: the volume cut into N bricks, each brick's
//! region of every view ray cast on its own (the samples in the cells it
//! owns, over a clear background) and the partial images composited front
//! to back in the order each pixel's ray enters the regions. Under
//! `mpirun -np N` each rank renders one brick and composites one band of
//! rows (direct-send), and rank 0 gathers the bands; alone, the one
//! process renders every brick in turn and composites the whole frame,
//! which is what the ranks compute together.

use std::time::Instant;

use anari_library_caveray::cluster::{
    band, bands_of, composite, floats_of, Partial, Region, Split,
};
use anari_library_caveray::geometry::RayGen;
use anari_library_caveray::render::Render as _;
use anari_library_caveray::render::{
    ColorData, ColorFormat, Frame, FrameDesc, Progress as ViewProgress, RenderSettings, Renderer,
};
use anari_library_caveray::scene::{PlacedVolume, Scene, StructuredVolume};
use glam::{UVec2, Vec4};
use serde::Serialize;

use crate::cluster::Cluster;
use crate::Failure;

/// The bricks of a data-parallel render, and the ones this process draws.
pub struct Bricks {
    split: Split,
    regions: Vec<Region>,
    /// This process's bricks: their index, scene and settings.
    mine: Vec<(usize, Scene, RenderSettings)>,
    background: Vec4,
}

/// Where each brick sits, for the report.
#[derive(Serialize)]
pub struct BrickInfo {
    pub rank: usize,
    /// First and last vertex of the cells it owns.
    pub owned: [[u32; 3]; 2],
    /// First and last vertex it holds (with the apron).
    pub stored: [[u32; 3]; 2],
    pub stored_bytes: u64,
}

/// One view as the bricks made it.
#[derive(Clone, Serialize, serde::Deserialize)]
pub struct ViewCost {
    /// Each brick's render, in brick order.
    pub render_ms: Vec<f64>,
    /// Each brick's volume samples.
    pub samples: Vec<u64>,
    /// Each compositing process's time: the exchange, its band and the
    /// gather (alone: the whole frame).
    pub composite_ms: Vec<f64>,
    /// Bytes each process sent to the others for this view.
    pub bytes_sent: Vec<u64>,
}

#[derive(Serialize)]
pub struct DataParallelReport {
    /// Bricks along x, y and z.
    pub counts: [u32; 3],
    /// Whether the bricks were spread over MPI ranks (else one process
    /// rendered them in turn).
    pub ranks: usize,
    pub bricks: Vec<BrickInfo>,
    /// Per view, in the order of `views`.
    pub costs: Vec<ViewCost>,
}

fn mismatch(parts: usize, ranks: usize) -> Failure {
    Failure::Usage(format!(
        "--parts: {parts} bricks over {ranks} MPI ranks: under mpirun each rank renders one brick, so --parts must equal -np"
    ))
}

/// The value range of `volume` from this rank's brick of `parts` and every
/// other rank's: each reads only the voxels of its brick.
pub fn value_range(
    volume: &StructuredVolume,
    parts: usize,
    cluster: &Cluster,
) -> Result<(f32, f32), Failure> {
    // Every rank takes the same branch: the refusals are the same on all.
    if cluster.size() != parts {
        return Err(mismatch(parts, cluster.size()));
    }
    let split = Split::new(volume.dims(), parts)
        .map_err(|why| Failure::Usage(format!("--parts: {why}")))?;
    let brick = &split.bricks[cluster.rank()];
    let (lo, hi) = brick.stored;
    let mine = volume
        .cropped(lo, hi)
        .map_err(|e| Failure::Runtime(e.to_string()))?
        .value_range();
    let all: Vec<(f32, f32)> = cluster.all_gather_json(&mine)?;
    Ok(all
        .into_iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), (lo, hi)| {
            (a.min(lo), b.max(hi))
        }))
}

impl Bricks {
    /// `scene`'s one volume cut into `parts` bricks: the ones `cluster`'s
    /// rank draws (alone: all of them), each a scene of its stored voxels
    /// under the same transfer function and placement, with `settings`
    /// clipped to its region and a clear background.
    pub fn new(
        scene: &Scene,
        settings: &RenderSettings,
        parts: usize,
        cluster: &Cluster,
    ) -> Result<Self, Failure> {
        let usage = |why: String| Failure::Usage(format!("--parts: {why}"));
        let [volume] = scene.volumes() else {
            return Err(usage(format!(
                "splits one volume over the bricks, and the scene has {}",
                scene.volumes().len()
            )));
        };
        if cluster.size() > 1 && cluster.size() != parts {
            return Err(mismatch(parts, cluster.size()));
        }
        if !scene.shapes().is_empty() {
            return Err(usage(
                "cuts a volume alone into bricks: every brick would draw the mesh over its part (leave out --mesh)".into(),
            ));
        }
        if settings.background_image.is_some() {
            return Err(usage(
                "partial images are composited over a plain background color, not an image".into(),
            ));
        }
        let split = Split::new(volume.volume.dims(), parts).map_err(usage)?;
        let regions: Vec<Region> = split
            .bricks
            .iter()
            .map(|b| Region::of_brick(volume, b))
            .collect();
        let whole = Region::of_grid(volume);
        let drawn: Vec<usize> = if cluster.size() > 1 {
            vec![cluster.rank()]
        } else {
            (0..parts).collect()
        };
        let mut mine = Vec::new();
        for i in drawn {
            let (lo, hi) = split.bricks[i].stored;
            let cropped = volume
                .volume
                .cropped(lo, hi)
                .map_err(|e| Failure::Runtime(format!("brick {i}: {e}")))?;
            let brick = Scene::placed(vec![PlacedVolume {
                volume: std::sync::Arc::new(cropped),
                ..volume.clone()
            }])
            .and_then(|s| s.with_shapes(scene.shapes().to_vec()))
            .map_err(|e| Failure::Runtime(format!("brick {i}: {e}")))?;
            let share = RenderSettings {
                background: Vec4::ZERO,
                part: Some(regions[i].part_of(&whole)),
                ..settings.clone()
            };
            mine.push((i, brick, share));
        }
        Ok(Self {
            split,
            regions,
            mine,
            background: settings.background,
        })
    }

    /// How many bricks there are.
    pub fn len(&self) -> usize {
        self.split.bricks.len()
    }

    /// The bricks' scenes this process draws, to upload.
    pub fn scenes(&self) -> impl Iterator<Item = &Scene> {
        self.mine.iter().map(|(_, s, _)| s)
    }

    pub fn report(&self, ranks: usize, costs: Vec<ViewCost>) -> DataParallelReport {
        let stored_bytes: Vec<u64> = self
            .split
            .bricks
            .iter()
            .map(|b| {
                let n = (b.stored.1 - b.stored.0 + glam::UVec3::ONE).as_u64vec3();
                n.x * n.y * n.z
            })
            .collect();
        // A brick held here by its own bytes; another rank's, by the
        // bytes per lattice vertex of one held here.
        let held = |i: usize| {
            self.mine
                .iter()
                .find(|(j, _, _)| *j == i)
                .map(|(_, s, _)| s.volumes()[0].volume.bytes())
        };
        let each = self
            .mine
            .first()
            .map(|(_, s, _)| {
                let v = &s.volumes()[0].volume;
                let n = v.dims().as_u64vec3();
                v.bytes() / (n.x * n.y * n.z).max(1)
            })
            .unwrap_or(1);
        DataParallelReport {
            counts: self.split.counts.to_array(),
            ranks,
            bricks: self
                .split
                .bricks
                .iter()
                .zip(stored_bytes)
                .enumerate()
                .map(|(rank, (b, n))| BrickInfo {
                    rank,
                    owned: [b.owned.0.to_array(), b.owned.1.to_array()],
                    stored: [b.stored.0.to_array(), b.stored.1.to_array()],
                    stored_bytes: held(rank).unwrap_or(n * each),
                })
                .collect(),
            costs,
        }
    }

    /// One view through `rays`: every brick this process draws, then the
    /// compositing (with the other ranks, under MPI). Rank 0 gets the
    /// frame; the others get None. `cost` has this process's numbers.
    pub fn render_view(
        &self,
        renderer: &mut Renderer,
        rays: &RayGen,
        size: UVec2,
        cluster: &Cluster,
        counter: &ViewProgress,
    ) -> Result<(Option<Frame>, ViewCost), Failure> {
        let desc = FrameDesc::new(size).with_color(ColorFormat::Rgba32F);
        let mut partials = Vec::with_capacity(self.mine.len());
        let mut render_ms = Vec::with_capacity(self.mine.len());
        let mut samples = Vec::with_capacity(self.mine.len());
        for (i, scene, settings) in &self.mine {
            let t = Instant::now();
            let frame = renderer
                .render_until(scene, rays, settings, &desc, counter)
                .map_err(|e| Failure::Runtime(format!("brick {i}: {e}")))?;
            render_ms.push(t.elapsed().as_secs_f64() * 1e3);
            samples.push(frame.samples);
            let ColorData::Rgba32F(color) = frame.color else {
                return Err(Failure::Runtime(
                    "internal: a partial image not in floats".into(),
                ));
            };
            partials.push(color);
        }
        let t = Instant::now();
        let out = FrameDesc::new(size);
        let encode = |rows: std::ops::Range<u32>, linear: Vec<f32>| {
            Frame::from_linear(
                &FrameDesc::new(UVec2::new(size.x, rows.len() as u32)),
                linear,
                None,
            )
            .map_err(|e| Failure::Runtime(e.to_string()))
        };
        if cluster.size() == 1 {
            let parts: Vec<Partial<'_>> = self
                .mine
                .iter()
                .zip(&partials)
                .map(|((i, ..), color)| Partial {
                    region: &self.regions[*i],
                    color,
                })
                .collect();
            let linear = composite(rays, size.x, 0..size.y, &parts, self.background)
                .map_err(Failure::Runtime)?;
            let mut frame = Frame::from_linear(&out, linear, None)
                .map_err(|e| Failure::Runtime(e.to_string()))?;
            frame.samples = samples.iter().sum();
            let cost = ViewCost {
                render_ms,
                samples,
                composite_ms: vec![t.elapsed().as_secs_f64() * 1e3],
                bytes_sent: vec![0],
            };
            return Ok((Some(frame), cost));
        }
        // Direct-send: band j of this rank's partial goes to rank j.
        let ranks = cluster.size();
        let [mine] = partials.as_slice() else {
            return Err(Failure::Runtime("internal: a rank draws one brick".into()));
        };
        let to = bands_of(mine, size.x, ranks);
        let sent: u64 = to
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != cluster.rank())
            .map(|(_, m)| m.len() as u64)
            .sum();
        let got = cluster.exchange(to)?;
        let floats: Vec<Vec<f32>> = got.iter().map(|b| floats_of(b)).collect();
        let parts: Vec<Partial<'_>> = floats
            .iter()
            .zip(&self.regions)
            .map(|(color, region)| Partial { region, color })
            .collect();
        let rows = band(size.y, ranks, cluster.rank());
        let linear = composite(rays, size.x, rows.clone(), &parts, self.background)
            .map_err(|e| Failure::Runtime(format!("compositing: {e}")))?;
        let ColorData::Rgba8(bytes) = encode(rows, linear)?.color else {
            return Err(Failure::Runtime("internal: a band not in 8 bits".into()));
        };
        let bands = cluster.gather_bytes(&bytes)?;
        let mut cost = ViewCost {
            render_ms,
            samples,
            composite_ms: vec![t.elapsed().as_secs_f64() * 1e3],
            bytes_sent: vec![
                sent + if cluster.is_root() {
                    0
                } else {
                    bytes.len() as u64
                },
            ],
        };
        let costs = cluster.gather_json(&cost)?;
        if !cluster.is_root() {
            return Ok((None, cost));
        }
        cost = ViewCost {
            render_ms: costs.iter().flat_map(|c| c.render_ms.clone()).collect(),
            samples: costs.iter().flat_map(|c| c.samples.clone()).collect(),
            composite_ms: costs.iter().flat_map(|c| c.composite_ms.clone()).collect(),
            bytes_sent: costs.iter().flat_map(|c| c.bytes_sent.clone()).collect(),
        };
        let frame = Frame {
            size,
            color: ColorData::Rgba8(bands.concat()),
            depth: None,
            hits: None,
            samples: cost.samples.iter().sum(),
        };
        Ok((Some(frame), cost))
    }
}
