use std::cell::Cell;
use std::sync::Arc;

use glam::{IVec3, Vec3, Vec4};

use super::packet::{Channels, PacketGrid};
use crate::render::empty_space::{Along, EmptySpace, Region};
use crate::render::hits::HitRecord;
use crate::render::march_plan::{MarchPlan, VolumePlan};
use crate::render::shapes::ShapeSet;
use crate::render::simd::Level;
use crate::scene::{
    AmrVolume, Filter, NanoVdbGrid, NearCells, RayCells, Scaling, SpatialField, UnstructuredVolume,
    Voxels, MAX_VOLUMES, TABLE_SIZE,
};

/// One volume as the CPU reads it: its numbers in their stored type (or
/// an f32 copy made for the packet path) and the scaling that makes them
/// values, exactly what the GPU texture holds; and its table.
pub(super) struct Grid<'a> {
    pub plan: &'a VolumePlan,
    numbers: Numbers<'a>,
    scaling: Scaling,
    table: &'a [Vec4],
    /// Where the plan skips: the clear bricks under this table.
    pub space: Option<&'a EmptySpace>,
}

thread_local! {
    /// Where this thread last found samples in each of the meshes it
    /// sampled most recently (by address): a thread marches one ray at a
    /// time, so the next sample's cell is found from there (the field is
    /// shared by all threads, and a ray's state does not reach its
    /// samples). The most recent mesh first.
    static NEAR: [Cell<(usize, NearCells)>; 4] =
        const { [const { Cell::new((0, NearCells { last: 0, entry: 0 })) }; 4] };
}

/// `f` given where this thread last found samples of `mesh`.
fn with_near<R>(mesh: &UnstructuredVolume, f: impl FnOnce(&mut NearCells) -> R) -> R {
    let key = std::ptr::from_ref(mesh) as usize;
    NEAR.with(|slots| {
        let (first, mut near) = slots[0].get();
        if first != key {
            // Bring this mesh's slot to the front, or a fresh one in place
            // of the least recent.
            let found = slots.iter().position(|s| s.get().0 == key);
            near = found.map_or(NearCells::default(), |k| slots[k].get().1);
            for i in (1..=found.unwrap_or(3)).rev() {
                slots[i].set(slots[i - 1].get());
            }
        }
        let r = f(&mut near);
        slots[0].set((key, near));
        r
    })
}

/// The mesh's field at `p`, looked for from this thread's last cell in it.
fn mesh_sample(mesh: &UnstructuredVolume, p: Vec3) -> f32 {
    with_near(mesh, |near| mesh.sample_near(p, near))
}

/// One primary ray through the scene's meshes: where it found its last
/// sample in each, so that the next is found by following the ray
/// (UnstructuredVolume::sample_along). Grids sample as they always do.
pub(super) struct MeshRays {
    rays: [Option<(RayCells, NearCells)>; MAX_VOLUMES],
}

impl MeshRays {
    /// The ray `origin + t dir` (world) through `field`'s meshes, each
    /// starting from where this thread's last ray in it did.
    pub fn new(field: &Field, origin: Vec3, dir: Vec3) -> Self {
        let mut rays = [None; MAX_VOLUMES];
        for (ray, grid) in rays.iter_mut().zip(&field.grids) {
            if let Numbers::Mesh(mesh) = grid.numbers {
                let (_, spacing) = mesh.lattice();
                let o = mesh.bounds().0 + grid.plan.grid(origin) * spacing;
                let d = grid.plan.grid_direction(dir) * spacing;
                *ray = Some((RayCells::new(o, d), with_near(mesh, |near| *near)));
            }
        }
        Self { rays }
    }

    /// Volume `v`'s value at `p`, `t` along the ray.
    pub fn sample(&mut self, field: &Field, v: usize, p: Vec3, t: f32) -> f32 {
        let grid = &field.grids[v];
        match (grid.numbers, &mut self.rays[v]) {
            (Numbers::Mesh(mesh), Some((ray, near))) => mesh.sample_along(ray, t, near),
            _ => grid.sample(grid.plan.grid(p)),
        }
    }

    /// Leaves this thread's next samples of each mesh (a shading ray's,
    /// the next ray's) starting where this ray is.
    pub fn keep(&self, field: &Field) {
        for (ray, grid) in self.rays.iter().zip(&field.grids) {
            if let (Numbers::Mesh(mesh), Some((ray, near))) = (grid.numbers, ray) {
                let last = ray.cell().unwrap_or(near.last);
                with_near(mesh, |kept| {
                    *kept = NearCells {
                        last,
                        entry: near.entry,
                    }
                });
            }
        }
    }
}

/// A volume's numbers as stored.
#[derive(Clone, Copy)]
enum Numbers<'a> {
    U8(&'a [u8]),
    U16(&'a [u16]),
    I16(&'a [i16]),
    F32(&'a [f32]),
    /// An unstructured field's cells, sampled where lattice points lie in
    /// them.
    Mesh(&'a UnstructuredVolume),
    /// An AMR field's cells, sampled where lattice points lie among them.
    Amr(&'a AmrVolume),
    /// A NanoVDB grid's tree, sampled at the lattice's index points.
    Vdb(&'a NanoVdbGrid),
}

impl<'a> Numbers<'a> {
    fn of(voxels: &'a Voxels) -> Self {
        match voxels {
            Voxels::U8(v) => Numbers::U8(v),
            Voxels::U16(v) => Numbers::U16(v),
            Voxels::I16(v) => Numbers::I16(v),
            Voxels::F32(v) => Numbers::F32(v),
        }
    }
}

impl Grid<'_> {
    /// Whether grid point `g` lies within the grid's vertices.
    pub fn contains(&self, g: Vec3) -> bool {
        g.cmpge(Vec3::ZERO).all() && g.cmple(self.plan.last_vertex()).all()
    }

    fn index(&self, i: IVec3) -> usize {
        let d = self.plan.dims;
        i.x as usize + d.x as usize * (i.y as usize + d.y as usize * i.z as usize)
    }

    fn voxel(&self, i: IVec3) -> f32 {
        let at = self.index(i);
        let stored = match self.numbers {
            Numbers::U8(v) => f32::from(v[at]),
            Numbers::U16(v) => f32::from(v[at]),
            Numbers::I16(v) => f32::from(v[at]),
            Numbers::F32(v) => v[at],
            Numbers::Mesh(_) | Numbers::Amr(_) | Numbers::Vdb(_) => {
                unreachable!("only a grid has voxels")
            }
        };
        self.scaling.apply(stored)
    }

    /// Trilinear interpolation between the eight grid vertices around
    /// grid point `g`, or the nearest vertex's value.
    pub fn sample(&self, g: Vec3) -> f32 {
        if let Numbers::Mesh(mesh) = self.numbers {
            let (_, spacing) = mesh.lattice();
            return mesh_sample(mesh, mesh.bounds().0 + g * spacing);
        }
        if let Numbers::Amr(amr) = self.numbers {
            return amr.sample(amr.amr_bounds().0 + g * amr.lattice_step());
        }
        if let Numbers::Vdb(grid) = self.numbers {
            return grid.sample(g);
        }
        let hi = self.plan.dims.as_ivec3() - IVec3::ONE;
        let g = g.clamp(Vec3::ZERO, hi.as_vec3());
        // g >= 0 here, so truncation (`as`) is floor, without a libm call.
        if self.plan.filter == Filter::Nearest {
            // floor(g + 0.5), not round(): the shader's rounding, halves up.
            return self.voxel((g + Vec3::splat(0.5)).as_ivec3().min(hi));
        }
        let i0 = g.as_ivec3().min((hi - IVec3::ONE).max(IVec3::ZERO));
        let f = g - i0.as_vec3();
        // The eight corners as one base index and three strides (0 on an
        // axis one vertex thick, where i1 = i0); one slice check for all.
        let d = self.plan.dims;
        let base = self.index(i0);
        let sx = usize::from(i0.x < hi.x);
        let sy = if i0.y < hi.y { d.x as usize } else { 0 };
        let sz = if i0.z < hi.z {
            d.x as usize * d.y as usize
        } else {
            0
        };
        let strides = (base, sx, sy, sz);
        // The scaling is linear: the stored numbers are interpolated, the
        // result mapped.
        let stored = match self.numbers {
            Numbers::U8(v) => trilinear(v, strides, f),
            Numbers::U16(v) => trilinear(v, strides, f),
            Numbers::I16(v) => trilinear(v, strides, f),
            Numbers::F32(v) => trilinear(v, strides, f),
            Numbers::Mesh(_) | Numbers::Amr(_) | Numbers::Vdb(_) => unreachable!("sampled above"),
        };
        self.scaling.apply(stored)
    }

    /// Post-classification: straight RGBA of a value from the table;
    /// nothing for NaN (outside every cell of a mesh).
    pub fn classify(&self, v: f32) -> Vec4 {
        if v.is_nan() {
            return Vec4::ZERO;
        }
        let plan = self.plan;
        let last = (TABLE_SIZE - 1) as f32;
        let t = ((v - plan.value_lo) * plan.value_scale).clamp(0.0, 1.0) * last;
        let i = (t as usize).min(TABLE_SIZE - 2);
        let f = t - i as f32;
        self.table[i] * (1.0 - f) + self.table[i + 1] * f
    }
}

/// The eight corners' stored numbers at `base` and its strides along x,
/// y and z, interpolated at `f`.
fn trilinear<T: Copy + Into<f32>>(
    v: &[T],
    (base, sx, sy, sz): (usize, usize, usize, usize),
    f: Vec3,
) -> f32 {
    let c = &v[base..=base + sx + sy + sz];
    let at = |i: usize| -> f32 { c[i].into() };
    let x00 = mix(at(0), at(sx), f.x);
    let x10 = mix(at(sy), at(sy + sx), f.x);
    let x01 = mix(at(sz), at(sz + sx), f.x);
    let x11 = mix(at(sz + sy), at(sz + sy + sx), f.x);
    mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z)
}

/// A volume's numbers as the CPU samples them.
#[derive(Clone, Debug)]
pub(super) enum Samples {
    /// Its values as f32: a copy made for the packet path's gathers.
    Copied(Arc<Vec<f32>>),
    /// The field's own numbers (a grid's read through its scaling).
    Stored(Arc<SpatialField>),
}

impl Samples {
    /// The values as one f32 slice, where they are that already: what
    /// the packet path gathers from.
    pub fn f32_values(&self) -> Option<&[f32]> {
        match self {
            Samples::Copied(v) => Some(v),
            Samples::Stored(field) => match field.structured() {
                Some(volume) => match volume.voxels() {
                    Voxels::F32(v) if volume.scaling() == Scaling::IDENTITY => Some(v),
                    _ => None,
                },
                None => None,
            },
        }
    }
}

/// One volume's numbers, its table and its clear bricks, shared with the
/// renderer's cache.
pub(super) struct Converted {
    pub samples: Samples,
    pub table: Arc<Vec<Vec4>>,
    pub space: Option<Arc<EmptySpace>>,
}

/// Every volume of the scene, and the plan they are marched by.
pub(super) struct Field<'a> {
    pub plan: &'a MarchPlan,
    pub grids: Vec<Grid<'a>>,
    /// Where the scene is one trilinear volume and the CPU has AVX2: its
    /// primary samples, eight at a time (packet.rs).
    pub packet: Option<PacketGrid<'a>>,
    /// The surfaces beside the volumes, which shadow and AO rays meet.
    pub shapes: Option<&'a ShapeSet>,
}

impl<'a> Field<'a> {
    /// `data` holds each volume's values and table, in the plan's order;
    /// `packets`: the packet path's lanes and the first table split for
    /// it, if it runs.
    pub fn new(
        plan: &'a MarchPlan,
        data: &'a [Converted],
        packets: Option<(Level, &'a Channels)>,
    ) -> Self {
        debug_assert_eq!(plan.volumes.len(), data.len());
        let grids = plan
            .volumes
            .iter()
            .zip(data)
            .map(|(plan, c)| {
                debug_assert_eq!(c.table.len(), TABLE_SIZE);
                let (numbers, scaling) = match &c.samples {
                    Samples::Copied(v) => (Numbers::F32(v), Scaling::IDENTITY),
                    Samples::Stored(field) => match &**field {
                        SpatialField::Structured(v) => (Numbers::of(v.voxels()), v.scaling()),
                        SpatialField::Unstructured(m) => (Numbers::Mesh(m), Scaling::IDENTITY),
                        SpatialField::Amr(a) => (Numbers::Amr(a), Scaling::IDENTITY),
                        SpatialField::NanoVdb(g) => (Numbers::Vdb(g), Scaling::IDENTITY),
                    },
                };
                Grid {
                    plan,
                    numbers,
                    scaling,
                    table: &c.table,
                    space: c.space.as_deref(),
                }
            })
            .collect();
        let packet = match (packets, &plan.volumes[..], data) {
            // x-neighbour pairs are single loads there: two vertices along x;
            // its gathers address up to 2^31 - 1 voxels.
            (Some((level, channels)), [one], [c])
                if one.filter == Filter::Linear
                    && one.dims.x >= 2
                    && super::packet::addressable(one.dims) =>
            {
                c.samples.f32_values().map(|values| PacketGrid {
                    level,
                    values,
                    dims: one.dims.as_ivec3().to_array(),
                    channels,
                    value_lo: one.value_lo,
                    value_scale: one.value_scale,
                })
            }
            _ => None,
        };
        Self {
            plan,
            grids,
            packet,
            shapes: None,
        }
    }

    /// This field with `shapes` in the way of its shading rays.
    pub fn with_shapes(self, shapes: Option<&'a ShapeSet>) -> Self {
        Self { shapes, ..self }
    }

    /// The light the surfaces let through from `p` along `d` over `reach`
    /// (ShapeSet::passes; all of it where there are none).
    pub fn surfaces_pass(&self, p: Vec3, d: Vec3, reach: f32) -> f32 {
        self.shapes.map_or(1.0, |s| s.passes(p, d, reach))
    }

    /// What the frame's hit channels record of world point `p`, where a
    /// ray of direction `dir` took its depth in the volumes: the first
    /// volume holding it (the nearest, if rounding put `p` just outside
    /// all), its classified color there and its normal, the field's
    /// gradient (central differences one step apart) facing the ray.
    pub fn record(&self, p: Vec3, dir: Vec3) -> HitRecord {
        let outside = |g: &Grid| {
            let q = g.plan.grid(p);
            (Vec3::ZERO.max(-q) + Vec3::ZERO.max(q - g.plan.last_vertex())).length_squared()
        };
        let Some((v, grid)) = self
            .grids
            .iter()
            .enumerate()
            .min_by(|a, b| outside(a.1).total_cmp(&outside(b.1)))
        else {
            return HitRecord::NOTHING;
        };
        let at = |q: Vec3| grid.sample(grid.plan.grid(q));
        let albedo = grid.classify(at(p)).truncate();
        let h = self.plan.step;
        let gradient = Vec3::new(
            at(p + Vec3::X * h) - at(p - Vec3::X * h),
            at(p + Vec3::Y * h) - at(p - Vec3::Y * h),
            at(p + Vec3::Z * h) - at(p - Vec3::Z * h),
        );
        HitRecord::volume(v, facing(gradient, dir), albedo)
    }

    /// Whether world point `p` lies in any volume.
    pub fn inside(&self, p: Vec3) -> bool {
        self.grids.iter().any(|g| g.contains(g.plan.grid(p)))
    }

    /// What the primary ray (unit direction `dir`) meets from its sample
    /// at `p`, `t` along it, given each volume's span of t: a stretch
    /// where every volume is clear (to leap over), or where some volume
    /// could show (to sample), and how long it is.
    pub fn region(&self, spans: &[Option<(f32, f32)>], p: Vec3, dir: Vec3, t: f32) -> Region {
        let (mut clear, mut busy) = (f32::INFINITY, f32::INFINITY);
        for (grid, span) in self.grids.iter().zip(spans) {
            let Some((a, b)) = *span else { continue };
            if t < a {
                clear = clear.min(a - t);
                continue;
            } else if t > b {
                continue;
            }
            let Some(space) = grid.space else {
                return Region {
                    clear: false,
                    length: 0.0,
                };
            };
            let hi = grid.plan.dims.as_ivec3() - IVec3::ONE;
            let g = grid.plan.grid(p);
            let r = space.region(g, &Along::new(grid.plan.grid_direction(dir)), hi);
            if r.clear {
                clear = clear.min(r.length);
            } else {
                busy = busy.min(r.length);
            }
        }
        if busy < f32::INFINITY {
            Region {
                clear: false,
                length: busy,
            }
        } else {
            Region {
                clear: true,
                length: clear,
            }
        }
    }

    /// Opacity at `p` of every volume there, mixed: each volume's table
    /// opacity, corrected to a segment `length` world units long (`None`:
    /// as the table gives it, per unit distance).
    pub fn opacity(&self, p: Vec3, length: Option<f32>, samples: &mut u32) -> f32 {
        let mut mixture = Mixture::default();
        for grid in &self.grids {
            let g = grid.plan.grid(p);
            if !grid.contains(g) {
                continue;
            }
            *samples += 1;
            let a = grid.classify(grid.sample(g)).w;
            let a = match length {
                Some(l) => correct(a, l * grid.plan.inv_unit_distance),
                None => a,
            };
            mixture.add(Vec3::ZERO, a);
        }
        mixture.alpha
    }
}

/// Overlapping volumes at one sample, as one medium: their opacities
/// combine as independent absorbers (1 - product of transmittances) and
/// their colors in proportion to their opacities, so the result does not
/// depend on the volumes' order.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Mixture {
    /// Sum of color times opacity.
    emitted: Vec3,
    /// Sum of opacities.
    weight: f32,
    pub alpha: f32,
}

impl Mixture {
    pub fn add(&mut self, rgb: Vec3, a: f32) {
        self.emitted += rgb * a;
        self.weight += a;
        self.alpha += (1.0 - self.alpha) * a;
    }

    /// Straight color; meaningful once any opacity was added.
    pub fn color(&self) -> Vec3 {
        // One division, not three: this runs for every sample that shows.
        self.emitted * (1.0 / self.weight)
    }

    pub fn is_empty(&self) -> bool {
        self.weight <= 0.0
    }
}

/// WGSL's `mix`.
/// `n` as a unit vector on the side a ray of direction `dir` sees;
/// against the ray where `n` has no direction.
fn facing(n: Vec3, dir: Vec3) -> Vec3 {
    let n = n.normalize_or_zero();
    if n == Vec3::ZERO {
        return -dir.normalize_or_zero();
    }
    if n.dot(dir) > 0.0 {
        -n
    } else {
        n
    }
}

fn mix(a: f32, b: f32, t: f32) -> f32 {
    a * (1.0 - t) + b * t
}

/// Opacity of a segment `exponent` unit distances long whose per-unit
/// opacity is `a`: `1 - (1 - a)^exponent`.
pub(super) fn correct(a: f32, exponent: f32) -> f32 {
    if a >= 1.0 {
        1.0
    } else {
        1.0 - (1.0 - a).powf(exponent)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mixture_does_not_depend_on_order_and_one_volume_is_itself() {
        let red = (Vec3::X, 0.3);
        let blue = (Vec3::Z, 0.6);
        let (mut ab, mut ba, mut one) =
            (Mixture::default(), Mixture::default(), Mixture::default());
        ab.add(red.0, red.1);
        ab.add(blue.0, blue.1);
        ba.add(blue.0, blue.1);
        ba.add(red.0, red.1);
        one.add(red.0, red.1);
        assert!((ab.alpha - ba.alpha).abs() < 1e-6);
        assert!((ab.alpha - (1.0 - 0.7 * 0.4)).abs() < 1e-6);
        assert!((ab.color() - ba.color()).abs().max_element() < 1e-6);
        assert!((ab.color() - Vec3::new(1.0 / 3.0, 0.0, 2.0 / 3.0)).length() < 1e-6);
        assert_eq!(one.alpha, 0.3);
        assert!((one.color() - Vec3::X).length() < 1e-6);
    }
}
