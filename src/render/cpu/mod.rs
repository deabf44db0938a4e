//! The reference ray caster: the model of docs/ray_casting.md written
//! plainly, one rayon task per image row. Tests hold the GPU to it, and
//! the tool falls back to it where no adapter exists.

mod capture;
mod march;
mod packet;
mod sample;

use std::sync::{Arc, Mutex};

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::frame::{encoded, filled, ColorFormat, Frame, FrameDesc};
use super::hits::{self, HitRecord};
use super::iso::{self, IsoFilter, IsoSettings};
use super::march_plan::MarchPlan;
use super::simd::Level;
use super::{Render, RenderError, RenderSettings, Watch};
use crate::geometry::RayGen;
use crate::render::empty_space::SpaceCache;
use crate::render::shapes::{Hit, ShapeSet, MAX_TRANSLUCENT, SURFACE_PASSES};
use crate::render::warp::LayerBuilder;
use crate::scene::Coverage;
use crate::scene::{PlacedShape, PlacedVolume, Scene, SpatialField, TransferFunction};
use packet::Channels;
use sample::{Converted, Samples};

/// Pixels per tile edge.
const TILE: usize = 16;

/// Isosurface fields, and crossing boxes per field, the CPU renderer keeps.
const ISO_KEPT: usize = 16;
/// The largest volume copied to f32 for the packet path (512 MiB of
/// copy): beyond it the packets' speed costs more memory than it is worth,
/// and the volume is sampled in its own type on the scalar path.
const PACKET_COPY_VOXELS: usize = 1 << 27;

#[derive(Debug, Default)]
pub struct CpuRenderer {
    /// The vector lanes that one trilinear volume's primary samples go
    /// through, sixteen or eight at a time (packet.rs); none for the
    /// scalar reference.
    packets: Option<Level>,
    /// Whether camera rays find their first surface a few neighbours at
    /// a time (shapes::ShapeSet::hits); the reference takes them one by
    /// one.
    surface_packets: bool,
    /// The last scene's voxels as f32 and its tables, kept while scenes
    /// bring the same `Arc`s, as the GPU keeps its uploads.
    cache: Mutex<Prepared>,
}

#[derive(Debug, Default)]
struct Prepared {
    samples: Vec<(Arc<SpatialField>, Samples)>,
    tables: Vec<(Arc<TransferFunction>, Arc<Vec<Vec4>>)>,
    spaces: SpaceCache,
    /// The last scene's surfaces, and their BVH.
    shapes: Option<(Vec<PlacedShape>, Arc<ShapeSet>)>,
    /// The isosurfaces' fields as f32, and their crossing boxes by
    /// iso-value and filter, kept while frames bring the same volumes.
    iso: Vec<IsoPrepared>,
}

#[derive(Debug)]
struct IsoPrepared {
    volume: Arc<SpatialField>,
    values: Arc<Vec<f32>>,
    boxes: Vec<((u32, IsoFilter), CrossingBox)>,
}

/// A crossing box's grid-space corners (render::iso::crossing_box).
type CrossingBox = (Vec3, Vec3);

impl CpuRenderer {
    /// The CPU renderer, with packets as wide as the CPU's vector unit
    /// (AVX-512, else AVX2), or as `CAVERAY_SIMD` narrows them.
    pub fn new() -> Self {
        Self {
            packets: packet::level(),
            surface_packets: true,
            ..Self::default()
        }
    }

    /// The CPU renderer with packets at `level` (AVX2 or AVX-512), if
    /// this CPU runs it: to compare the paths.
    pub fn with_simd(level: Level) -> Option<Self> {
        (level >= Level::Avx2 && level.runs()).then(|| Self {
            packets: Some(level),
            surface_packets: true,
            ..Self::default()
        })
    }

    /// This renderer with camera rays traced to their first surface
    /// together (`true`) or one by one: to compare the two.
    pub fn with_surface_packets(self, on: bool) -> Self {
        Self {
            surface_packets: on,
            ..self
        }
    }

    /// The reference: every sample by the scalar path of docs/ray_casting.md,
    /// which the packet path and the GPU are held to.
    pub fn reference() -> Self {
        Self::default()
    }

    /// The lanes frames of one trilinear volume take on this CPU, if
    /// they take the packet path.
    pub fn packet_level(&self) -> Option<Level> {
        self.packets
    }

    /// Whether camera rays find their first surface in packets.
    pub fn uses_surface_packets(&self) -> bool {
        self.surface_packets
    }

    pub fn uses_packets(&self) -> bool {
        self.packets.is_some()
    }

    /// `placed`'s values as f32 and its crossing box for `settings`, made
    /// only when new: a frame of isosurfaces would otherwise convert and
    /// scan every voxel each time.
    pub fn iso_field(
        &self,
        placed: &PlacedVolume,
        settings: &IsoSettings,
    ) -> Result<(Arc<Vec<f32>>, CrossingBox), RenderError> {
        let mut cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        let volume = &placed.volume;
        let index = match cache
            .iso
            .iter()
            .position(|p| Arc::ptr_eq(&p.volume, volume))
        {
            Some(i) => i,
            None => {
                let values = iso::values(placed)?;
                // Few volumes at a time: the oldest goes.
                if cache.iso.len() >= ISO_KEPT {
                    cache.iso.remove(0);
                }
                cache.iso.push(IsoPrepared {
                    volume: Arc::clone(volume),
                    values: Arc::new(values),
                    boxes: Vec::new(),
                });
                cache.iso.len() - 1
            }
        };
        let entry = &mut cache.iso[index];
        let key = (settings.isovalue.to_bits(), settings.filter);
        let bounds = match entry.boxes.iter().find(|(k, _)| *k == key) {
            Some((_, b)) => *b,
            None => {
                let values = &entry.values;
                let b = iso::crossing_box(
                    volume.dims(),
                    |i| values[i],
                    settings.isovalue,
                    settings.filter,
                );
                if entry.boxes.len() >= ISO_KEPT {
                    entry.boxes.remove(0);
                }
                entry.boxes.push((key, b));
                b
            }
        };
        Ok((Arc::clone(&entry.values), bounds))
    }

    /// How `volume` is sampled: its own stored numbers, unless the packet
    /// path runs here and needs f32 values it does not hold; then a copy
    /// as f32, where one of at most PACKET_COPY_VOXELS pays for itself in
    /// speed (past that, the memory counts more).
    fn samples(&self, volume: &Arc<SpatialField>) -> Result<Samples, RenderError> {
        let own = Samples::Stored(Arc::clone(volume));
        // A mesh is sampled in its cells, never by the packet path.
        let Some(volume) = volume.structured() else {
            return Ok(own);
        };
        let n = volume.voxels().len();
        if !self.uses_packets() || own.f32_values().is_some() || n > PACKET_COPY_VOXELS {
            return Ok(own);
        }
        let mut values = filled(n, 0.0f32, "the volume as f32")?;
        for (i, v) in values.iter_mut().enumerate() {
            *v = volume.value(i);
        }
        Ok(Samples::Copied(Arc::new(values)))
    }

    /// Bytes of the f32 copies the packet path keeps of `scene`'s volumes.
    pub fn copy_bytes(&self, scene: &Scene) -> u64 {
        let cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        cache
            .samples
            .iter()
            .filter(|(v, _)| scene.volumes().iter().any(|p| Arc::ptr_eq(&p.volume, v)))
            .map(|(_, s)| match s {
                Samples::Copied(values) => 4 * values.len() as u64,
                Samples::Stored(_) => 0,
            })
            .sum()
    }

    /// Each volume's values, table and (if the plan skips) clear bricks,
    /// made only when new.
    fn prepare(&self, scene: &Scene, plan: &MarchPlan) -> Result<Vec<Converted>, RenderError> {
        // A poisoned lock only means a panic elsewhere; the cache is rebuilt.
        let mut cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        let spaces = if plan.skipping {
            cache
                .spaces
                .update(scene, plan)?
                .0
                .into_iter()
                .map(Some)
                .collect()
        } else {
            vec![None; scene.volumes().len()]
        };
        let mut next = Prepared {
            spaces: std::mem::take(&mut cache.spaces),
            iso: std::mem::take(&mut cache.iso),
            shapes: cache.shapes.take(),
            ..Prepared::default()
        };
        let mut converted = Vec::new();
        for (placed, space) in scene.volumes().iter().zip(spaces) {
            let volume = &placed.volume;
            let kept = cache
                .samples
                .iter()
                .find(|(v, _)| Arc::ptr_eq(v, volume))
                .map(|(_, s)| s.clone());
            let samples = match kept {
                Some(s) => s,
                None => self.samples(volume)?,
            };
            let tf = &placed.transfer_function;
            let table = reuse(&cache.tables, tf).unwrap_or_else(|| Arc::new(tf.table()));
            next.samples.push((Arc::clone(volume), samples.clone()));
            next.tables.push((Arc::clone(tf), Arc::clone(&table)));
            converted.push(Converted {
                samples,
                table,
                space,
            });
        }
        *cache = next;
        Ok(converted)
    }
}

impl CpuRenderer {
    /// The BVH of `scene`'s surfaces, built only when they are new; `None`
    /// for a scene of volumes alone.
    pub fn shape_set(&self, scene: &Scene) -> Result<Option<Arc<ShapeSet>>, RenderError> {
        let shapes = scene.shapes();
        if shapes.is_empty() {
            return Ok(None);
        }
        let mut cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((kept, set)) = &cache.shapes {
            if kept.len() == shapes.len() && kept.iter().zip(shapes).all(|(a, b)| a.same(b)) {
                return Ok(Some(Arc::clone(set)));
            }
        }
        let set = Arc::new(ShapeSet::build(shapes)?);
        cache.shapes = Some((shapes.to_vec(), Arc::clone(&set)));
        Ok(Some(set))
    }
}

impl Render for &CpuRenderer {
    /// Casts no further pixel once the stop flag is set; counts tiles of
    /// 16 x 16 pixels.
    fn render_until<'w>(
        self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        desc: &FrameDesc,
        watch: impl Into<Watch<'w>>,
    ) -> Result<Frame, RenderError> {
        self.render_watched(scene, rays, settings, desc, watch.into())
    }
}

impl CpuRenderer {
    /// `render_until` past the conversion, made once for every kind of
    /// watch.
    fn render_watched(
        &self,
        scene: &Scene,
        rays: &RayGen,
        settings: &RenderSettings,
        desc: &FrameDesc,
        watch: Watch,
    ) -> Result<Frame, RenderError> {
        desc.validate()?;
        let plan = MarchPlan::new(scene, rays, settings)?;
        let shapes = self.shape_set(scene)?;
        let data = self.prepare(scene, &plan)?;
        let channels = match (&data[..], self.packets) {
            ([one], Some(level)) => Some((level, Channels::new(&one.table))),
            _ => None,
        };
        let packets = channels.as_ref().map(|(level, c)| (*level, &**c));
        let field = sample::Field::new(&plan, &data, packets).with_shapes(shapes.as_deref());
        let (w, h) = (desc.size.x as usize, desc.size.y as usize);
        // Square tiles, not rows: neighbouring rays in both directions read
        // the same voxels while they are in cache, and a tile is small
        // enough that two threads stay busy to the frame's end.
        let (tx, ty) = (w.div_ceil(TILE), h.div_ceil(TILE));
        // An 8-bit frame is encoded pixel by pixel in its tiles: no float
        // copy of the whole frame is ever held (16 bytes a pixel).
        let encode = desc.color != ColorFormat::Rgba32F;
        watch.expect((tx * ty) as u64);
        let tiles: Vec<Tile> = (0..tx * ty)
            .into_par_iter()
            .map(|tile| {
                let (x0, y0) = ((tile % tx) * TILE, (tile / tx) * TILE);
                let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
                let mut out = Tile {
                    index: tile,
                    color: Vec::with_capacity(if encode { 0 } else { 4 * TILE * TILE }),
                    bytes: Vec::with_capacity(if encode { 4 * TILE * TILE } else { 0 }),
                    depth: Vec::with_capacity(TILE * TILE),
                    hits: Vec::with_capacity(if desc.hits { TILE * TILE } else { 0 }),
                    samples: 0,
                };
                // The camera rays' first surfaces, found a few neighbours at
                // a time (shapes/wide.rs's packets), row by row.
                let firsts = match shapes.as_deref() {
                    Some(s) if self.surface_packets => s.camera_hits(rays, (x0, y0), (x1, y1)),
                    _ => Vec::new(),
                };
                for y in y0..y1 {
                    for x in x0..x1 {
                        // Per pixel: one slow tile must not hold up a stop.
                        if watch.stopped() {
                            return out;
                        }
                        let (o, dir) = rays.pixel_ray(x as u32, y as u32);
                        let first = firsts.get((y - y0) * (x1 - x0) + (x - x0)).copied();
                        let bg = match &settings.background_image {
                            Some(image) => image.at(x as u32, y as u32, desc.size),
                            None => plan.background,
                        };
                        let (color, depth, n, first) = match shapes.as_deref() {
                            None => {
                                let ray =
                                    march::march(&field, rays, o, dir, (bg, f32::INFINITY), None);
                                (ray.color, ray.depth, ray.samples, None)
                            }
                            Some(s) => {
                                let ray = ((o, dir), first);
                                through_surfaces(s, &field, rays, ray, bg, settings, None)
                            }
                        };
                        if desc.hits {
                            out.hits.push(match (first, shapes.as_deref()) {
                                (Some(hit), Some(s)) => s.record(&hit),
                                _ if depth.is_finite() => field
                                    .record(rays.point_at_depth(x as u32, y as u32, depth), dir),
                                _ => HitRecord::NOTHING,
                            });
                        }
                        if encode {
                            out.bytes
                                .extend_from_slice(&encoded(desc.color, color.to_array()));
                        } else {
                            out.color.extend_from_slice(&color.to_array());
                        }
                        out.depth.push(depth);
                        out.samples += u64::from(n);
                    }
                }
                watch.advance(1);
                out
            })
            .collect();
        // A stopped render leaves at once: filling a large frame's buffers
        // alone takes a good part of a second.
        if watch.stopped() {
            return Err(RenderError::Stopped);
        }
        let mut color = match encode {
            true => Vec::new(),
            false => filled(4 * desc.pixels(), 0.0f32, "the frame's color")?,
        };
        let mut bytes = match encode {
            true => filled(4 * desc.pixels(), 0u8, "the frame's 8-bit color")?,
            false => Vec::new(),
        };
        let mut depth = filled(desc.pixels(), 0.0f32, "the frame's depth")?;
        let mut records = match desc.hits {
            true => filled(desc.pixels(), HitRecord::NOTHING, "the frame's hits")?,
            false => Vec::new(),
        };
        let mut samples = 0;
        for tile in tiles {
            samples += tile.samples;
            let (x0, y0) = ((tile.index % tx) * TILE, (tile.index / tx) * TILE);
            let tw = (x0 + TILE).min(w) - x0;
            for (row, dr) in tile.depth.chunks(tw).enumerate() {
                let at = (y0 + row) * w + x0;
                depth[at..at + dr.len()].copy_from_slice(dr);
            }
            for (row, cr) in tile.color.chunks(4 * tw).enumerate() {
                let at = 4 * ((y0 + row) * w + x0);
                color[at..at + cr.len()].copy_from_slice(cr);
            }
            for (row, br) in tile.bytes.chunks(4 * tw).enumerate() {
                let at = 4 * ((y0 + row) * w + x0);
                bytes[at..at + br.len()].copy_from_slice(br);
            }
            for (row, hr) in tile.hits.chunks(tw).enumerate() {
                let at = (y0 + row) * w + x0;
                records[at..at + hr.len()].copy_from_slice(hr);
            }
        }
        if watch.stopped() {
            return Err(RenderError::Stopped);
        }
        let depth = desc.depth.then_some(depth);
        let mut frame = match encode {
            true => Frame::from_encoded(desc, bytes, depth)?,
            false => Frame::from_linear(desc, color, depth)?,
        };
        if desc.hits {
            frame.hits = Some(hits::resolve(scene, &records));
        }
        frame.samples = samples;
        Ok(frame)
    }
}

/// One tile's pixels, row by row.
struct Tile {
    index: usize,
    /// Linear RGBA, for a float frame.
    color: Vec<f32>,
    /// Encoded RGBA, for an 8-bit frame.
    bytes: Vec<u8>,
    depth: Vec<f32>,
    /// Empty unless the frame asks for hits.
    hits: Vec<HitRecord>,
    samples: u64,
}

/// What `cache` holds for `key`, if it holds it.
fn reuse<K, V>(cache: &[(Arc<K>, Arc<V>)], key: &Arc<K>) -> Option<Arc<V>> {
    cache
        .iter()
        .find(|(k, _)| Arc::ptr_eq(k, key))
        .map(|(_, v)| Arc::clone(v))
}

/// One pixel's ray `(o, dir)` through the volumes and `shapes`: marched
/// up to each surface it meets, a translucent one composited in its turn
/// (up to MAX_TRANSLUCENT, the rest passed through), and ended by the
/// first opaque one, whose lit color hides `bg`. Returns the color, the depth (the nearer of the
/// opaque surface and where the accumulated opacity reached the
/// threshold), the volume samples taken and the surface hit at that
/// depth (`None`: the depth is the volumes', or there is none). With
/// `layers`, every contributing sample and surface is recorded there.
fn through_surfaces(
    shapes: &ShapeSet,
    field: &sample::Field,
    rays: &RayGen,
    ((o, dir), known): ((glam::Vec3, glam::Vec3), Option<Option<Hit>>),
    bg: glam::Vec4,
    settings: &RenderSettings,
    mut layers: Option<&mut LayerBuilder>,
) -> (glam::Vec4, f32, u32, Option<Hit>) {
    let plan = field.plan;
    let mut acc = march::Accumulator::new();
    let mut samples = 0;
    let mut from = rays.t_near;
    let mut composited = 0;
    let mut first = None;
    let mut known = known;
    for _ in 0..SURFACE_PASSES {
        // The first surface may have been found with the pixel's
        // neighbours, between the same bounds.
        let hit = match known.take() {
            Some(hit) => hit,
            None => shapes.hit(o, dir, from, rays.t_far),
        };
        let stop = hit.map_or(f32::INFINITY, |h| h.t);
        samples += march::march_segment(
            field,
            rays,
            (o, dir),
            (from, stop),
            &mut acc,
            layers.as_deref_mut(),
        );
        let Some(h) = hit else {
            return (acc.over(bg), acc.depth, samples, first);
        };
        match shapes.coverage(&h) {
            Coverage::Translucent(a) => {
                if composited < MAX_TRANSLUCENT {
                    let lit = shapes.shade(&h, (o, dir), settings);
                    let p = o + dir * h.t;
                    let had_depth = acc.depth.is_finite();
                    let stop = acc.add(plan, rays, p, h.t, lit, a);
                    if !had_depth && acc.depth.is_finite() {
                        first = Some(h);
                    }
                    if let Some(layers) = layers.as_deref_mut() {
                        layers.add_surface(h.t, lit, a, acc.color.w);
                    }
                    if stop {
                        return (acc.over(bg), acc.depth, samples, first);
                    }
                    composited += 1;
                }
                from = h.t;
            }
            // Hidden surfaces are not in the BVH.
            Coverage::Opaque | Coverage::Hidden => {
                let lit = shapes.shade(&h, (o, dir), settings);
                if let Some(layers) = layers.as_deref_mut() {
                    layers.add_surface(h.t, lit, 1.0, 1.0);
                }
                let lit = lit.extend(1.0);
                let surface = rays.depth_at(o + dir * h.t, h.t);
                if surface <= acc.depth {
                    first = Some(h);
                }
                return (acc.over(lit), acc.depth.min(surface), samples, first);
            }
        }
    }
    // Past that many translucent surfaces, the ray goes on through any.
    samples += march::march_segment(
        field,
        rays,
        (o, dir),
        (from, f32::INFINITY),
        &mut acc,
        layers,
    );
    (acc.over(bg), acc.depth, samples, first)
}
