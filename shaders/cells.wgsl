// #import constants, volume_bindings
// Unstructured volumes: the field inside the cells of a mesh, read from
// its words in `meshes` (layout in src/render/gpu/mesh.rs). Mirrors
// src/scene/unstructured.rs and tet_walk.rs: a walk from the ray's last
// cell finds the tetrahedron holding a point, else the cells' BVH finds
// the cells whose boxes hold it; barycentric coordinates place it in a
// tetrahedron and Newton's method inverts VTK's shape functions in the
// other kinds.

// Set where a volume of the scene is a mesh: without it the traversal
// and the shape functions are dropped.
override MESHES: bool = false;

// What a sample outside every cell reads: classify() makes it clear. A
// finite stand-in for the reference's NaN, which WGSL lets compilers
// assume away.
const MESH_OUTSIDE: f32 = -3.0e38;

fn mesh_word(at: u32) -> u32 {
    return meshes[at];
}

fn mesh_f32(at: u32) -> f32 {
    return bitcast<f32>(meshes[at]);
}

fn mesh_vec3(at: u32) -> vec3f {
    return vec3f(mesh_f32(at), mesh_f32(at + 1u), mesh_f32(at + 2u));
}

fn cell_vertices(kind: u32) -> u32 {
    switch kind {
        case 0u: { return 4u; }
        case 1u: { return 8u; }
        case 2u: { return 6u; }
        default: { return 5u; }
    }
}

// Vertex i's weight at parametric point r (x) and its derivatives along
// r, s and t (yzw), by VTK's interpolation functions.
fn cell_shape(kind: u32, i: u32, r: vec3f) -> vec4f {
    switch kind {
        case 0u: {
            switch i {
                case 0u: { return vec4f(1.0 - r.x - r.y - r.z, -1.0, -1.0, -1.0); }
                case 1u: { return vec4f(r.x, 1.0, 0.0, 0.0); }
                case 2u: { return vec4f(r.y, 0.0, 1.0, 0.0); }
                default: { return vec4f(r.z, 0.0, 0.0, 1.0); }
            }
        }
        case 2u: {
            // Wedge: triangle 0 1 2 at t = 0, 3 4 5 above.
            let j = i % 3u;
            var tri = vec3f(1.0 - r.x - r.y, -1.0, -1.0);
            if j == 1u {
                tri = vec3f(r.x, 1.0, 0.0);
            } else if j == 2u {
                tri = vec3f(r.y, 0.0, 1.0);
            }
            var h = 1.0 - r.z;
            var dh = -1.0;
            if i >= 3u {
                h = r.z;
                dh = 1.0;
            }
            return vec4f(tri.x * h, tri.y * h, tri.z * h, tri.x * dh);
        }
        default: {
            // Hexahedron, and the pyramid's base (its apex is vertex 4).
            if kind == 3u && i == 4u {
                return vec4f(r.z, 0.0, 0.0, 1.0);
            }
            let k = i % 4u;
            let cx = k == 1u || k == 2u;
            let cy = k >= 2u;
            let cz = kind == 1u && i >= 4u;
            let a = select(1.0 - r.x, r.x, cx);
            let b = select(1.0 - r.y, r.y, cy);
            let c = select(1.0 - r.z, r.z, cz);
            let sa = select(-1.0, 1.0, cx);
            let sb = select(-1.0, 1.0, cy);
            let sc = select(-1.0, 1.0, cz);
            return vec4f(a * b * c, sa * b * c, a * sb * c, a * b * sc);
        }
    }
}

fn cell_holds(kind: u32, r: vec3f) -> bool {
    let eps = CELL_TOLERANCE;
    let unit = all(r >= vec3f(-eps)) && all(r <= vec3f(1.0 + eps));
    switch kind {
        case 0u: { return all(r >= vec3f(-eps)) && r.x + r.y + r.z <= 1.0 + eps; }
        case 2u: { return unit && r.x + r.y <= 1.0 + eps; }
        default: { return unit; }
    }
}

struct CellHit {
    inside: bool,
    value: f32,
}

// The field at p if cell c (BVH order) of the mesh at word m holds it.
fn cell_value(m: u32, c: u32, p: vec3f) -> CellHit {
    let miss = CellHit(false, 0.0);
    let word = mesh_word(m + mesh_word(m + 1u) + c);
    let kind = word & 3u;
    let first = m + mesh_word(m + 2u) + (word >> 2u);
    let positions = m + mesh_word(m + 3u);
    let n = cell_vertices(kind);
    var lo = vec3f(3.0e38);
    var hi = vec3f(-3.0e38);
    for (var k = 0u; k < n; k++) {
        let q = mesh_vec3(positions + 3u * mesh_word(first + k));
        lo = min(lo, q);
        hi = max(hi, q);
    }
    let margin = (hi - lo) * CELL_TOLERANCE;
    if any(p < lo - margin) || any(p > hi + margin) {
        return miss;
    }
    var r: vec3f;
    if kind == 0u {
        let v0 = mesh_vec3(positions + 3u * mesh_word(first));
        let a = mesh_vec3(positions + 3u * mesh_word(first + 1u)) - v0;
        let b = mesh_vec3(positions + 3u * mesh_word(first + 2u)) - v0;
        let c3 = mesh_vec3(positions + 3u * mesh_word(first + 3u)) - v0;
        let det = dot(a, cross(b, c3));
        if det == 0.0 {
            return miss;
        }
        let q = p - v0;
        r = vec3f(dot(q, cross(b, c3)), dot(a, cross(q, c3)), dot(a, cross(b, q))) / det;
    } else {
        r = select(select(vec3f(0.5, 0.5, 0.2), vec3f(1.0 / 3.0, 1.0 / 3.0, 0.5), kind == 2u), vec3f(0.5), kind == 1u);
        for (var step = 0u; step < NEWTON_STEPS; step++) {
            var x = vec3f(0.0);
            var jr = vec3f(0.0);
            var js = vec3f(0.0);
            var jt = vec3f(0.0);
            for (var k = 0u; k < n; k++) {
                let s = cell_shape(kind, k, r);
                let q = mesh_vec3(positions + 3u * mesh_word(first + k));
                x += s.x * q;
                jr += s.y * q;
                js += s.z * q;
                jt += s.w * q;
            }
            let jac = mat3x3f(jr, js, jt);
            let det = determinant(jac);
            if det == 0.0 {
                return miss;
            }
            // The inverse by cofactors: transpose of the adjugate.
            let inv = transpose(mat3x3f(cross(js, jt), cross(jt, jr), cross(jr, js))) * (1.0 / det);
            let delta = inv * (x - p);
            r -= delta;
            if max(abs(delta.x), max(abs(delta.y), abs(delta.z))) < NEWTON_TOLERANCE {
                break;
            }
        }
    }
    if !cell_holds(kind, r) {
        return miss;
    }
    let values = m + mesh_word(m + 4u);
    if mesh_word(m + 5u) == 0u {
        return CellHit(true, mesh_f32(values + c));
    }
    var sum = 0.0;
    for (var k = 0u; k < n; k++) {
        sum += cell_shape(kind, k, r).x * mesh_f32(values + mesh_word(first + k));
    }
    return CellHit(true, sum);
}

// Where this invocation last found a sample in each volume's mesh (a
// cell number in BVH order): its next point sample is looked for from
// there.
var<private> mesh_near: array<u32, MAX_VOLUMES>;

struct Walked {
    found: bool,
    value: f32,
    cell: u32,
}

// The tetrahedron of the mesh at word m strictly holding p, walking from
// cell `start` across the face opposite the most negative barycentric
// coordinate (src/scene/tet_walk.rs), and the field there.
fn mesh_walk(m: u32, start: u32, p: vec3f) -> Walked {
    let walk = m + mesh_word(m + 12u);
    let cells = mesh_word(m + 2u) - mesh_word(m + 1u);
    var c = start;
    var out = Walked(false, 0.0, 0u);
    for (var s = 0u; s < WALK_STEPS; s++) {
        if c >= cells {
            break;
        }
        let w = walk + WALK_WORDS * c;
        if mesh_word(w + 20u) == 0u {
            break;
        }
        let q = p - mesh_vec3(w);
        let l1 = dot(mesh_vec3(w + 4u), q);
        let l2 = dot(mesh_vec3(w + 7u), q);
        let l3 = dot(mesh_vec3(w + 10u), q);
        let l0 = 1.0 - l1 - l2 - l3;
        if min(min(l0, l1), min(l2, l3)) >= 0.0 {
            out = Walked(true, mesh_f32(w + 3u) + dot(mesh_vec3(w + 13u), q), c);
            break;
        }
        var worst = 0u;
        var least = l0;
        if l1 < least {
            least = l1;
            worst = 1u;
        }
        if l2 < least {
            least = l2;
            worst = 2u;
        }
        if l3 < least {
            worst = 3u;
        }
        c = mesh_word(w + 16u + worst);
    }
    return out;
}

// Where the ray being marched runs through a tetrahedron of a mesh
// (tet_walk.rs's Stretch): from t_in to t_out, the field a + b t there,
// leaving into cell `next`. NO_STRETCH holds no t.
struct Stretch {
    cell: u32,
    t_in: f32,
    t_out: f32,
    a: f32,
    b: f32,
    next: u32,
}

const NO_STRETCH = Stretch(0xffffffffu, 0.0, -1.0, 0.0, 0.0, 0xffffffffu);

// Per volume: the marched ray in its mesh's coordinates, and the stretch
// of its last sample.
var<private> mesh_ray_o: array<vec3f, MAX_VOLUMES>;
var<private> mesh_ray_d: array<vec3f, MAX_VOLUMES>;
var<private> mesh_stretch_of: array<Stretch, MAX_VOLUMES>;

// Cell c's stretch of the ray o + t d (mesh at word m), NO_STRETCH where
// the ray misses it or it is no tetrahedron: each barycentric coordinate
// is linear in t, and the ray leaves where the first falls to 0.
fn mesh_stretch(m: u32, c: u32, o: vec3f, d: vec3f) -> Stretch {
    let cells = mesh_word(m + 2u) - mesh_word(m + 1u);
    if c >= cells {
        return NO_STRETCH;
    }
    let w = m + mesh_word(m + 12u) + WALK_WORDS * c;
    if mesh_word(w + 20u) == 0u {
        return NO_STRETCH;
    }
    let q = o - mesh_vec3(w);
    let r1 = mesh_vec3(w + 4u);
    let r2 = mesh_vec3(w + 7u);
    let r3 = mesh_vec3(w + 10u);
    let l = vec3f(dot(r1, q), dot(r2, q), dot(r3, q));
    let dl = vec3f(dot(r1, d), dot(r2, d), dot(r3, d));
    // Per face (opposite vertex 0 to 3): the coordinate and its change.
    let l4 = vec4f(1.0 - l.x - l.y - l.z, l);
    let d4 = vec4f(-dl.x - dl.y - dl.z, dl);
    if any((d4 == vec4f(0.0)) & (l4 < vec4f(0.0))) {
        // Parallel to a face and outside it.
        return NO_STRETCH;
    }
    let at = -l4 / d4;
    let inf = bitcast<f32>(0x7f800000u);
    let entering = select(vec4f(-inf), at, d4 > vec4f(0.0));
    let leaving = select(vec4f(inf), at, d4 < vec4f(0.0));
    let t_in = max(max(entering.x, entering.y), max(entering.z, entering.w));
    let t_out = min(min(leaving.x, leaving.y), min(leaving.z, leaving.w));
    // The first face where the ray leaves (4 where it never does).
    let first = select(vec4u(4u), vec4u(0u, 1u, 2u, 3u), leaving == vec4f(t_out));
    let exit = min(min(first.x, first.y), min(first.z, first.w));
    if !(t_in <= t_out) || t_out == inf {
        return NO_STRETCH;
    }
    let g = mesh_vec3(w + 13u);
    return Stretch(c, t_in, t_out, mesh_f32(w + 3u) + dot(g, q), dot(g, d), mesh_word(w + 16u + exit));
}

// Starts the march of ray o + t d (world) through volume v's mesh.
fn mesh_begin(v: u32, o: vec3f, d: vec3f) {
    let m = params.volumes[v].mesh_offset;
    let spacing = mesh_vec3(m + 9u);
    mesh_ray_o[v] = mesh_vec3(m + 6u) + grid_of(v, o) * spacing;
    mesh_ray_d[v] = grid_direction(v, d) * spacing;
    mesh_stretch_of[v] = NO_STRETCH;
}

// Volume v's mesh at lattice point `grid`, t along the marched ray, whose
// samples come in increasing t: in the tetrahedron of the last sample or
// one the ray enters after it (UnstructuredVolume::sample_along), else as
// mesh_value finds it.
fn mesh_value_along(v: u32, grid: vec3f, t: f32) -> f32 {
    let m = params.volumes[v].mesh_offset;
    if mesh_word(m + 12u) == 0u {
        return mesh_value(v, grid);
    }
    let o = mesh_ray_o[v];
    let d = mesh_ray_d[v];
    var s = mesh_stretch_of[v];
    for (var k = 0u; k < WALK_STEPS && t > s.t_out && s.cell != 0xffffffffu; k++) {
        s = mesh_stretch(m, s.next, o, d);
    }
    if s.t_in <= t && t <= s.t_out {
        mesh_stretch_of[v] = s;
        mesh_near[v] = s.cell;
        return s.a + s.b * t;
    }
    let value = mesh_value(v, grid);
    s = NO_STRETCH;
    if value != MESH_OUTSIDE {
        s = mesh_stretch(m, mesh_near[v], o, d);
        if !(s.t_in <= t && t <= s.t_out) {
            s = NO_STRETCH;
        }
    }
    mesh_stretch_of[v] = s;
    return value;
}

// Volume v's mesh at lattice point `grid`: the first cell holding it, or
// MESH_OUTSIDE; where the mesh has tetrahedra, first by a walk from the
// ray's last cell.
fn mesh_value(v: u32, grid: vec3f) -> f32 {
    let m = params.volumes[v].mesh_offset;
    let p = mesh_vec3(m + 6u) + grid * mesh_vec3(m + 9u);
    if mesh_word(m + 12u) != 0u {
        let walked = mesh_walk(m, mesh_near[v], p);
        if walked.found {
            mesh_near[v] = walked.cell;
            return walked.value;
        }
    }
    let nodes = m + mesh_word(m);
    var stack: array<u32, MESH_STACK>;
    stack[0] = 0u;
    var depth = 1u;
    var value = MESH_OUTSIDE;
    loop {
        if depth == 0u {
            break;
        }
        depth -= 1u;
        let at = nodes + 8u * stack[depth];
        if any(p < mesh_vec3(at)) || any(p > mesh_vec3(at + 4u)) {
            continue;
        }
        let first = mesh_word(at + 3u);
        let count = mesh_word(at + 7u);
        if count == 0u {
            stack[depth] = first;
            stack[depth + 1u] = first + 1u;
            depth += 2u;
            continue;
        }
        var found = false;
        for (var c = first; c < first + count; c++) {
            let hit = cell_value(m, c, p);
            if hit.inside {
                value = hit.value;
                mesh_near[v] = c;
                found = true;
                break;
            }
        }
        if found {
            break;
        }
    }
    return value;
}
