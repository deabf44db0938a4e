// #import constants, volume_bindings, cells
// NanoVDB grids: the field through the grid's own tree, read from its
// words in `meshes` (layout in src/render/gpu/nanovdb.rs). Mirrors
// src/scene/nanovdb.rs: root tile, upper node, lower node, leaf; a tile's
// value or the background where the tree holds no leaf.

// Set where a volume of the scene is a NanoVDB grid: without it the
// sampling is dropped.
override VDB: bool = false;

const VDB_NONE: u32 = 0xffffffffu;

// Node layouts in words (bytes / 4, scene::nanovdb).
const VDB_UPPER_MASK: u32 = 1032u;
const VDB_UPPER_TABLE: u32 = 2064u;
const VDB_LOWER_MASK: u32 = 136u;
const VDB_LOWER_TABLE: u32 = 272u;
const VDB_LEAF_TABLE: u32 = 24u;

// What a voxel's lookup found: its leaf's first word, or VDB_NONE and
// the value of the tile (or background) holding it. Either holds for
// the whole 8^3 block around the voxel.
struct VdbFound {
    leaf: u32,
    value: f32,
}

// Per invocation, the last block a lookup found (the grid's first word
// in w, the block's first voxel in xyz), as the CPU keeps one per
// thread: a ray's samples fall in the same leaf again and again.
var<private> vdb_last_key: vec4i = vec4i(0, 0, 0, -1);
var<private> vdb_last: VdbFound;

// An internal node's tile entry at word e of grid a.
fn vdb_tile(a: u32, e: u32) -> f32 {
    let w = mesh_word(e);
    if mesh_word(a) == 1u {
        return unpack2x16float(w).x;
    }
    return bitcast<f32>(w);
}

fn vdb_find(a: u32, ijk: vec3i) -> VdbFound {
    let count = mesh_word(a + 2u);
    let tiles = a + mesh_word(a + 3u);
    let key = ijk & vec3i(~4095);
    var t = VDB_NONE;
    for (var i = 0u; i < count; i++) {
        let e = tiles + 5u * i;
        let o = bitcast<vec3i>(vec3u(mesh_word(e), mesh_word(e + 1u), mesh_word(e + 2u)));
        if all(o == key) {
            t = e;
            break;
        }
    }
    if t == VDB_NONE {
        return VdbFound(VDB_NONE, mesh_f32(a + 5u));
    }
    let child = mesh_word(t + 3u);
    if child == VDB_NONE {
        return VdbFound(VDB_NONE, mesh_f32(t + 4u));
    }
    let upper = a + mesh_word(a + 4u) + child;
    let u = (ijk & vec3i(4095)) >> vec3u(7u);
    let n = u32((u.x << 10u) | (u.y << 5u) | u.z);
    let e = upper + VDB_UPPER_TABLE + 2u * n;
    if ((mesh_word(upper + VDB_UPPER_MASK + (n >> 5u)) >> (n & 31u)) & 1u) == 0u {
        return VdbFound(VDB_NONE, vdb_tile(a, e));
    }
    // Child offsets are in bytes from the node, checked at commit to be
    // positive and below 2^32.
    let lower = upper + mesh_word(e) / 4u;
    let l = (ijk & vec3i(127)) >> vec3u(3u);
    let m = u32((l.x << 8u) | (l.y << 4u) | l.z);
    let f = lower + VDB_LOWER_TABLE + 2u * m;
    if ((mesh_word(lower + VDB_LOWER_MASK + (m >> 5u)) >> (m & 31u)) & 1u) == 0u {
        return VdbFound(VDB_NONE, vdb_tile(a, f));
    }
    return VdbFound(lower + mesh_word(f) / 4u, 0.0);
}

// Value n (x * 64 + y * 8 + z) of the leaf at word `leaf`.
fn vdb_leaf_value(a: u32, leaf: u32, n: u32) -> f32 {
    let t = leaf + VDB_LEAF_TABLE;
    let code = mesh_word(a);
    if code == 0u {
        return mesh_f32(t + n);
    }
    if code == 1u {
        return unpack2x16float(mesh_word(t + n / 2u))[n & 1u];
    }
    // Quantized: 2^code bits a value, 2^(5 - code) values a word; the
    // leaf's minimum and quantum lie 16 and 12 bytes before its table.
    let bits = 1u << code;
    let per_word = 5u - code;
    let w = mesh_word(t + (n >> per_word));
    let q = (w >> ((n & ((1u << per_word) - 1u)) * bits)) & ((1u << bits) - 1u);
    return f32(q) * mesh_f32(t - 3u) + mesh_f32(t - 4u);
}

fn vdb_voxel(a: u32, ijk: vec3i) -> f32 {
    let found = vdb_find(a, ijk);
    if found.leaf == VDB_NONE {
        return found.value;
    }
    let l = ijk & vec3i(7);
    return vdb_leaf_value(a, found.leaf, u32((l.x << 6u) | (l.y << 3u) | l.z));
}

// Volume v's NanoVDB grid at lattice point `grid`: the nearest voxel, or
// trilinear between the eight around it (one lookup where they share a
// leaf or a tile).
fn vdb_value(v: u32, grid: vec3f) -> f32 {
    let a = params.volumes[v].mesh_offset;
    let first = bitcast<vec3i>(vec3u(mesh_word(a + 6u), mesh_word(a + 7u), mesh_word(a + 8u)));
    let p = vec3f(first) + grid;
    if mesh_word(a + 1u) == 1u {
        return vdb_voxel(a, vec3i(floor(p + vec3f(0.5))));
    }
    let p0 = floor(p);
    let f = p - p0;
    let i0 = vec3i(p0);
    let l = i0 & vec3i(7);
    var c: array<f32, 8>;
    if all(l < vec3i(7)) {
        let key = vec4i(i0 & vec3i(~7), i32(a));
        if any(key != vdb_last_key) {
            vdb_last = vdb_find(a, i0);
            vdb_last_key = key;
        }
        let found = vdb_last;
        if found.leaf == VDB_NONE {
            return found.value;
        }
        let n = u32((l.x << 6u) | (l.y << 3u) | l.z);
        for (var k = 0u; k < 8u; k++) {
            c[k] = vdb_leaf_value(a, found.leaf, n + 64u * (k & 1u) + 8u * ((k >> 1u) & 1u) + (k >> 2u));
        }
    } else {
        for (var k = 0u; k < 8u; k++) {
            c[k] = vdb_voxel(a, i0 + vec3i(i32(k & 1u), i32((k >> 1u) & 1u), i32(k >> 2u)));
        }
    }
    let x00 = mix(c[0], c[1], f.x);
    let x10 = mix(c[2], c[3], f.x);
    let x01 = mix(c[4], c[5], f.x);
    let x11 = mix(c[6], c[7], f.x);
    return mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z);
}
