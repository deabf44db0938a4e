// #import constants, volume_bindings, cells
// AMR volumes: the field among the cells of block-structured levels, read
// from their words in `meshes` (layout in src/render/gpu/amr.rs). Mirrors
// src/scene/amr.rs: level by level, finest first, the eight cells around
// the point, weighted by the interior ones; the basis method for what no
// whole stencil covers.

// Set where a volume of the scene is an AMR field: without it the
// sampling is dropped.
override AMR: bool = false;

const AMR_NONE: u32 = 0xffffffffu;

// The first word of level `level`'s brick `b` of the field at word `a`,
// or AMR_NONE: the hash of scene::amr::amr_slot, probed linearly.
fn amr_brick(a: u32, level: u32, b: vec3i) -> u32 {
    let mask = mesh_word(a + 1u);
    let probes = mesh_word(a + 2u);
    let table = a + mesh_word(a + 3u);
    let u = bitcast<vec3u>(b);
    let h = (u.x * 0x9e3779b1u) ^ (u.y * 0x85ebca77u) ^ (u.z * 0xc2b2ae3du) ^ (level * 0x27d4eb2fu);
    var s = (h ^ (h >> 15u)) & mask;
    for (var i = 0u; i < probes; i++) {
        let e = table + 4u * s;
        let tag = mesh_word(e + 3u);
        if tag == AMR_EMPTY {
            return AMR_NONE;
        }
        if tag >> 27u == level && mesh_word(e) == u.x && mesh_word(e + 1u) == u.y && mesh_word(e + 2u) == u.z {
            return a + mesh_word(a + 4u) + (tag & 0x7ffffffu) * 512u;
        }
        s = (s + 1u) & mask;
    }
    return AMR_NONE;
}

// Volume v's AMR field at lattice point `grid`, or MESH_OUTSIDE beyond
// every cell's tent.
fn amr_value(v: u32, grid: vec3f) -> f32 {
    let a = params.volumes[v].mesh_offset;
    let x = mesh_vec3(a + 5u) + grid * mesh_vec3(a + 8u);
    let levels = mesh_word(a);
    var basis: array<vec2f, MAX_AMR_LEVELS>;
    var remaining = 1.0;
    var acc = 0.0;
    for (var k = 0u; k < levels; k++) {
        let at = a + 11u + 8u * k;
        let level = mesh_word(at);
        let u = clamp(x * mesh_f32(at + 1u) - vec3f(0.5), mesh_vec3(at + 2u), mesh_vec3(at + 5u));
        let i0f = floor(u);
        let f = u - i0f;
        let i0 = vec3i(i0f);
        var words: array<u32, 8>;
        var all = 1u;
        var last = vec3i(0);
        var brick = AMR_NONE;
        var alpha = 0.0;
        var weights = 0.0;
        var sum = 0.0;
        for (var n = 0u; n < 8u; n++) {
            let d = vec3u(n & 1u, (n >> 1u) & 1u, n >> 2u);
            let c = i0 + vec3i(d);
            let b = c >> vec3u(3u);
            if n == 0u || any(b != last) {
                brick = amr_brick(a, level, b);
                last = b;
            }
            var word = AMR_ABSENT;
            if brick != AMR_NONE {
                let l = c & vec3i(7);
                word = mesh_word(brick + u32(l.x + 8 * (l.y + 8 * l.z)));
            }
            words[n] = word;
            all &= word;
            if word != AMR_ABSENT {
                let wv = select(vec3f(1.0) - f, f, d == vec3u(1u));
                let weight = wv.x * wv.y * wv.z;
                weights += weight;
                sum += weight * bitcast<f32>(word & ~1u);
                if (word & 1u) == 1u {
                    alpha += weight;
                }
            }
        }
        basis[k] = vec2f(weights, sum);
        // Eight interior cells: the level's trilinear value is all that is
        // left to take (the reference's form of it).
        if (all & 1u) == 1u {
            var v: array<f32, 8>;
            for (var n = 0u; n < 8u; n++) {
                v[n] = bitcast<f32>(words[n] & ~1u);
            }
            let x00 = v[0] + (v[1] - v[0]) * f.x;
            let x10 = v[2] + (v[3] - v[2]) * f.x;
            let x01 = v[4] + (v[5] - v[4]) * f.x;
            let x11 = v[6] + (v[7] - v[6]) * f.x;
            let y0 = x00 + (x10 - x00) * f.y;
            let y1 = x01 + (x11 - x01) * f.y;
            return acc + remaining * (y0 + (y1 - y0) * f.z);
        }
        if alpha > 0.0 {
            acc += remaining * alpha * sum;
            remaining *= 1.0 - alpha;
            if remaining <= 0.0 {
                return acc;
            }
        }
    }
    var left = 1.0;
    var filled = 0.0;
    for (var k = 0u; k < levels; k++) {
        filled += left * basis[k].y;
        left *= 1.0 - basis[k].x;
    }
    if left >= 1.0 {
        return MESH_OUTSIDE;
    }
    return acc + remaining * filled / (1.0 - left);
}
