//! Volumes read through a page table: a grid longer than the adapter's
//! largest 3D texture, or larger than its share of the GPU memory budget,
//! is cut into bricks at every level of its level-of-detail chain, and a
//! pool texture of fixed size holds those bricks the current view asks
//! for. Level l halves level l - 1 (each voxel the mean of the full-detail
//! voxels it covers), so the coarsest level is one brick, always resident;
//! each frame picks, coarse first and most visible first, the bricks to
//! hold (the finest the level of detail asks for, coarser where the pool
//! is full), a loader thread builds the missing ones from the host's
//! voxels (a mapped file stays mapped: only the bricks read are paged in),
//! and the frame renders what is resident: the shader reads each sample
//! from the finest resident level at or above the one it wants.
//!
//! Bricks carry a one-voxel apron on their high sides: every trilinear
//! cell whose low corner lies in a brick lies wholly in that brick's
//! texels, so the exact path reads its eight voxels from one brick and the
//! texture unit filters within one brick.

use std::collections::{BinaryHeap, VecDeque};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Instant;

use glam::{Mat4, UVec2, UVec3, Vec3};

use super::context::Context;
use super::volume_texture::{self, Texel, Writer, LOD_LEVELS};
use crate::render::empty_space::{BrickRanges, Visibility};
use crate::render::RenderError;
use crate::scene::{Scaling, Scene, SpatialField, StructuredVolume};

/// A brick's side in the pool, apron included, unless the adapter's
/// largest 3D texture is shorter.
const BRICK_TEXELS: u32 = 64;

/// Built bricks the loader keeps waiting for a frame at most, in bytes:
/// bounds the host memory streaming takes beyond the voxels.
const READY_BYTES: usize = 64 << 20;

/// How a paged volume's bricks are shaped and where the pool holds them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Pool {
    /// Voxels of its level a brick covers per axis: the whole axis where
    /// the full-detail grid fits in one brick (a thin grid is not padded
    /// to cubes).
    pub side: UVec3,
    /// A pool slot's texels per axis: the side, and the apron on the axes
    /// cut into several bricks.
    pub texels: UVec3,
    /// Slots per row and column of the pool texture.
    pub atlas: UVec2,
    pub slots: u32,
}

impl Pool {
    /// The brick shape for a grid of `dims` in textures of at most
    /// `max_side` texels a side (`forced`: a brick size in texels, for
    /// tests); None where no brick fits.
    pub fn shape(dims: UVec3, max_side: u32, forced: Option<u32>) -> Option<(UVec3, UVec3)> {
        let texels = forced.unwrap_or(BRICK_TEXELS).min(max_side);
        if texels < 2 {
            return None;
        }
        let side = UVec3::from_array(
            dims.to_array()
                .map(|n| if n <= texels { n } else { texels - 1 }),
        );
        let cut = UVec3::from_array(dims.to_array().map(|n| u32::from(n > texels)));
        Some((side, side + cut))
    }

    /// The most slots one pool texture of at most `max_side` texels a
    /// side holds.
    pub fn max_slots(texels: UVec3, max_side: u32) -> u64 {
        (UVec3::splat(max_side) / texels)
            .as_u64vec3()
            .element_product()
    }

    /// A pool of `slots` bricks of `texels`, packed into as few rows and
    /// layers as textures of `max_side` allow.
    pub fn new(side: UVec3, texels: UVec3, slots: u32, max_side: u32) -> Self {
        let per_axis = UVec3::splat(max_side) / texels;
        let count = u64::from(slots.max(1));
        let x = u64::from(per_axis.x).min(count);
        let y = u64::from(per_axis.y).min(count.div_ceil(x));
        let z = count.div_ceil(x * y);
        // No more rows, then no more columns, than the slots fill.
        let y = count.div_ceil(x * z);
        let x = count.div_ceil(y * z);
        Self {
            side,
            texels,
            atlas: UVec2::new(x as u32, y as u32),
            slots,
        }
    }

    /// The pool texture's size in texels.
    pub fn dims(self) -> UVec3 {
        let rows = self.atlas.x * self.atlas.y;
        UVec3::new(self.atlas.x, self.atlas.y, self.slots.max(1).div_ceil(rows)) * self.texels
    }

    /// Where slot k's first texel lies in the pool texture.
    pub fn place(self, k: u32) -> UVec3 {
        let (x, y) = (self.atlas.x, self.atlas.y);
        UVec3::new(k % x, (k / x) % y, k / (x * y)) * self.texels
    }

    pub fn slot_bytes(self, texel: Texel) -> u64 {
        self.texels.as_u64vec3().element_product() * texel.bytes()
    }
}

/// A brick of the level chain: `at` in bricks of level `level`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) struct Brick {
    pub level: u32,
    pub at: UVec3,
}

/// A grid's level chain cut into bricks of one shape, and where each
/// level's page entries start.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Pyramid {
    pub dims: UVec3,
    pub side: UVec3,
    /// Page entries of the levels below each level.
    first: Vec<u32>,
}

impl Pyramid {
    pub fn new(dims: UVec3, side: UVec3) -> Self {
        let mut first = vec![0];
        let mut level = 0;
        loop {
            let b = bricks_of(level_dims(dims, level), side);
            first.push(first[level as usize] + b.x * b.y * b.z);
            if b == UVec3::ONE {
                break;
            }
            level += 1;
        }
        first.pop();
        Self { dims, side, first }
    }

    pub fn levels(&self) -> u32 {
        self.first.len() as u32
    }

    /// Bricks of every level.
    pub fn count(&self) -> u32 {
        let top = self.levels() - 1;
        self.first[top as usize] + 1
    }

    pub fn level_dims(&self, level: u32) -> UVec3 {
        level_dims(self.dims, level)
    }

    pub fn bricks(&self, level: u32) -> UVec3 {
        bricks_of(self.level_dims(level), self.side)
    }

    pub fn root(&self) -> Brick {
        Brick {
            level: self.levels() - 1,
            at: UVec3::ZERO,
        }
    }

    /// Brick b's page entry: levels finest first, x fastest.
    pub fn page(&self, b: Brick) -> u32 {
        let n = self.bricks(b.level);
        self.first[b.level as usize] + b.at.x + n.x * (b.at.y + n.y * b.at.z)
    }

    pub fn brick(&self, page: u32) -> Brick {
        let level = self.first.partition_point(|&f| f <= page) as u32 - 1;
        let n = self.bricks(level);
        let k = page - self.first[level as usize];
        Brick {
            level,
            at: UVec3::new(k % n.x, (k / n.x) % n.y, k / (n.x * n.y)),
        }
    }

    /// The bricks of the next finer level a brick's voxels split into.
    pub fn children(&self, b: Brick) -> impl Iterator<Item = Brick> {
        let level = b.level.saturating_sub(1);
        let n = self.bricks(level);
        let lo = b.at * 2;
        let hi = (lo + UVec3::splat(2)).min(n);
        let none = b.level == 0;
        (lo.z..hi.z)
            .flat_map(move |z| (lo.y..hi.y).flat_map(move |y| (lo.x..hi.x).map(move |x| (x, y, z))))
            .filter(move |_| !none)
            .map(move |(x, y, z)| Brick {
                level,
                at: UVec3::new(x, y, z),
            })
    }

    /// The level's voxels brick b's texels hold: from `lo`, `count` of
    /// them (the texels past the level's last voxel repeat it).
    fn level_voxels(&self, b: Brick, texels: UVec3) -> (UVec3, UVec3) {
        let lo = b.at * self.side;
        let n = self.level_dims(b.level);
        (lo, (lo + texels).min(n) - lo)
    }

    /// The full-detail voxels brick b's texels cover: `lo..hi`.
    pub fn covered(&self, b: Brick, texels: UVec3) -> (UVec3, UVec3) {
        let (lo, count) = self.level_voxels(b, texels);
        let s = 1 << b.level;
        (lo * s, ((lo + count) * s).min(self.dims))
    }

    /// The page table as the shader reads it: one word per level, where
    /// its entries start (from the table's first word), then every entry:
    /// its slot + 1, or 0 where the brick is not resident.
    pub fn table(&self, slot_of: &[u32]) -> Vec<u32> {
        let levels = self.levels();
        let mut words: Vec<u32> = self.first.iter().map(|f| f + levels).collect();
        words.extend(
            slot_of
                .iter()
                .map(|&s| if s == NO_SLOT { 0 } else { s + 1 }),
        );
        words
    }
}

fn level_dims(dims: UVec3, level: u32) -> UVec3 {
    ((dims + UVec3::splat((1 << level) - 1)) >> level).max(UVec3::ONE)
}

fn bricks_of(dims: UVec3, side: UVec3) -> UVec3 {
    (dims + side - UVec3::ONE) / side
}

/// The level a pixel's footprint asks for at distance t, as the shader's
/// `lod_level` does, rounded to the finer level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Footprint {
    /// Level of detail (0: full detail everywhere).
    pub lod: f32,
    pub width: f32,
    pub spread: f32,
    pub step: f32,
}

impl Footprint {
    pub fn level(&self, t: f32) -> u32 {
        if self.lod <= 0.0 {
            return 0;
        }
        let footprint = self.width + t.max(0.0) * self.spread;
        let level = (self.lod * footprint / self.step).max(1.0).log2();
        (level.floor() as u32).min(LOD_LEVELS - 1)
    }
}

/// One placement of a paged grid, as a frame sees it.
pub(super) struct Sight {
    pub world_to_grid: Mat4,
    pub grid_to_world: Mat4,
    /// Which values its table shows.
    pub visible: Visibility,
}

/// What a frame asks of a paged volume: where its eyes are, what level
/// the footprint asks for, and how each placement shows it.
pub(super) struct View<'a> {
    pub eyes: &'a [Vec3],
    pub footprint: Footprint,
    pub sights: &'a [Sight],
}

impl View<'_> {
    /// The nearest any eye comes to the full-detail voxels `lo..hi`, in
    /// world units, and the world length of one full-detail voxel there
    /// (the longest axis).
    fn distance(&self, lo: UVec3, hi: UVec3) -> (f32, f32) {
        let mut nearest = f32::INFINITY;
        let mut voxel = 0.0f32;
        for s in self.sights {
            let m = &s.grid_to_world;
            voxel = voxel.max(
                m.x_axis
                    .truncate()
                    .length()
                    .max(m.y_axis.truncate().length())
                    .max(m.z_axis.truncate().length()),
            );
            for &eye in self.eyes {
                let g = s.world_to_grid.transform_point3(eye);
                // Vertex i at grid coordinate i; a voxel reaches half a
                // cell around it.
                let near = g.clamp(lo.as_vec3() - 0.5, hi.as_vec3() - 0.5);
                nearest = nearest.min(m.transform_point3(near).distance(eye));
            }
        }
        (nearest, voxel)
    }

    fn shows(&self, [lo, hi]: [f32; 2]) -> bool {
        self.sights.iter().any(|s| s.visible.shows(lo, hi))
    }
}

/// The bricks a frame holds in a pool of `capacity` slots: the root, then
/// coarse to fine, the refinements that matter most (visible bricks
/// before clear ones, then the largest voxels on screen), each brick's
/// children taken together, while the pool has room and the footprint
/// asks for finer detail. `ranges`: the values each block of the grid's
/// samples read (the empty-space grid's), which say which bricks are clear.
pub(super) fn select(
    pyramid: &Pyramid,
    texels: UVec3,
    capacity: u32,
    ranges: &BrickRanges,
    view: &View,
) -> Vec<Brick> {
    if capacity == 0 {
        return Vec::new();
    }
    let consider = |b: Brick, heap: &mut BinaryHeap<_>| {
        if b.level == 0 {
            return;
        }
        let (lo, hi) = pyramid.covered(b, texels);
        let (t, voxel) = view.distance(lo, hi);
        if b.level <= view.footprint.level(t) {
            return;
        }
        let visible = view.shows(ranges.covering(lo, hi));
        let size = voxel * (1 << b.level) as f32 / t.max(1e-6);
        // Visible first, then the largest voxels on screen (positive
        // floats order as their bits).
        heap.push(((visible, size.to_bits()), pyramid.page(b)));
    };
    let root = pyramid.root();
    let mut chosen = vec![root];
    let mut heap = BinaryHeap::new();
    consider(root, &mut heap);
    let mut used = 1u32;
    while let Some((_, page)) = heap.pop() {
        let b = pyramid.brick(page);
        let children: Vec<Brick> = pyramid.children(b).collect();
        if used + children.len() as u32 > capacity {
            continue;
        }
        used += children.len() as u32;
        for c in children {
            chosen.push(c);
            consider(c, &mut heap);
        }
    }
    chosen
}

/// A page with no slot.
const NO_SLOT: u32 = u32::MAX;

/// Which brick each pool slot holds, and when a frame last wanted it.
pub(super) struct Residency {
    /// Per page: its slot, or NO_SLOT.
    slot_of: Vec<u32>,
    /// Per slot: its page, or NO_SLOT.
    page_of: Vec<u32>,
    /// Per slot: the last frame that selected its brick.
    used: Vec<u64>,
    frame: u64,
}

impl Residency {
    pub fn new(pages: u32, slots: u32) -> Self {
        Self {
            slot_of: vec![NO_SLOT; pages as usize],
            page_of: vec![NO_SLOT; slots as usize],
            used: vec![0; slots as usize],
            frame: 0,
        }
    }

    pub fn resident(&self, page: u32) -> bool {
        self.slot_of[page as usize] != NO_SLOT
    }

    /// Marks the selection as wanted this frame (its slots are not
    /// reused for other bricks while it stands).
    pub fn want(&mut self, pyramid: &Pyramid, selection: &[Brick]) {
        self.frame += 1;
        for b in selection {
            let s = self.slot_of[pyramid.page(*b) as usize];
            if s != NO_SLOT {
                self.used[s as usize] = self.frame;
            }
        }
    }

    /// A slot for `page`: a free one, else the one whose brick was wanted
    /// longest ago, finest level first among equals; None where every
    /// slot holds a brick this frame wants.
    pub fn place(&mut self, page: u32) -> Option<u32> {
        if self.resident(page) {
            return None;
        }
        let slot = (0..self.page_of.len() as u32)
            .filter(|&s| self.used[s as usize] < self.frame || self.page_of[s as usize] == NO_SLOT)
            .min_by_key(|&s| {
                let p = self.page_of[s as usize];
                (p != NO_SLOT, self.used[s as usize], p)
            })?;
        let old = self.page_of[slot as usize];
        if old != NO_SLOT {
            self.slot_of[old as usize] = NO_SLOT;
        }
        self.page_of[slot as usize] = page;
        self.slot_of[page as usize] = slot;
        self.used[slot as usize] = self.frame;
        Some(slot)
    }

    pub fn slots(&self) -> &[u32] {
        &self.slot_of
    }
}

/// A brick built by the loader: its texels.
pub(super) struct Built {
    pub page: u32,
    pub bytes: Vec<u8>,
}

/// What the bricks are built from: the volume's voxels (full detail) and,
/// made in one pass over them, its coarser levels as texels in host memory
/// (a seventh of the voxels' bytes at most, in their format).
pub(super) struct Chain {
    texel: Texel,
    pyramid: Pyramid,
    texels: UVec3,
    /// Levels 1 and up: their texels, x fastest.
    levels: Vec<Vec<u8>>,
}

impl Chain {
    /// One pass over `volume`'s voxels: level 1 the mean of the (up to 8)
    /// voxels each of its voxels covers, each level after it of the level
    /// below. None where `stop` says so (asked once a slice).
    pub fn new(
        volume: &StructuredVolume,
        (texel, pyramid, texels): (Texel, Pyramid, UVec3),
        stop: &dyn Fn() -> bool,
    ) -> Option<Self> {
        let voxels = volume.voxels();
        let one = texel.bytes() as usize;
        let mut levels: Vec<Vec<u8>> = Vec::new();
        for l in 1..pyramid.levels() {
            let (from, to) = (pyramid.level_dims(l - 1), pyramid.level_dims(l));
            let below = levels.last();
            let value = |i: usize| match below {
                None => texel.read(voxels, i),
                Some(below) => texel.decode(&below[i * one..(i + 1) * one]),
            };
            let mut level = Vec::with_capacity(to.element_product() as usize * one);
            let slice = to.x as usize * to.y as usize;
            let mut sums = vec![0.0f64; slice];
            let mut counts = vec![0u32; slice];
            for z in 0..from.z {
                if stop() {
                    return None;
                }
                for y in 0..from.y {
                    let row = from.x as usize * (y as usize + from.y as usize * z as usize);
                    let out = to.x as usize * (y / 2) as usize;
                    for x in 0..from.x as usize {
                        sums[out + x / 2] += f64::from(value(row + x));
                        counts[out + x / 2] += 1;
                    }
                }
                if z % 2 == 1 || z + 1 == from.z {
                    for (s, c) in sums.iter_mut().zip(counts.iter_mut()) {
                        texel.write((*s / f64::from((*c).max(1))) as f32, &mut level);
                        *s = 0.0;
                        *c = 0;
                    }
                }
            }
            levels.push(level);
        }
        Some(Self {
            texel,
            pyramid,
            texels,
            levels,
        })
    }

    /// Bytes the coarser levels take in host memory.
    pub fn bytes(&self) -> u64 {
        self.levels.iter().map(|l| l.len() as u64).sum()
    }

    /// Brick `b`'s texels: full detail copied from the voxels, coarser
    /// levels from the chain; texels past the level's last voxel repeat
    /// it.
    pub fn build(&self, volume: &StructuredVolume, b: Brick) -> Built {
        let (texel, texels) = (self.texel, self.texels);
        let p = &self.pyramid;
        let (lo, count) = p.level_voxels(b, texels);
        let n = p.level_dims(b.level);
        let one = texel.bytes() as usize;
        let mut bytes = Vec::with_capacity(texels.element_product() as usize * one);
        for z in 0..texels.z {
            for y in 0..texels.y {
                let (gy, gz) = (lo.y + y.min(count.y - 1), lo.z + z.min(count.z - 1));
                let row = lo.x as usize + n.x as usize * (gy as usize + n.y as usize * gz as usize);
                let end = bytes.len() + texels.x as usize * one;
                let span = row..row + count.x as usize;
                match b.level {
                    0 => texel.encode(volume.voxels(), span, &mut bytes),
                    l => bytes.extend_from_slice(
                        &self.levels[l as usize - 1][span.start * one..span.end * one],
                    ),
                }
                let edge = bytes.len() - one;
                while bytes.len() < end {
                    bytes.extend_from_within(edge..edge + one);
                }
            }
        }
        Built {
            page: p.page(b),
            bytes,
        }
    }
}

/// Builds the bricks a paged volume asks for on a thread of its own: first
/// the chain (one pass over the voxels), then the bricks in the order
/// asked, keeping at most READY_BYTES built for the frames to take. Where
/// no thread can be started, the chain is made here and the frames build
/// what they need themselves.
pub(super) struct Loader {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    /// Without a thread: the volume and its chain.
    inline: Option<(Arc<StructuredVolume>, Chain)>,
}

#[derive(Default)]
struct Shared {
    state: Mutex<LoadState>,
    /// Signalled when bricks are asked for, taken, or the loader stops.
    asked: Condvar,
    /// Signalled when a brick is built or the queue runs dry.
    built: Condvar,
}

#[derive(Default)]
struct LoadState {
    wanted: VecDeque<u32>,
    /// The page being built now.
    busy: Option<u32>,
    /// Whether the chain is still being made.
    chaining: bool,
    /// Bytes the chain's coarser levels hold, once made.
    chain_bytes: u64,
    ready: Vec<Built>,
    ready_bytes: usize,
    stop: bool,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, LoadState> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Loader {
    pub fn start(
        volume: Arc<StructuredVolume>,
        texel: Texel,
        pyramid: Pyramid,
        texels: UVec3,
    ) -> Self {
        let shared = Arc::new(Shared::default());
        shared.lock().chaining = true;
        let thread = {
            let (shared, volume, pyramid) =
                (Arc::clone(&shared), Arc::clone(&volume), pyramid.clone());
            std::thread::Builder::new()
                .name("caveray-bricks".into())
                .spawn(move || {
                    let stop = || shared.lock().stop;
                    // This thread reads the voxels outside any render: it
                    // is a reader of a host's memory while it does.
                    let reading = || volume.voxels().lender().map(|l| l.reading());
                    let started = reading();
                    let Some(chain) = Chain::new(&volume, (texel, pyramid, texels), &stop) else {
                        return;
                    };
                    drop(started);
                    {
                        let mut s = shared.lock();
                        s.chaining = false;
                        s.chain_bytes = chain.bytes();
                    }
                    loop {
                        let page = {
                            let mut s = shared.lock();
                            loop {
                                if s.stop {
                                    return;
                                }
                                if s.ready_bytes < READY_BYTES {
                                    if let Some(p) = s.wanted.pop_front() {
                                        s.busy = Some(p);
                                        break p;
                                    }
                                }
                                shared.built.notify_all();
                                s = shared.asked.wait(s).unwrap_or_else(|e| e.into_inner());
                            }
                        };
                        let held = reading();
                        let built = chain.build(&volume, chain.pyramid.brick(page));
                        drop(held);
                        let mut s = shared.lock();
                        s.busy = None;
                        s.ready_bytes += built.bytes.len();
                        s.ready.push(built);
                        shared.built.notify_all();
                    }
                })
                .ok()
        };
        let inline = match thread {
            Some(_) => None,
            None => Chain::new(&volume, (texel, pyramid, texels), &|| false).map(|chain| {
                let mut s = shared.lock();
                s.chaining = false;
                s.chain_bytes = chain.bytes();
                drop(s);
                (volume, chain)
            }),
        };
        Self {
            shared,
            thread,
            inline,
        }
    }

    /// Asks for `pages`, in this order, instead of what was asked before
    /// (bricks built or being built are not asked again).
    pub fn ask(&self, pages: &[u32]) {
        let mut s = self.shared.lock();
        let busy = s.busy;
        let ready: Vec<u32> = s.ready.iter().map(|b| b.page).collect();
        s.wanted = pages
            .iter()
            .copied()
            .filter(|p| Some(*p) != busy && !ready.contains(p))
            .collect();
        self.shared.asked.notify_all();
    }

    /// The bricks built so far, waiting (until `until`, or for as long as
    /// it takes where None) for one if none is and some are asked for.
    /// Without a thread, builds those asked for here.
    pub fn take(&self, until: Option<Instant>) -> Vec<Built> {
        if let Some((volume, chain)) = &self.inline {
            let wanted = std::mem::take(&mut self.shared.lock().wanted);
            return wanted
                .into_iter()
                .map(|p| chain.build(volume, chain.pyramid.brick(p)))
                .collect();
        }
        if self.thread.is_none() {
            return Vec::new();
        }
        let mut s = self.shared.lock();
        while s.ready.is_empty() && (s.chaining || s.busy.is_some() || !s.wanted.is_empty()) {
            s = match until {
                None => self.shared.built.wait(s).unwrap_or_else(|e| e.into_inner()),
                Some(t) => {
                    let now = Instant::now();
                    if now >= t {
                        break;
                    }
                    self.shared
                        .built
                        .wait_timeout(s, t - now)
                        .unwrap_or_else(|e| e.into_inner())
                        .0
                }
            };
        }
        s.ready_bytes = 0;
        let ready = std::mem::take(&mut s.ready);
        self.shared.asked.notify_all();
        ready
    }

    /// Bytes the chain's coarser levels hold in host memory (0 until
    /// made).
    pub fn chain_bytes(&self) -> u64 {
        self.shared.lock().chain_bytes
    }
}

impl Drop for Loader {
    fn drop(&mut self) {
        self.shared.lock().stop = true;
        self.shared.asked.notify_all();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// How long a frame may wait for bricks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StreamWait {
    /// Until every brick it selected is resident: complete frames.
    Complete,
    /// At most `wait` (after the coarsest level, which the first frame
    /// waits for), uploading at most `bricks` bricks: later frames
    /// refine.
    Budget {
        wait: std::time::Duration,
        bricks: u32,
    },
}

/// How far a frame's paged volumes were from what it selected.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Streaming {
    /// Bricks the frame's views asked for, over every paged volume.
    pub wanted: u32,
    /// Of those, the resident ones it rendered with.
    pub resident: u32,
    /// Bricks uploaded for this frame.
    pub uploaded: u32,
}

impl Streaming {
    /// The fraction of the bricks asked for that were resident (1 where
    /// nothing is paged).
    pub fn progress(&self) -> f32 {
        if self.wanted == 0 {
            1.0
        } else {
            self.resident as f32 / self.wanted as f32
        }
    }

    pub fn add(&mut self, other: Streaming) {
        self.wanted += other.wanted;
        self.resident += other.resident;
        self.uploaded += other.uploaded;
    }
}

/// A paged volume on the GPU: its pool texture, page table state and
/// loader.
pub(super) struct PagedVolume {
    pub view: wgpu::TextureView,
    texture: wgpu::Texture,
    pub pool: Pool,
    pub pyramid: Pyramid,
    texel: Texel,
    pub to_value: Scaling,
    residency: Residency,
    loader: Loader,
    /// Built bricks past a frame's upload limit, for the next frames.
    pending: VecDeque<Built>,
    /// Whether the page table changed since the scene last wrote it.
    pub dirty: bool,
}

impl PagedVolume {
    /// The pool texture for `pool` (nothing resident yet) and a loader
    /// for `volume`'s bricks; refused as out of memory where the adapter
    /// cannot allocate it.
    pub fn new(
        ctx: &Context,
        volume: &Arc<StructuredVolume>,
        pool: Pool,
    ) -> Result<Self, RenderError> {
        let texel = Texel::of(volume.voxels(), ctx.norm16);
        let pyramid = Pyramid::new(volume.dims(), pool.side);
        let texture = volume_texture::allocate(ctx, pool.dims(), 1, texel, "brick pool")?;
        let residency = Residency::new(pyramid.count(), pool.slots);
        let loader = Loader::start(Arc::clone(volume), texel, pyramid.clone(), pool.texels);
        Ok(Self {
            view: texture.create_view(&Default::default()),
            texture,
            pool,
            to_value: texel.to_value(volume.scaling()),
            texel,
            residency,
            loader,
            pending: VecDeque::new(),
            pyramid,
            dirty: true,
        })
    }

    pub fn bytes(&self) -> u64 {
        u64::from(self.pool.slots) * self.pool.slot_bytes(self.texel)
    }

    /// Bytes its coarser levels take in host memory, once made.
    pub fn host_bytes(&self) -> u64 {
        self.loader.chain_bytes()
    }

    /// Selects what `view` asks for, uploads what the loader has built
    /// (waiting as `wait` says) and counts how much of the selection is
    /// resident.
    pub fn stream(
        &mut self,
        ctx: &Context,
        (view, ranges): (&View, &BrickRanges),
        wait: StreamWait,
        until: Instant,
    ) -> Result<Streaming, RenderError> {
        let mut uploaded = 0;
        let mut writer = Writer::new(ctx, &self.texture, self.texel);
        loop {
            let selection = select(
                &self.pyramid,
                self.pool.texels,
                self.pool.slots,
                ranges,
                view,
            );
            self.residency.want(&self.pyramid, &selection);
            let missing: Vec<u32> = selection
                .iter()
                .map(|b| self.pyramid.page(*b))
                .filter(|&p| !self.residency.resident(p))
                .collect();
            let root = self.pyramid.page(self.pyramid.root());
            let (deadline, limit) = match wait {
                StreamWait::Complete => (None, u32::MAX),
                StreamWait::Budget { bricks, .. } if !self.residency.resident(root) => {
                    (None, bricks.max(1))
                }
                StreamWait::Budget { bricks, .. } => (Some(until), bricks),
            };
            self.loader.ask(&missing);
            if self.pending.is_empty() && !missing.is_empty() && uploaded < limit {
                self.pending.extend(self.loader.take(deadline));
            }
            let selected: std::collections::HashSet<u32> =
                selection.iter().map(|b| self.pyramid.page(*b)).collect();
            let mut got = 0;
            while uploaded < limit {
                let Some(b) = self.pending.pop_front() else {
                    break;
                };
                got += 1;
                // A brick an earlier frame asked for and this one does not
                // leaves the slots to those it does.
                if !selected.contains(&b.page) {
                    continue;
                }
                if let Some(slot) = self.residency.place(b.page) {
                    writer.put(0, self.pool.place(slot), self.pool.texels, &b.bytes)?;
                    uploaded += 1;
                    self.dirty = true;
                }
            }
            let resident = selection
                .iter()
                .filter(|b| self.residency.resident(self.pyramid.page(**b)))
                .count() as u32;
            let done = resident as usize == selection.len();
            let late = matches!(wait, StreamWait::Budget { .. })
                && self.residency.resident(root)
                && (Instant::now() >= until || uploaded >= limit);
            if done || late || got == 0 {
                // What is staged (under UPLOAD_BYTES) goes with the
                // frame's own submission: no wait here.
                return Ok(Streaming {
                    wanted: selection.len() as u32,
                    resident,
                    uploaded,
                });
            }
        }
    }

    /// The page table words (Pyramid::table).
    pub fn table(&self) -> Vec<u32> {
        self.pyramid.table(self.residency.slots())
    }
}

/// How one grid of a scene goes to the GPU.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) enum Layout {
    /// One texture (with mips where level of detail asks for them).
    Whole { bytes: u64 },
    /// Paged through a pool.
    Paged { pool: Pool, bytes: u64 },
    /// An unstructured field's words in the meshes buffer (gpu/mesh.rs).
    Cells { bytes: u64 },
}

impl Layout {
    pub fn bytes(&self) -> u64 {
        match self {
            Layout::Whole { bytes } | Layout::Paged { bytes, .. } | Layout::Cells { bytes } => {
                *bytes
            }
        }
    }
}

/// Words a mesh, an AMR field or a NanoVDB grid takes in the meshes
/// buffer; none for a grid.
fn cell_words(field: &SpatialField) -> u64 {
    match field {
        SpatialField::Unstructured(m) => super::mesh::word_count(m),
        SpatialField::Amr(a) => super::amr::word_count(a),
        SpatialField::NanoVdb(g) => super::nanovdb::word_count(g),
        SpatialField::Structured(_) => 0,
    }
}

/// How each of the scene's grids (Scene::grids order) goes to the GPU:
/// whole where it fits the adapter's textures and the scene fits the
/// memory budget; paged otherwise, each paged grid's pool its share of the
/// budget (by its full size) or, without one, room for its whole level
/// chain as far as one pool texture allows. Refused, before anything is
/// allocated, where a pool could not hold even the coarsest brick.
pub(super) fn layouts(ctx: &Context, scene: &Scene) -> Result<Vec<Layout>, RenderError> {
    let max = ctx.limits.max_texture_dimension_3d;
    let fields: Vec<&Arc<SpatialField>> = scene.grids().collect();
    // Meshes and AMR fields go whole into one buffer, whatever the budget
    // says of grids.
    let mesh_words: u64 = fields.iter().map(|f| cell_words(f)).sum();
    super::mesh::check(ctx, mesh_words)?;
    let grids: Vec<Option<&StructuredVolume>> = fields.iter().map(|f| f.structured()).collect();
    let whole: Vec<u64> = grids
        .iter()
        .map(|g| {
            g.map_or(0, |g| {
                let texel = Texel::of(g.voxels(), ctx.norm16);
                g.dims().as_u64vec3().element_product() * texel.bytes()
            })
        })
        .collect();
    let must_page =
        |g: &StructuredVolume| ctx.brick_texels.is_some() || g.dims().max_element() > max;
    let over = ctx
        .budget()
        .is_some_and(|budget| whole.iter().sum::<u64>() > budget);
    let total: u64 = whole.iter().sum();
    let mut out = Vec::with_capacity(grids.len());
    for ((field, g), &bytes) in fields.iter().zip(&grids).zip(&whole) {
        let Some(g) = g else {
            out.push(Layout::Cells {
                bytes: 4 * cell_words(field),
            });
            continue;
        };
        if !over && !must_page(g) {
            out.push(Layout::Whole { bytes });
            continue;
        }
        let dims = g.dims();
        let (side, texels) = Pool::shape(dims, max, ctx.brick_texels).ok_or_else(|| {
            RenderError::VolumeTooLarge {
                dims: dims.to_array(),
                max,
                adapter: ctx.info.name.clone(),
            }
        })?;
        let pyramid = Pyramid::new(dims, side);
        let texel = Texel::of(g.voxels(), ctx.norm16);
        let slot = texels.as_u64vec3().element_product() * texel.bytes();
        let mut slots = u64::from(pyramid.count()).min(Pool::max_slots(texels, max));
        if over {
            let budget = ctx.budget().unwrap_or(u64::MAX);
            let share = (u128::from(budget) * u128::from(bytes) / u128::from(total.max(1))) as u64;
            // The page table comes out of the share too.
            let table = 4 * u64::from(pyramid.levels() + pyramid.count());
            slots = slots.min(share.saturating_sub(table) / slot);
        }
        if slots == 0 {
            return Err(RenderError::OutOfMemory {
                bytes: slot,
                what: format!(
                    "one {}x{}x{} brick of a {}x{}x{} volume, past its share of the GPU memory budget of {} bytes",
                    texels.x,
                    texels.y,
                    texels.z,
                    dims.x,
                    dims.y,
                    dims.z,
                    ctx.budget().unwrap_or(0)
                ),
            });
        }
        let pool = Pool::new(side, texels, slots as u32, max);
        out.push(Layout::Paged {
            pool,
            bytes: slots * slot,
        });
    }
    Ok(out)
}

/// Whether one of the scene's grids is paged on this adapter (its
/// shaders then need the page arithmetic).
pub(super) fn any_paged(ctx: &Context, scene: &Scene) -> bool {
    layouts(ctx, scene).is_ok_and(|l| l.iter().any(|l| matches!(l, Layout::Paged { .. })))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{TransferFunction, Voxels, TABLE_SIZE};

    #[test]
    fn a_pyramid_halves_to_one_brick_and_numbers_its_pages() {
        let p = Pyramid::new(UVec3::new(200, 100, 30), UVec3::new(63, 63, 30));
        assert_eq!(p.bricks(0), UVec3::new(4, 2, 1));
        assert_eq!(p.level_dims(1), UVec3::new(100, 50, 15));
        assert_eq!(p.bricks(1), UVec3::new(2, 1, 1));
        assert_eq!(p.bricks(2), UVec3::ONE);
        assert_eq!(p.levels(), 3);
        assert_eq!(p.count(), 8 + 2 + 1);
        for page in 0..p.count() {
            assert_eq!(p.page(p.brick(page)), page);
        }
        let kids: Vec<Brick> = p.children(p.root()).collect();
        assert_eq!(kids.len(), 2);
        assert!(kids.iter().all(|k| k.level == 1));
        let kids: Vec<Brick> = p.children(kids[1]).collect();
        assert_eq!(kids.len(), 4, "{kids:?}");
        // Every full-detail voxel is covered by the children together.
        let (lo, hi) = p.covered(p.root(), UVec3::new(64, 64, 30));
        assert_eq!((lo, hi), (UVec3::ZERO, UVec3::new(200, 100, 30)));
    }

    #[test]
    fn a_pool_packs_its_slots_within_the_texture_limit() {
        let pool = Pool::new(UVec3::splat(63), UVec3::splat(64), 60, 256);
        let d = pool.dims();
        assert!(d.max_element() <= 256, "{d}");
        let places: std::collections::HashSet<_> = (0..60).map(|k| pool.place(k)).collect();
        assert_eq!(places.len(), 60);
        assert!((0..60).all(|k| (pool.place(k) + pool.texels).cmple(d).all()));
        assert_eq!(Pool::max_slots(UVec3::splat(64), 256), 64);
    }

    #[test]
    fn grids_that_fit_one_brick_on_an_axis_are_not_padded() {
        let (side, texels) = Pool::shape(UVec3::new(1 << 22, 1, 3), 2048, None).unwrap();
        assert_eq!(side, UVec3::new(63, 1, 3));
        assert_eq!(texels, UVec3::new(64, 1, 3));
        assert_eq!(Pool::shape(UVec3::splat(4), 1, None), None);
    }

    fn ramp_volume(dims: UVec3) -> StructuredVolume {
        let n = dims.element_product() as usize;
        let v: Vec<f32> = (0..n).map(|i| (i % 97) as f32).collect();
        StructuredVolume::new(dims, Voxels::F32(v.into()), Vec3::ZERO, Vec3::ONE).unwrap()
    }

    #[test]
    fn a_coarse_brick_holds_the_means_of_the_voxels_it_covers() {
        let dims = UVec3::new(9, 5, 4);
        let volume = ramp_volume(dims);
        let p = Pyramid::new(dims, UVec3::new(3, 3, 3));
        let texels = UVec3::splat(4);
        let b = Brick {
            level: 1,
            at: UVec3::new(1, 0, 0),
        };
        let built = Chain::new(&volume, (Texel::Float, p.clone(), texels), &|| false)
            .unwrap()
            .build(&volume, b);
        let values: Vec<f32> = built
            .bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        assert_eq!(values.len(), 64);
        // Level-1 voxel (3, 0, 0) covers full-detail x 6..8, y 0..2, z 0..2.
        let at = |x: u32, y: u32, z: u32| volume.value((x + 9 * (y + 5 * z)) as usize);
        let mut sum = 0.0;
        for z in 0..2 {
            for y in 0..2 {
                for x in 6..8 {
                    sum += at(x, y, z);
                }
            }
        }
        assert!((values[0] - sum / 8.0).abs() < 1e-4);
        // Level-1 x runs 0..5; the brick holds 3 and 4, then repeats 4
        // (which covers the last full-detail voxel, x 8, alone).
        let last = (at(8, 0, 0) + at(8, 1, 0) + at(8, 0, 1) + at(8, 1, 1)) / 4.0;
        assert!((values[1] - last).abs() < 1e-4, "{} {last}", values[1]);
        assert_eq!(values[1], values[2]);
        // Level 2 is the mean of level 1's voxels: (0, 0, 0) of level 1's
        // (0..2, 0..2, 0..2).
        let chain = Chain::new(&volume, (Texel::Float, p.clone(), texels), &|| false).unwrap();
        let level1 = |x: usize, y: usize, z: usize| {
            let i = x + 5 * (y + 3 * z);
            f32::from_le_bytes(chain.levels[0][4 * i..4 * i + 4].try_into().unwrap())
        };
        let mean = (0..8)
            .map(|k| level1(k & 1, k >> 1 & 1, k >> 2))
            .sum::<f32>()
            / 8.0;
        let top = chain.build(&volume, p.root());
        let first = f32::from_le_bytes(top.bytes[..4].try_into().unwrap());
        assert!((first - mean).abs() < 1e-4, "{first} {mean}");
    }

    fn view_of<'a>(eyes: &'a [Vec3], sights: &'a [Sight], lod: f32) -> View<'a> {
        View {
            eyes,
            footprint: Footprint {
                lod,
                width: 0.0,
                spread: 0.01,
                step: 1.0,
            },
            sights,
        }
    }

    fn sight(visible_from: f32) -> Sight {
        let tf = TransferFunction::new(vec![glam::Vec4::ONE; 2], vec![0.0, 1.0], (0.0, 100.0), 1.0)
            .unwrap();
        let mut table = tf.table();
        for (i, c) in table.iter_mut().enumerate() {
            c.w = if (i as f32) < visible_from * (TABLE_SIZE - 1) as f32 / 100.0 {
                0.0
            } else {
                1.0
            };
        }
        Sight {
            world_to_grid: Mat4::IDENTITY,
            grid_to_world: Mat4::IDENTITY,
            visible: Visibility::new(&table, 0.0, 0.01),
        }
    }

    #[test]
    fn selection_refines_the_nearest_bricks_first_within_the_pool() {
        let dims = UVec3::new(256, 64, 64);
        let p = Pyramid::new(dims, UVec3::splat(63));
        let texels = UVec3::splat(64);
        let ranges = BrickRanges::new(dims, |_| 50.0).unwrap();
        let sights = [sight(0.0)];
        let eyes = [Vec3::new(-100.0, 32.0, 32.0)];
        let view = view_of(&eyes, &sights, 0.0);
        // Everything fits: the whole chain is selected.
        let all = select(&p, texels, p.count(), &ranges, &view);
        assert_eq!(all.len() as u32, p.count());
        // Levels 3 to 1 take 1 + 2 + 3 bricks; room for one more
        // refinement: the level-1 brick nearest the eye (low x).
        let some = select(&p, texels, 14, &ranges, &view);
        assert_eq!(some.len(), 14);
        assert_eq!(some[0], p.root());
        let fine: Vec<&Brick> = some.iter().filter(|b| b.level == 0).collect();
        assert_eq!(fine.len(), 8);
        assert!(fine.iter().all(|b| b.at.x <= 1), "{some:?}");
        // Under level of detail, far bricks stay coarse.
        let lod = view_of(&eyes, &sights, 400.0);
        let coarse = select(&p, texels, p.count(), &ranges, &lod);
        assert!(coarse.len() < all.len());
    }

    #[test]
    fn clear_bricks_are_refined_after_those_that_show() {
        // Values 0 where x < 200, 100 beyond: the table shows 50 and up,
        // so the level-1 brick nearest the eye (full-detail x 0..128) is
        // clear.
        let dims = UVec3::new(256, 64, 64);
        let ranges = BrickRanges::new(dims, |i| if i % 256 < 200 { 0.0 } else { 100.0 }).unwrap();
        let p = Pyramid::new(dims, UVec3::splat(63));
        let texels = UVec3::splat(64);
        let sights = [sight(50.0)];
        // The eye nearer the clear half: distance alone would refine it
        // first.
        let eyes = [Vec3::new(-100.0, 32.0, 32.0)];
        let view = view_of(&eyes, &sights, 0.0);
        let some = select(&p, texels, 14, &ranges, &view);
        let fine: Vec<&Brick> = some.iter().filter(|b| b.level == 0).collect();
        assert_eq!(fine.len(), 8, "{some:?}");
        // The refined level-1 brick is one that shows (its voxels reach
        // x >= 200): level-0 bricks from x = 2 on.
        assert!(fine.iter().all(|b| b.at.x >= 2), "{some:?}");
        // With room for all, clear bricks come too.
        assert_eq!(
            select(&p, texels, p.count(), &ranges, &view).len() as u32,
            p.count()
        );
    }

    #[test]
    fn a_full_pool_evicts_what_the_frame_does_not_want_longest_unwanted_first() {
        let p = Pyramid::new(UVec3::new(126, 63, 63), UVec3::splat(63));
        let mut r = Residency::new(p.count(), 2);
        let [a, b, c] = [0, 1, 2];
        r.want(&p, &[]);
        assert_eq!(r.place(a), Some(0));
        assert_eq!(r.place(b), Some(1));
        // A frame that wants both leaves no room for c.
        r.want(&p, &[p.brick(a), p.brick(b)]);
        assert_eq!(r.place(c), None);
        // One that wants a and c evicts b.
        r.want(&p, &[p.brick(a), p.brick(c)]);
        assert_eq!(r.place(c), Some(1));
        assert!(r.resident(a) && r.resident(c) && !r.resident(b));
        let table = p.table(r.slots());
        assert_eq!(&table[..2], &[2, 4]);
        assert_eq!(&table[2..], &[1, 0, 2]);
    }

    #[test]
    fn the_loader_builds_what_it_is_asked_for() {
        let dims = UVec3::new(20, 10, 10);
        let volume = Arc::new(ramp_volume(dims));
        let p = Pyramid::new(dims, UVec3::splat(7));
        let texels = UVec3::splat(8);
        let loader = Loader::start(Arc::clone(&volume), Texel::Float, p.clone(), texels);
        let pages: Vec<u32> = (0..p.count()).collect();
        loader.ask(&pages);
        let mut got = Vec::new();
        while got.len() < pages.len() {
            let batch = loader.take(None);
            assert!(!batch.is_empty());
            got.extend(batch);
        }
        let mut seen: Vec<u32> = got.iter().map(|b| b.page).collect();
        seen.sort_unstable();
        assert_eq!(seen, pages);
        let chain = Chain::new(&volume, (Texel::Float, p.clone(), texels), &|| false).unwrap();
        for b in &got {
            let want = chain.build(&volume, p.brick(b.page));
            assert_eq!(b.bytes, want.bytes);
        }
    }
}
