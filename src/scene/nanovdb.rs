//! NanoVDB grids (KHR_SPATIAL_FIELD_NANOVDB): one grid exactly as the
//! NanoVDB library lays it out in memory, kept as it is (one copy, no
//! conversion) and read through its own tree. Layout version
//! 32 (NanoVDB 32.x keeps its ABI within a major version; the offsets
//! below are those of PNanoVDB.h, which states them for every version
//! 32 release).
//!
//! A grid is a tree of fixed depth below a root: the root's tiles each
//! cover 4096^3 voxels and hold an upper node or one value; an upper node
//! holds 32^3 entries of 128^3 voxels, each a lower node or one value; a
//! lower node 16^3 entries of 8^3 voxels, each a leaf or one value; a
//! leaf 8^3 values. Voxels are vertex-centred: voxel (i, j, k)'s value
//! lies at index point (i, j, k), so linear filtering is trilinear
//! between the eight voxels around a point, as NanoVDB's own sampler
//! reads it. Every voxel has a value: where no leaf is, its tile's, and
//! beyond every tile the background.
//!
//! The whole tree is walked once when a grid is made: every offset must
//! land inside the grid on a node of the level below (nodes of a level
//! lie in one section, one after another), and no node may be reached
//! twice, so a blob with offsets past its end, into the wrong level or
//! in a cycle is refused with the reason, and reading a sample later
//! never leaves the grid. The GPU reads the same words (gpu/nanovdb.rs).
//!
//! Rays march the grid's active box (the root's bounding box) on a
//! lattice of its voxels; the index-to-world map places the lattice.

use std::cell::Cell;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use glam::{DVec3, IVec3, UVec3, Vec3};
use thiserror::Error;

use super::volume::Filter;

/// "NanoVDB0", little-endian: the first eight bytes of a grid (and of a
/// file's segments) up to NanoVDB 32.5.
pub const NANOVDB_MAGIC: u64 = 0x3042_4456_6f6e_614e;
/// "NanoVDB1": a grid's first eight bytes from NanoVDB 32.6 on.
pub const NANOVDB_MAGIC_GRID: u64 = 0x3142_4456_6f6e_614e;
/// "NanoVDB2": a file's segments' from NanoVDB 32.6 on.
pub const NANOVDB_MAGIC_FILE: u64 = 0x3242_4456_6f6e_614e;
/// The layout version read: NanoVDB keeps its ABI within a major version.
pub const NANOVDB_MAJOR: u32 = 32;

const GRID_SIZE: usize = 672;
const TREE_SIZE: usize = 64;
const GRID_OFF_NAME: usize = 40;
const GRID_OFF_MAP: usize = 296;
const GRID_OFF_CLASS: usize = 632;
const GRID_OFF_TYPE: usize = 636;
const MAP_OFF_MATD: usize = 88;
const MAP_OFF_VECD: usize = 232;
const ROOT_OFF_TABLE_SIZE: usize = 24;
const ROOT_OFF_BACKGROUND: usize = 28;
const ROOT_SIZE: usize = 64;
const ROOT_TILE_SIZE: usize = 32;
const ROOT_TILE_OFF_CHILD: usize = 8;
const ROOT_TILE_OFF_STATE: usize = 16;
const ROOT_TILE_OFF_VALUE: usize = 20;
/// Node layouts shared by every value type read here: where the child
/// masks and the tables of children and tiles begin (bytes from the
/// node), and a node's size.
pub const UPPER_OFF_CHILD_MASK: usize = 4128;
pub const UPPER_OFF_TABLE: usize = 8256;
const UPPER_SIZE: usize = 270_400;
pub const LOWER_OFF_CHILD_MASK: usize = 544;
pub const LOWER_OFF_TABLE: usize = 1088;
const LOWER_SIZE: usize = 33_856;
pub const LEAF_OFF_TABLE: usize = 96;
/// Voxels a lattice may hold: as many as a structured grid.
const MAX_LATTICE_VOXELS: u64 = 1 << 32;
/// Index coordinates are sampled in single precision: the active box
/// must lie within +-2^24, where every integer is exact.
const MAX_INDEX: i32 = 1 << 24;
/// Where index points are clamped to before floor: far past any tile a
/// sample reads, well within i32.
const FAR: f32 = (1u32 << 30) as f32;

/// NanoVDB's grid type codes, by name, for errors.
pub const VDB_TYPE_NAMES: [&str; 27] = [
    "Unknown",
    "Float",
    "Double",
    "Int16",
    "Int32",
    "Int64",
    "Vec3f",
    "Vec3d",
    "Mask",
    "Half",
    "UInt32",
    "Boolean",
    "RGBA8",
    "Fp4",
    "Fp8",
    "Fp16",
    "FpN",
    "Vec4f",
    "Vec4d",
    "Index",
    "OnIndex",
    "IndexMask",
    "OnIndexMask",
    "PointIndex",
    "Vec3u8",
    "Vec3u16",
    "UInt8",
];
const CLASS_NAMES: [&str; 10] = [
    "Unknown",
    "LevelSet",
    "FogVolume",
    "Staggered",
    "PointIndex",
    "PointData",
    "Topology",
    "VoxelVolume",
    "IndexGrid",
    "TensorGrid",
];

/// How a grid's leaves store their values (the scalar grid types read).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VdbValues {
    Float,
    /// IEEE binary16.
    Half,
    /// Quantized: code * quantum + minimum, per leaf, 4, 8 or 16 bits.
    Fp4,
    Fp8,
    Fp16,
}

impl VdbValues {
    fn of(code: u32) -> Result<Self, NanoVdbError> {
        Ok(match code {
            1 => VdbValues::Float,
            9 => VdbValues::Half,
            13 => VdbValues::Fp4,
            14 => VdbValues::Fp8,
            15 => VdbValues::Fp16,
            other => {
                return Err(NanoVdbError::GridType {
                    name: VDB_TYPE_NAMES
                        .get(other as usize)
                        .map(|n| n.to_string())
                        .unwrap_or_else(|| format!("type {other}")),
                })
            }
        })
    }

    /// NanoVDB's name of the type.
    pub fn name(self) -> &'static str {
        match self {
            VdbValues::Float => "Float",
            VdbValues::Half => "Half",
            VdbValues::Fp4 => "Fp4",
            VdbValues::Fp8 => "Fp8",
            VdbValues::Fp16 => "Fp16",
        }
    }

    /// The code the GPU switches on (shaders/nanovdb.wgsl).
    pub fn code(self) -> u32 {
        match self {
            VdbValues::Float => 0,
            VdbValues::Half => 1,
            VdbValues::Fp4 => 2,
            VdbValues::Fp8 => 3,
            VdbValues::Fp16 => 4,
        }
    }

    fn leaf_size(self) -> usize {
        match self {
            VdbValues::Float => 2144,
            VdbValues::Half | VdbValues::Fp16 => 1120,
            VdbValues::Fp4 => 352,
            VdbValues::Fp8 => 608,
        }
    }

    /// Bits of a quantized code, or None for Float and Half.
    fn code_bits(self) -> Option<u32> {
        match self {
            VdbValues::Fp4 => Some(4),
            VdbValues::Fp8 => Some(8),
            VdbValues::Fp16 => Some(16),
            VdbValues::Float | VdbValues::Half => None,
        }
    }
}

#[derive(Debug, Error, Clone, PartialEq)]
pub enum NanoVdbError {
    #[error("the blob is {len} bytes; a NanoVDB grid is at least {needed}")]
    TooShort { len: u64, needed: u64 },
    #[error("the blob does not start with a NanoVDB grid's magic number (\"NanoVDB0\" or \"NanoVDB1\") but with {found:#018x}")]
    Magic { found: u64 },
    #[error("the grid is NanoVDB {major}.{minor}.{patch}; caveray reads the version {NANOVDB_MAJOR} layout")]
    Version { major: u32, minor: u32, patch: u32 },
    #[error(
        "the grid holds {name} values; caveray reads scalar grids of Float, Half, Fp4, Fp8 or Fp16"
    )]
    GridType { name: String },
    #[error("the grid's index-to-world map {0}")]
    Map(String),
    #[error("{what} at byte {at} reaches byte {end}, past the grid's {size} bytes")]
    PastEnd {
        what: String,
        at: u64,
        end: u64,
        size: u64,
    },
    #[error("{what} points to byte {at}, which is not a node of the level below it")]
    NotANode { what: String, at: u64 },
    #[error("{what} points to the node at byte {at}, which another entry reached already (a cycle or a shared node)")]
    Twice { what: String, at: u64 },
    #[error("the grid's active box is empty: it has no active voxels to render")]
    Empty,
    #[error("the grid's active box, voxels {lo} to {hi}, reaches past voxel {MAX_INDEX} on an axis, where single precision no longer tells voxels apart")]
    FarOut { lo: IVec3, hi: IVec3 },
    #[error(
        "the grid's active box is {dims} voxels; caveray marches at most {MAX_LATTICE_VOXELS}"
    )]
    TooLarge { dims: UVec3 },
    #[error("cannot allocate {0} bytes for the grid")]
    Allocation(u64),
    #[error("{what} is at byte {at}, not on the 32-byte boundary NanoVDB aligns every node to")]
    Misaligned { what: String, at: u64 },
    #[error("the grid is {0} bytes; caveray reads grids of up to 4 GiB")]
    Huge(u64),
    #[error("root tile {tile}'s key {key:#018x} {why}")]
    BadKey {
        tile: usize,
        key: u64,
        why: &'static str,
    },
}

/// A root tile as read from the blob: where it starts in index space,
/// its upper node (a byte offset into the grid) or its one value, and
/// its place in the root's table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RootTile {
    pub origin: IVec3,
    pub child: Option<u32>,
    pub value: f32,
    pub slot: u32,
}

/// What a voxel's lookup found: the leaf holding it (byte offset), or
/// the one value of the tile or background covering it. Either holds for
/// the whole 8^3 block of voxels around it.
#[derive(Clone, Copy)]
enum Found {
    Leaf(usize),
    Value(f32),
}

/// Ids of grids made, for the lookup cache: never 0.
static NEXT_ID: AtomicU64 = AtomicU64::new(1);

thread_local! {
    /// Per thread, the last 8^3 block a lookup found, with its grid's
    /// id: a ray's samples fall in the same leaf again and again, and a
    /// walk from the root costs more than the sample.
    static LAST_BLOCK: Cell<(u64, IVec3, Found)> = const {
        Cell::new((0, IVec3::ZERO, Found::Value(0.0)))
    };
}

/// A validated NanoVDB grid, sampled through its own tree.
#[derive(Clone, Debug, PartialEq)]
pub struct NanoVdbGrid {
    /// This grid's words' id (its clones share them, and it).
    id: u64,
    /// The grid's bytes as little-endian words (a grid is 32-byte
    /// aligned, its size a multiple of 32).
    words: Arc<Vec<u32>>,
    values: VdbValues,
    class: u32,
    name: String,
    filter: Filter,
    root: usize,
    /// The root's tiles a sample can reach (those near the active box).
    tiles: Vec<RootTile>,
    /// Entries in the root's table.
    table_len: usize,
    background: f32,
    /// The active box's voxels (inclusive), the lattice's first vertex
    /// and last.
    active: (IVec3, IVec3),
    /// The voxels this field's lattice covers: the active box, or a part
    /// of it once cropped.
    window: (IVec3, IVec3),
    /// Index-to-world: world = origin + index * scale.
    origin: DVec3,
    scale: DVec3,
    active_voxels: u64,
    counts: [u32; 3],
    value_range: (f32, f32),
}

/// Little-endian reads that fail past the end, for the walk that checks
/// the blob.
struct Bytes<'a> {
    b: &'a [u8],
}

impl Bytes<'_> {
    fn u32(&self, at: usize) -> Option<u32> {
        let s = self.b.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes(s.try_into().ok()?))
    }
    fn u64(&self, at: usize) -> Option<u64> {
        let s = self.b.get(at..at.checked_add(8)?)?;
        Some(u64::from_le_bytes(s.try_into().ok()?))
    }
    fn f64(&self, at: usize) -> Option<f64> {
        self.u64(at).map(f64::from_bits)
    }
}

/// IEEE binary16 to f32.
pub fn half_to_f32(h: u16) -> f32 {
    let sign = u32::from(h >> 15) << 31;
    let exp = u32::from((h >> 10) & 0x1f);
    let man = u32::from(h & 0x3ff);
    let bits = match (exp, man) {
        (0, 0) => sign,
        (0, m) => {
            // Subnormal: m * 2^-24.
            let v = m as f32 / 16_777_216.0;
            return if sign != 0 { -v } else { v };
        }
        (31, 0) => sign | 0x7f80_0000,
        (31, m) => sign | 0x7f80_0000 | (m << 13),
        (e, m) => sign | ((e + 112) << 23) | (m << 13),
    };
    f32::from_bits(bits)
}

/// The sections nodes of each level lie in: (first byte, count, size).
struct Sections {
    upper: (usize, usize, usize),
    lower: (usize, usize, usize),
    leaf: (usize, usize, usize),
}

impl Sections {
    /// The index of the node at `at` in section `s`, if it is one.
    fn node(s: (usize, usize, usize), at: usize) -> Option<usize> {
        let (first, count, size) = s;
        let d = at.checked_sub(first)?;
        (d % size == 0 && d / size < count).then_some(d / size)
    }
}

impl NanoVdbGrid {
    /// Reads and checks the grid at the start of `blob`, to be sampled
    /// with `filter`.
    pub fn new(blob: &[u8], filter: Filter) -> Result<Self, NanoVdbError> {
        let b = Bytes { b: blob };
        let len = blob.len() as u64;
        let short = || NanoVdbError::TooShort {
            len,
            needed: (GRID_SIZE + TREE_SIZE + ROOT_SIZE) as u64,
        };
        let magic = b.u64(0).ok_or_else(short)?;
        if magic != NANOVDB_MAGIC && magic != NANOVDB_MAGIC_GRID {
            return Err(NanoVdbError::Magic { found: magic });
        }
        let version = b.u32(16).ok_or_else(short)?;
        let major = version >> 21;
        if major != NANOVDB_MAJOR {
            return Err(NanoVdbError::Version {
                major,
                minor: (version >> 10) & 0x7ff,
                patch: version & 0x3ff,
            });
        }
        if blob.len() < GRID_SIZE + TREE_SIZE + ROOT_SIZE {
            return Err(short());
        }
        let values = VdbValues::of(b.u32(GRID_OFF_TYPE).ok_or_else(short)?)?;
        let class = b.u32(GRID_OFF_CLASS).ok_or_else(short)?;
        let grid_size = b.u64(32).ok_or_else(short)?;
        if grid_size > len {
            return Err(NanoVdbError::PastEnd {
                what: "the grid's size".into(),
                at: 32,
                end: grid_size,
                size: len,
            });
        }
        if grid_size < (GRID_SIZE + TREE_SIZE + ROOT_SIZE) as u64 {
            return Err(NanoVdbError::TooShort {
                len: grid_size,
                needed: (GRID_SIZE + TREE_SIZE + ROOT_SIZE) as u64,
            });
        }
        // Offsets are kept in 32 bits (the GPU's addresses are), and
        // every node lies on a 32-byte boundary, so that the CPU and the
        // GPU, which reads words, find the same nodes.
        if grid_size > u64::from(u32::MAX) {
            return Err(NanoVdbError::Huge(grid_size));
        }
        if grid_size % 32 != 0 {
            return Err(NanoVdbError::Misaligned {
                what: "the grid's end".into(),
                at: grid_size,
            });
        }
        let size = grid_size as usize;
        let b = Bytes { b: &blob[..size] };
        let name_bytes = &blob[GRID_OFF_NAME..GRID_OFF_NAME + 256];
        let name_end = name_bytes.iter().position(|&c| c == 0).unwrap_or(256);
        let name = String::from_utf8_lossy(&name_bytes[..name_end]).into_owned();
        let (origin, scale) = map_of(&b)?;

        let past = |what: &str, at: usize, end: u64| NanoVdbError::PastEnd {
            what: what.to_string(),
            at: at as u64,
            end,
            size: grid_size,
        };
        let tree = GRID_SIZE;
        let section = |k: usize, count_at: usize, node: usize, what: &str| {
            let off = b.u64(tree + 8 * k).unwrap_or(u64::MAX);
            let count = u64::from(b.u32(tree + count_at).unwrap_or(0));
            let first = (tree as u64).saturating_add(off);
            let end = first.saturating_add(count.saturating_mul(node as u64));
            if count > 0 && end > grid_size {
                return Err(past(what, tree + 8 * k, end));
            }
            if count > 0 && !first.is_multiple_of(32) {
                return Err(NanoVdbError::Misaligned {
                    what: what.to_string(),
                    at: first,
                });
            }
            Ok((first.min(grid_size) as usize, count as usize, node))
        };
        let sections = Sections {
            leaf: section(0, 32, values.leaf_size(), "the leaves")?,
            lower: section(1, 36, LOWER_SIZE, "the lower nodes")?,
            upper: section(2, 40, UPPER_SIZE, "the upper nodes")?,
        };
        let root_off = b.u64(tree + 24).unwrap_or(u64::MAX);
        let root = (tree as u64).saturating_add(root_off);
        if root.saturating_add(ROOT_SIZE as u64) > grid_size {
            return Err(past(
                "the root",
                tree + 24,
                root.saturating_add(ROOT_SIZE as u64),
            ));
        }
        if !root.is_multiple_of(32) {
            return Err(NanoVdbError::Misaligned {
                what: "the root".into(),
                at: root,
            });
        }
        let root = root as usize;
        let table = u64::from(b.u32(root + ROOT_OFF_TABLE_SIZE).unwrap_or(0));
        let tiles_end = (root + ROOT_SIZE) as u64 + table * ROOT_TILE_SIZE as u64;
        if tiles_end > grid_size {
            return Err(past(
                "the root's tiles",
                root + ROOT_OFF_TABLE_SIZE,
                tiles_end,
            ));
        }
        let value = |at: usize| -> f32 {
            match values {
                VdbValues::Half => half_to_f32(b.u32(at).unwrap_or(0) as u16),
                _ => f32::from_bits(b.u32(at).unwrap_or(0)),
            }
        };
        let background = value(root + ROOT_OFF_BACKGROUND);
        let active = {
            let i = |k: usize| b.u32(root + 4 * k).unwrap_or(0) as i32;
            (IVec3::new(i(0), i(1), i(2)), IVec3::new(i(3), i(4), i(5)))
        };
        if active.1.cmplt(active.0).any() {
            return Err(NanoVdbError::Empty);
        }
        let reach = IVec3::splat(MAX_INDEX);
        if active.0.cmplt(-reach).any() || active.1.cmpgt(reach).any() {
            return Err(NanoVdbError::FarOut {
                lo: active.0,
                hi: active.1,
            });
        }
        let dims =
            (active.1.as_i64vec3() - active.0.as_i64vec3() + glam::I64Vec3::ONE).as_u64vec3();
        if dims.x.saturating_mul(dims.y).saturating_mul(dims.z) > MAX_LATTICE_VOXELS {
            return Err(NanoVdbError::TooLarge {
                dims: dims
                    .min(glam::U64Vec3::splat(u64::from(u32::MAX)))
                    .as_uvec3(),
            });
        }

        let mut words = Vec::new();
        words
            .try_reserve_exact(size / 4)
            .map_err(|_| NanoVdbError::Allocation(grid_size))?;
        words.extend(
            blob[..size]
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])),
        );

        // The walk: every child offset onto a node of the level below,
        // each node once.
        let mut seen_upper = vec![false; sections.upper.1];
        let mut seen_lower = vec![false; sections.lower.1];
        let mut seen_leaf = vec![false; sections.leaf.1];
        let mut tiles = Vec::new();
        let mut origins = std::collections::HashSet::new();
        let mut uppers = Vec::new();
        // Samples read the active box and one voxel beyond it: only the
        // tiles that reach it are looked up.
        let near = |o: IVec3| {
            (o.cmple(active.1 + IVec3::ONE) & (o + IVec3::splat(4095)).cmpge(active.0 - IVec3::ONE))
                .all()
        };
        for t in 0..table as usize {
            let at = root + ROOT_SIZE + t * ROOT_TILE_SIZE;
            let key = b.u64(at).unwrap_or(0);
            // Three fields of 20 bits (a coordinate's upper bits), x
            // highest, each in 21.
            const FIELDS: u64 = 0xf_ffff | 0xf_ffff << 21 | 0xf_ffff << 42;
            if key & !FIELDS != 0 {
                return Err(NanoVdbError::BadKey {
                    tile: t,
                    key,
                    why: "has bits set outside its three 20-bit coordinates",
                });
            }
            let axis = |shift: u32| (((key >> shift) & 0xf_ffff) as u32).wrapping_shl(12) as i32;
            let origin = IVec3::new(axis(42), axis(21), axis(0));
            if !origins.insert(origin) {
                return Err(NanoVdbError::BadKey {
                    tile: t,
                    key,
                    why: "is another tile's too",
                });
            }
            let child = b.u64(at + ROOT_TILE_OFF_CHILD).unwrap_or(0) as i64;
            let _state = b.u32(at + ROOT_TILE_OFF_STATE);
            let tile_value = value(at + ROOT_TILE_OFF_VALUE);
            let child = if child == 0 {
                None
            } else {
                let what = format!("root tile {t}");
                let node = (root as i64).checked_add(child).filter(|&n| n >= 0);
                let Some(node) = node.map(|n| n as usize) else {
                    return Err(NanoVdbError::NotANode {
                        what,
                        at: child as u64,
                    });
                };
                let i =
                    Sections::node(sections.upper, node).ok_or_else(|| NanoVdbError::NotANode {
                        what: what.clone(),
                        at: node as u64,
                    })?;
                if std::mem::replace(&mut seen_upper[i], true) {
                    return Err(NanoVdbError::Twice {
                        what,
                        at: node as u64,
                    });
                }
                uppers.push(node);
                Some(node as u32)
            };
            if near(origin) {
                tiles.push(RootTile {
                    origin,
                    child,
                    value: tile_value,
                    slot: t as u32,
                });
            }
        }
        let mut lowers = Vec::new();
        for &node in &uppers {
            walk_node(
                &words,
                (node, UPPER_OFF_CHILD_MASK, UPPER_OFF_TABLE, 32 * 32 * 32),
                sections.lower,
                ("upper", "lower"),
                &mut seen_lower,
                &mut lowers,
            )?;
        }
        let mut leaves = Vec::new();
        for &node in &lowers {
            walk_node(
                &words,
                (node, LOWER_OFF_CHILD_MASK, LOWER_OFF_TABLE, 16 * 16 * 16),
                sections.leaf,
                ("lower", "leaf"),
                &mut seen_leaf,
                &mut leaves,
            )?;
        }
        let mut grid = Self {
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            words: Arc::new(words),
            values,
            class,
            name,
            filter,
            root,
            tiles,
            table_len: table as usize,
            background,
            active,
            window: active,
            origin,
            scale,
            active_voxels: b.u64(tree + 56).unwrap_or(0),
            counts: [
                uppers.len() as u32,
                lowers.len() as u32,
                leaves.len() as u32,
            ],
            value_range: (0.0, 0.0),
        };
        grid.value_range = grid.window_range();
        Ok(grid)
    }

    fn f(&self, byte: usize) -> f32 {
        f32::from_bits(self.words[byte >> 2])
    }

    /// `find`, through this thread's last block.
    fn find_cached(&self, ijk: IVec3) -> Found {
        let block = ijk & IVec3::splat(!7);
        LAST_BLOCK.with(|last| {
            let (id, b, found) = last.get();
            if id == self.id && b == block {
                return found;
            }
            let found = self.find(ijk);
            last.set((self.id, block, found));
            found
        })
    }

    /// The node (or value) holding voxel `ijk`.
    fn find(&self, ijk: IVec3) -> Found {
        let key = ijk & IVec3::splat(!4095);
        let Some(tile) = self.tiles.iter().find(|t| t.origin == key) else {
            return Found::Value(self.background);
        };
        let Some(upper) = tile.child else {
            return Found::Value(tile.value);
        };
        let upper = upper as usize;
        let u: IVec3 = (ijk & IVec3::splat(4095)) >> 7;
        let n = ((u.x << 10) | (u.y << 5) | u.z) as usize;
        let lower = match self.child(upper, UPPER_OFF_CHILD_MASK, UPPER_OFF_TABLE, n) {
            Ok(c) => c,
            Err(v) => return Found::Value(v),
        };
        let l: IVec3 = (ijk & IVec3::splat(127)) >> 3;
        let n = ((l.x << 8) | (l.y << 4) | l.z) as usize;
        match self.child(lower, LOWER_OFF_CHILD_MASK, LOWER_OFF_TABLE, n) {
            Ok(leaf) => Found::Leaf(leaf),
            Err(v) => Found::Value(v),
        }
    }

    /// Entry `n` of the internal node at `node`: its child's byte offset,
    /// or its tile's value.
    fn child(&self, node: usize, mask: usize, table: usize, n: usize) -> Result<usize, f32> {
        let word = self.words[(node + mask) / 4 + n / 32];
        let at = node + table + 8 * n;
        if word >> (n % 32) & 1 == 1 {
            Ok(node + self.words[at / 4] as usize)
        } else {
            Err(tile_of(&self.words, self.values, at))
        }
    }

    /// Value `n` (x * 64 + y * 8 + z) of the leaf at `leaf`.
    fn leaf_value(&self, leaf: usize, n: usize) -> f32 {
        let t = leaf + LEAF_OFF_TABLE;
        match (self.values, self.values.code_bits()) {
            (VdbValues::Float, _) => self.f(t + 4 * n),
            (VdbValues::Half, _) => {
                let w = self.words[(t + 2 * n) / 4];
                half_to_f32((w >> (16 * (n % 2))) as u16)
            }
            (_, Some(bits)) => {
                let per_word = (32 / bits) as usize;
                let w = self.words[t / 4 + n / per_word];
                let code = (w >> ((n % per_word) as u32 * bits)) & ((1u32 << bits) - 1);
                code as f32 * self.f(t - 12) + self.f(t - 16)
            }
            (_, None) => unreachable!("Float and Half are matched above"),
        }
    }

    /// Voxel `ijk`'s value.
    pub fn value(&self, ijk: IVec3) -> f32 {
        match self.find_cached(ijk) {
            Found::Leaf(leaf) => {
                let l = ijk & IVec3::splat(7);
                self.leaf_value(leaf, ((l.x << 6) | (l.y << 3) | l.z) as usize)
            }
            Found::Value(v) => v,
        }
    }

    /// The field at index point `p`: the nearest voxel's value, or
    /// trilinear between the eight around it.
    pub fn sample_index(&self, p: Vec3) -> f32 {
        // Far beyond the grid (2^30 voxels; the active box lies within
        // 2^24) every voxel is the background: kept in i32.
        let p = p.clamp(Vec3::splat(-FAR), Vec3::splat(FAR));
        if self.filter == Filter::Nearest {
            return self.value(floor(p + Vec3::splat(0.5)));
        }
        let i0 = floor(p);
        let f = p - i0.as_vec3();
        let l = i0 & IVec3::splat(7);
        let corner = |c: usize| IVec3::new((c & 1) as i32, (c >> 1 & 1) as i32, (c >> 2) as i32);
        let corners: [f32; 8] = if l.cmplt(IVec3::splat(7)).all() {
            // The eight voxels share one leaf, or one tile's value.
            match self.find_cached(i0) {
                Found::Value(v) => return v,
                Found::Leaf(leaf) => {
                    let n = ((l.x << 6) | (l.y << 3) | l.z) as usize;
                    std::array::from_fn(|c| {
                        self.leaf_value(leaf, n + 64 * (c & 1) + 8 * (c >> 1 & 1) + (c >> 2))
                    })
                }
            }
        } else {
            // The stencil reaches into up to seven neighbouring blocks:
            // each found once.
            let mut blocks: [Option<Found>; 8] = [None; 8];
            std::array::from_fn(|c| {
                let at = l + corner(c);
                let b =
                    usize::from(at.x > 7) | usize::from(at.y > 7) << 1 | usize::from(at.z > 7) << 2;
                let found = *blocks[b].get_or_insert_with(|| {
                    if b == 0 {
                        self.find_cached(i0)
                    } else {
                        self.find(i0 + corner(c))
                    }
                });
                match found {
                    Found::Value(v) => v,
                    Found::Leaf(leaf) => {
                        let q = at & IVec3::splat(7);
                        self.leaf_value(leaf, ((q.x << 6) | (q.y << 3) | q.z) as usize)
                    }
                }
            })
        };
        let x00 = mix(corners[0], corners[1], f.x);
        let x10 = mix(corners[2], corners[3], f.x);
        let x01 = mix(corners[4], corners[5], f.x);
        let x11 = mix(corners[6], corners[7], f.x);
        mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z)
    }

    /// The field at lattice point `g` (vertex 0 the window's first voxel).
    pub fn sample(&self, g: Vec3) -> f32 {
        self.sample_index(self.window.0.as_vec3() + g)
    }

    /// The field at world point `p`.
    pub fn sample_world(&self, p: Vec3) -> f32 {
        let index = (p.as_dvec3() - self.origin) / self.scale;
        self.sample_index(index.as_vec3())
    }

    /// The lattice's vertices per axis and their spacing (world units).
    pub fn lattice(&self) -> (UVec3, Vec3) {
        let (lo, hi) = self.window;
        ((hi - lo + IVec3::ONE).as_uvec3(), self.scale.as_vec3())
    }

    /// The world box of the lattice.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let (lo, hi) = self.window;
        (
            (self.origin + lo.as_dvec3() * self.scale).as_vec3(),
            (self.origin + hi.as_dvec3() * self.scale).as_vec3(),
        )
    }

    /// The lattice restricted to its vertices `lo..=hi`: a grid of the
    /// nodes a sample there can read (the others dropped, their parents'
    /// entries made tiles), sampled there as the whole is.
    pub fn window_of(&self, lo: UVec3, hi: UVec3) -> Result<Self, String> {
        let dims = self.lattice().0;
        if lo.cmpgt(hi).any() || hi.cmpge(dims).any() {
            return Err(format!(
                "vertices {lo} to {hi} are not a box of the NanoVDB grid's {dims} lattice"
            ));
        }
        let base = self.window.0;
        let window = (base + lo.as_ivec3(), base + hi.as_ivec3());
        // A sample reads the voxels around it, one beyond the window, and
        // a hit's gradient a step (at most a voxel at the default rates)
        // each side of it.
        let words = self
            .pruned((window.0 - IVec3::splat(2), window.1 + IVec3::splat(2)))
            .map_err(|e| e.to_string())?;
        let mut part =
            Self::new(bytemuck::cast_slice(&words), self.filter).map_err(|e| e.to_string())?;
        part.window = window;
        part.value_range = part.window_range();
        Ok(part)
    }

    /// The grid's words with only the nodes that reach the voxels
    /// `reach` (inclusive): the header, tree and root as they are, then
    /// the upper nodes, lower nodes and leaves kept, each parent's child
    /// offsets rewritten and its dropped children's entries made tiles.
    fn pruned(&self, reach: (IVec3, IVec3)) -> Result<Vec<u32>, NanoVdbError> {
        let meets = |lo: IVec3, span: i32| {
            (lo.cmple(reach.1) & (lo + IVec3::splat(span - 1)).cmpge(reach.0)).all()
        };
        let w = &self.words;
        // Kept nodes: (old byte offset, index of the entry or tile naming
        // it, index of the kept parent).
        let mut uppers = Vec::new();
        for t in &self.tiles {
            if let Some(u) = t.child.filter(|_| meets(t.origin, 4096)) {
                uppers.push((u as usize, t.slot as usize, 0usize, t.origin));
            }
        }
        let mut lowers = Vec::new();
        for (k, &(upper, _, _, origin)) in uppers.iter().enumerate() {
            for n in 0..32 * 32 * 32usize {
                let o = origin
                    + IVec3::new((n >> 10) as i32, (n >> 5 & 31) as i32, (n & 31) as i32) * 128;
                if let Ok(lower) = self.child(upper, UPPER_OFF_CHILD_MASK, UPPER_OFF_TABLE, n) {
                    if meets(o, 128) {
                        lowers.push((lower, n, k, o));
                    }
                }
            }
        }
        let mut leaves = Vec::new();
        for (k, &(lower, _, _, origin)) in lowers.iter().enumerate() {
            for m in 0..16 * 16 * 16usize {
                let o =
                    origin + IVec3::new((m >> 8) as i32, (m >> 4 & 15) as i32, (m & 15) as i32) * 8;
                if let Ok(leaf) = self.child(lower, LOWER_OFF_CHILD_MASK, LOWER_OFF_TABLE, m) {
                    if meets(o, 8) {
                        leaves.push((leaf, m, k, o));
                    }
                }
            }
        }
        let head = GRID_SIZE + TREE_SIZE;
        let root_size = ROOT_SIZE + ROOT_TILE_SIZE * self.table_len;
        let leaf_size = self.values.leaf_size();
        let upper_at = head + root_size;
        let lower_at = upper_at + uppers.len() * UPPER_SIZE;
        let leaf_at = lower_at + lowers.len() * LOWER_SIZE;
        let size = leaf_at + leaves.len() * leaf_size;
        let mut out = Vec::new();
        out.try_reserve_exact(size / 4)
            .map_err(|_| NanoVdbError::Allocation(size as u64))?;
        out.extend_from_slice(&w[..head / 4]);
        out.extend_from_slice(&w[self.root / 4..(self.root + root_size) / 4]);
        let copy = |out: &mut Vec<u32>, at: usize, len: usize| {
            out.extend_from_slice(&w[at / 4..(at + len) / 4])
        };
        for &(u, ..) in &uppers {
            copy(&mut out, u, UPPER_SIZE);
        }
        for &(l, ..) in &lowers {
            copy(&mut out, l, LOWER_SIZE);
        }
        for &(f, ..) in &leaves {
            copy(&mut out, f, leaf_size);
        }
        let put64 = |out: &mut Vec<u32>, at: usize, v: u64| {
            out[at / 4] = v as u32;
            out[at / 4 + 1] = (v >> 32) as u32;
        };
        put64(&mut out, 32, size as u64);
        // No checksum (NanoVDB's "disabled", all ones) and no blind data:
        // both described the whole grid.
        put64(&mut out, 8, u64::MAX);
        put64(&mut out, 640, 0);
        out[648 / 4] = 0;
        let tree = GRID_SIZE;
        put64(&mut out, tree, (leaf_at - tree) as u64);
        put64(&mut out, tree + 8, (lower_at - tree) as u64);
        put64(&mut out, tree + 16, (upper_at - tree) as u64);
        put64(&mut out, tree + 24, (head - tree) as u64);
        out[(tree + 32) / 4] = leaves.len() as u32;
        out[(tree + 36) / 4] = lowers.len() as u32;
        out[(tree + 40) / 4] = uppers.len() as u32;
        // Every child dropped first, then the kept ones named again.
        for i in 0..self.table_len {
            put64(
                &mut out,
                head + ROOT_SIZE + ROOT_TILE_SIZE * i + ROOT_TILE_OFF_CHILD,
                0,
            );
        }
        for k in 0..uppers.len() {
            drop_children(
                &mut out,
                upper_at + k * UPPER_SIZE,
                UPPER_OFF_CHILD_MASK,
                UPPER_OFF_TABLE,
                32 * 32 * 32,
            );
        }
        for k in 0..lowers.len() {
            drop_children(
                &mut out,
                lower_at + k * LOWER_SIZE,
                LOWER_OFF_CHILD_MASK,
                LOWER_OFF_TABLE,
                16 * 16 * 16,
            );
        }
        for (k, &(_, i, ..)) in uppers.iter().enumerate() {
            let tile = head + ROOT_SIZE + ROOT_TILE_SIZE * i;
            put64(
                &mut out,
                tile + ROOT_TILE_OFF_CHILD,
                (upper_at + k * UPPER_SIZE - head) as u64,
            );
        }
        let relink = |out: &mut Vec<u32>,
                      (node, mask, table): (usize, usize, usize),
                      n: usize,
                      child: usize| {
            out[(node + mask) / 4 + n / 32] |= 1 << (n % 32);
            put64(out, node + table + 8 * n, (child - node) as u64);
        };
        for (k, &(_, n, parent, _)) in lowers.iter().enumerate() {
            let node = upper_at + parent * UPPER_SIZE;
            relink(
                &mut out,
                (node, UPPER_OFF_CHILD_MASK, UPPER_OFF_TABLE),
                n,
                lower_at + k * LOWER_SIZE,
            );
        }
        for (k, &(_, m, parent, _)) in leaves.iter().enumerate() {
            let node = lower_at + parent * LOWER_SIZE;
            relink(
                &mut out,
                (node, LOWER_OFF_CHILD_MASK, LOWER_OFF_TABLE),
                m,
                leaf_at + k * leaf_size,
            );
        }
        Ok(out)
    }

    /// Boxes of lattice vertices (window coordinates, inclusive, possibly
    /// beyond the window) and the range of the values there: the
    /// background where no root tile is, then each tile and each leaf of
    /// the tree that reaches the window.
    pub fn value_boxes(&self) -> Vec<((Vec3, Vec3), (f32, f32))> {
        let (w0, w1) = self.window;
        let mut out = Vec::new();
        let k0: IVec3 = (w0 - IVec3::ONE) >> 12;
        let k1: IVec3 = (w1 + IVec3::ONE) >> 12;
        for z in k0.z..=k1.z {
            for y in k0.y..=k1.y {
                for x in k0.x..=k1.x {
                    let origin = IVec3::new(x, y, z) << 12;
                    if self.tiles.iter().all(|t| t.origin != origin) {
                        let lo = (origin - w0).as_vec3();
                        out.push((
                            (lo, lo + Vec3::splat(4095.0)),
                            (self.background, self.background),
                        ));
                    }
                }
            }
        }
        let mut add = |lo: IVec3, span: i32, range: (f32, f32)| {
            let hi = lo + IVec3::splat(span - 1);
            // A sample reads one voxel beyond the box it lies in.
            if hi.saturating_add(IVec3::ONE).cmplt(w0).any()
                || lo.saturating_sub(IVec3::ONE).cmpgt(w1).any()
            {
                return;
            }
            if range.0.is_nan() || range.1.is_nan() {
                return;
            }
            out.push((((lo - w0).as_vec3(), (hi - w0).as_vec3()), range));
        };
        for t in &self.tiles {
            let Some(upper) = t.child else {
                add(t.origin, 4096, (t.value, t.value));
                continue;
            };
            let upper = upper as usize;
            for n in 0..32 * 32 * 32usize {
                let uo = t.origin
                    + IVec3::new((n >> 10) as i32, (n >> 5 & 31) as i32, (n & 31) as i32) * 128;
                match self.child(upper, UPPER_OFF_CHILD_MASK, UPPER_OFF_TABLE, n) {
                    Err(v) => add(uo, 128, (v, v)),
                    Ok(lower) => {
                        for m in 0..16 * 16 * 16usize {
                            let lo = uo
                                + IVec3::new(
                                    (m >> 8) as i32,
                                    (m >> 4 & 15) as i32,
                                    (m & 15) as i32,
                                ) * 8;
                            match self.child(lower, LOWER_OFF_CHILD_MASK, LOWER_OFF_TABLE, m) {
                                Err(v) => add(lo, 8, (v, v)),
                                Ok(leaf) => {
                                    // NaN reads as no value; infinities
                                    // classify as the table's ends.
                                    let mut r = (f32::INFINITY, f32::NEG_INFINITY);
                                    for k in 0..512 {
                                        let v = self.leaf_value(leaf, k);
                                        if !v.is_nan() {
                                            r = (r.0.min(v), r.1.max(v));
                                        }
                                    }
                                    add(lo, 8, r);
                                }
                            }
                        }
                    }
                }
            }
        }
        out
    }

    /// The range of the finite values a sample in the window can read:
    /// of the leaves and tiles reaching it, and of the background where
    /// no root tile is.
    fn window_range(&self) -> (f32, f32) {
        // Finite ends only: a transfer function is stretched over this.
        let (lo, hi) = self.value_boxes().iter().fold(
            (f32::INFINITY, f32::NEG_INFINITY),
            |(lo, hi), &(_, (a, b))| {
                let keep = |v: f32, or: f32| if v.is_finite() { v } else { or };
                (lo.min(keep(a, lo)), hi.max(keep(b, hi)))
            },
        );
        if lo > hi {
            (self.background, self.background)
        } else {
            (lo, hi)
        }
    }

    pub fn words(&self) -> &[u32] {
        &self.words
    }

    pub fn tiles(&self) -> &[RootTile] {
        &self.tiles
    }

    pub fn values(&self) -> VdbValues {
        self.values
    }

    /// NanoVDB's name of the grid class (LevelSet, FogVolume, ...).
    pub fn class_name(&self) -> &'static str {
        CLASS_NAMES
            .get(self.class as usize)
            .copied()
            .unwrap_or("Unknown")
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn filter(&self) -> Filter {
        self.filter
    }

    pub fn background(&self) -> f32 {
        self.background
    }

    /// The active box's voxels, inclusive, in index space.
    pub fn active_box(&self) -> (IVec3, IVec3) {
        self.active
    }

    /// The window's first voxel in index space.
    pub fn window_origin(&self) -> IVec3 {
        self.window.0
    }

    pub fn active_voxels(&self) -> u64 {
        self.active_voxels
    }

    /// Upper nodes, lower nodes and leaves.
    pub fn node_counts(&self) -> [u32; 3] {
        self.counts
    }

    /// The world size of a voxel.
    pub fn voxel_size(&self) -> Vec3 {
        self.scale.as_vec3()
    }

    pub fn value_range(&self) -> (f32, f32) {
        self.value_range
    }

    /// Bytes held: the grid as it came.
    pub fn bytes(&self) -> u64 {
        4 * self.words.len() as u64
    }
}

/// Makes every child entry of the internal node at byte `node` of `out`
/// a tile (of 0: a sample never reads it, or the entry is named again).
fn drop_children(out: &mut [u32], node: usize, mask: usize, table: usize, entries: usize) {
    for n in 0..entries {
        let word = &mut out[(node + mask) / 4 + n / 32];
        if *word >> (n % 32) & 1 == 1 {
            *word &= !(1 << (n % 32));
            out[(node + table + 8 * n) / 4] = 0;
            out[(node + table + 8 * n) / 4 + 1] = 0;
        }
    }
}

/// The value of an internal node's tile entry at byte `at`.
fn tile_of(words: &[u32], values: VdbValues, at: usize) -> f32 {
    let w = words[at / 4];
    match values {
        VdbValues::Half => half_to_f32(w as u16),
        _ => f32::from_bits(w),
    }
}

/// Checks the children of the internal node `node` (its child mask and
/// table at those offsets, `entries` entries): each must be a node of
/// `below`, reached once; each is pushed to `out`.
fn walk_node(
    words: &[u32],
    (node, mask, table, entries): (usize, usize, usize, usize),
    below: (usize, usize, usize),
    (level, child_level): (&str, &str),
    seen: &mut [bool],
    out: &mut Vec<usize>,
) -> Result<(), NanoVdbError> {
    for n in 0..entries {
        let at = node + table + 8 * n;
        if words[(node + mask) / 4 + n / 32] >> (n % 32) & 1 == 0 {
            continue;
        }
        let offset = u64::from(words[at / 4]) | u64::from(words[at / 4 + 1]) << 32;
        let what = format!("the {level} node at byte {node}, entry {n},");
        let child = (node as u64)
            .checked_add(offset)
            .filter(|_| (offset as i64) > 0)
            .filter(|&c| c <= u64::from(u32::MAX));
        let Some(child) = child.map(|c| c as usize) else {
            return Err(NanoVdbError::NotANode {
                what,
                at: (node as i64).wrapping_add(offset as i64) as u64,
            });
        };
        let Some(i) = Sections::node(below, child) else {
            return Err(NanoVdbError::NotANode {
                what: format!("{what} (a {child_level} node expected)"),
                at: child as u64,
            });
        };
        if std::mem::replace(&mut seen[i], true) {
            return Err(NanoVdbError::Twice {
                what,
                at: child as u64,
            });
        }
        out.push(child);
    }
    Ok(())
}

/// The index-to-world map as origin and per-axis scale: only maps
/// without rotation or shear are placed (a volume's instance transform
/// turns it).
fn map_of(b: &Bytes<'_>) -> Result<(DVec3, DVec3), NanoVdbError> {
    let m: Vec<f64> = (0..9)
        .map(|k| {
            b.f64(GRID_OFF_MAP + MAP_OFF_MATD + 8 * k)
                .unwrap_or(f64::NAN)
        })
        .collect();
    let v = DVec3::from_array(std::array::from_fn(|k| {
        b.f64(GRID_OFF_MAP + MAP_OFF_VECD + 8 * k)
            .unwrap_or(f64::NAN)
    }));
    let scale = DVec3::new(m[0], m[4], m[8]);
    // Renderers take the voxel size in single precision.
    let single = scale.as_vec3();
    if !single.is_finite()
        || !v.as_vec3().is_finite()
        || single.cmplt(Vec3::splat(f32::MIN_POSITIVE)).any()
    {
        return Err(NanoVdbError::Map(format!(
            "has scale {scale} and translation {v}; both must be finite in single precision and the scale positive"
        )));
    }
    let largest = scale.max_element();
    for (k, &e) in m.iter().enumerate() {
        if k % 4 != 0 && e.abs() > 1e-9 * largest {
            return Err(NanoVdbError::Map(format!(
                "rotates or shears (entry {} of its matrix is {e}); caveray places grids axis-aligned: resample the grid, or turn the volume with an instance transform",
                k
            )));
        }
    }
    Ok((v, scale))
}

/// floor(p) per axis, without a libm call: truncation, one less where
/// it rounded a negative value up.
fn floor(p: Vec3) -> IVec3 {
    let t = p.as_ivec3();
    t - IVec3::select(t.as_vec3().cmpgt(p), IVec3::ONE, IVec3::ZERO)
}

fn mix(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_floats_convert_as_ieee_says() {
        assert_eq!(half_to_f32(0x3c00), 1.0);
        assert_eq!(half_to_f32(0xc000), -2.0);
        assert_eq!(half_to_f32(0x7bff), 65504.0);
        assert_eq!(half_to_f32(0x0001), 5.960_464_5e-8);
        assert_eq!(half_to_f32(0x8000), -0.0);
        assert!(half_to_f32(0x7e00).is_nan());
        assert_eq!(half_to_f32(0x7c00), f32::INFINITY);
        assert_eq!(half_to_f32(0x3555), 0.333_251_95);
    }

    #[test]
    fn a_blob_without_the_magic_number_is_refused_by_name() {
        let mut blob = vec![0u8; 2048];
        blob[..8].copy_from_slice(b"OpenVDB!");
        let e = NanoVdbGrid::new(&blob, Filter::Linear).unwrap_err();
        assert!(e.to_string().contains("magic number"), "{e}");
        let e = NanoVdbGrid::new(&blob[..4], Filter::Linear).unwrap_err();
        assert!(e.to_string().contains("the blob is 4 bytes"), "{e}");
    }

    #[test]
    fn another_major_version_is_refused_with_its_number() {
        let mut blob = vec![0u8; 2048];
        blob[..8].copy_from_slice(&NANOVDB_MAGIC.to_le_bytes());
        blob[16..20].copy_from_slice(&((31u32 << 21) | (2 << 10) | 1).to_le_bytes());
        let e = NanoVdbGrid::new(&blob, Filter::Linear).unwrap_err();
        assert_eq!(
            e,
            NanoVdbError::Version {
                major: 31,
                minor: 2,
                patch: 1
            }
        );
    }
}
