// #import constants, volume_bindings, volume
// The world's triangles, spheres, cones (cylinders among them) and curves: the nearest hit along a
// ray in their BVH and its lit color, as src/render/shapes/ finds and
// shades it on the CPU (the reference), operation for operation. The
// words of `surfaces` and `surface_shading` are laid out by
// src/render/shapes/packed.rs, which documents them; params.surface_nodes is 0 where the world has none.

const NO_SLOT: u32 = 0xffffffffu;

// Set where the scene has surfaces (variant.rs): every pass that meets
// them tests it first, so that without surfaces the compiler drops the
// traversal and the shading. Software Vulkan compiles them for seconds,
// and a march that merely contains them runs several times slower.
override SURFACES: bool = true;

struct SurfaceHit {
    // Along the ray; infinite where nothing was hit.
    t: f32,
    // The leaf slot of the primitive hit, and the weights of its second
    // and third corner there.
    slot: u32,
    bary: vec2f,
}

fn infinite() -> f32 {
    return bitcast<f32>(0x7f800000u);
}

// A box's far distance is stretched by this much (1 + 2 gamma(3), Ize
// 2013), so that rounding cannot make a ray miss a box it grazes: a ray
// through a mesh's corner meets the boxes of the triangles there.
const ROBUST: f32 = 1.0000004;

// Where o + t d enters box [lo, hi] within (t_min, t_max), or infinity.
fn box_entry(o: vec3f, inv: vec3f, lo: vec3f, hi: vec3f, t_min: f32, t_max: f32) -> f32 {
    let ta = (lo - o) * inv;
    let tb = (hi - o) * inv;
    let tn = min(ta, tb);
    let tf = max(ta, tb);
    let near = max(max(max(tn.x, tn.y), tn.z), t_min);
    let far = min(min(min(tf.x, tf.y), tf.z), t_max) * ROBUST;
    if near <= far {
        return near;
    }
    return infinite();
}

fn surface_word(i: u32) -> vec4f {
    return surfaces[i];
}

fn prim_word(slot: u32, k: u32) -> vec4f {
    return surfaces[params.surface_prims + 3u * slot + k];
}

// Where shape's words begin.
fn shape_at(shape: u32) -> u32 {
    return params.surface_shapes + SHAPE_WORDS * shape;
}

fn shape_word(shape: u32, k: u32) -> vec4f {
    return surfaces[shape_at(shape) + k];
}

// Point p (w 1) or direction (w 0) into shape's object space.
fn to_object(shape: u32, v: vec4f) -> vec3f {
    return vec3f(dot(shape_word(shape, 0u), v), dot(shape_word(shape, 1u), v), dot(shape_word(shape, 2u), v));
}

fn normal_to_world(shape: u32, n: vec3f) -> vec3f {
    return vec3f(dot(shape_word(shape, 3u).xyz, n), dot(shape_word(shape, 4u).xyz, n), dot(shape_word(shape, 5u).xyz, n));
}

// The watertight test from either side (intersect.rs's
// sheared_triangle): (t, weights of b and c), t infinite on a miss.
fn hit_triangle(o: vec3f, d: vec3f, a_world: vec3f, b_world: vec3f, c_world: vec3f) -> vec3f {
    let miss = vec3f(infinite(), 0.0, 0.0);
    let m = abs(d);
    var kz = 2u;
    if m.x >= m.y && m.x >= m.z {
        kz = 0u;
    } else if m.y >= m.z {
        kz = 1u;
    }
    var kx = (kz + 1u) % 3u;
    var ky = (kz + 2u) % 3u;
    if d[kz] < 0.0 {
        let swap = kx;
        kx = ky;
        ky = swap;
    }
    let sx = d[kx] / d[kz];
    let sy = d[ky] / d[kz];
    let sz = 1.0 / d[kz];
    let a = a_world - o;
    let b = b_world - o;
    let c = c_world - o;
    let ax = a[kx] - sx * a[kz];
    let ay = a[ky] - sy * a[kz];
    let bx = b[kx] - sx * b[kz];
    let by = b[ky] - sy * b[kz];
    let cx = c[kx] - sx * c[kz];
    let cy = c[ky] - sy * c[kz];
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return miss;
    }
    let det = u + v + w;
    if det == 0.0 || !(abs(det) < infinite()) {
        return miss;
    }
    let t = u * (sz * a[kz]) + v * (sz * b[kz]) + w * (sz * c[kz]);
    let inv = 1.0 / det;
    return vec3f(t * inv, v * inv, w * inv);
}

// The first t in (t_min, t_max) on the sphere at c of radius r, d of
// any length; infinite on a miss.
fn hit_sphere(o: vec3f, d: vec3f, c: vec3f, r: f32, t_min: f32, t_max: f32) -> f32 {
    let a = dot(d, d);
    if a == 0.0 {
        return infinite();
    }
    let oc = o - c;
    let b = dot(oc, d);
    let perp = oc - d * (b / a);
    let disc = r * r - dot(perp, perp);
    if disc < 0.0 {
        return infinite();
    }
    let h = sqrt(a * disc);
    let near = (-b - h) / a;
    if near > t_min && near < t_max {
        return near;
    }
    let far = (-b + h) / a;
    if far > t_min && far < t_max {
        return far;
    }
    return infinite();
}

// The first t in (t_min, t_max) on the cone from a (radius ra) to b
// (radius rb), with the caps bits 0 (at a) and 1 (at b) closed, and how
// far along the axis it is met: (t, s), t infinite on a miss (cone() in
// src/render/shapes/intersect.rs).
fn hit_cone(o: vec3f, d: vec3f, a: vec4f, b: vec4f, caps: u32, t_min: f32, t_max: f32) -> vec2f {
    var best = vec2f(infinite(), 0.0);
    let dd = dot(d, d);
    if dd == 0.0 {
        return best;
    }
    let len = distance(a.xyz, b.xyz);
    let axis = (b.xyz - a.xyz) / len;
    let shift = dot((a.xyz + b.xyz) * 0.5 - o, d) / dd;
    let oc = o + d * shift - a.xyz;
    let slope = (b.w - a.w) / len;
    let along_d = dot(d, axis);
    let along_o = dot(oc, axis);
    let dp = d - axis * along_d;
    let op = oc - axis * along_o;
    let r0 = a.w + slope * along_o;
    let rd = slope * along_d;
    let qa = dot(dp, dp) - rd * rd;
    let qb = dot(op, dp) - r0 * rd;
    let qc = dot(op, op) - r0 * r0;
    let disc = qb * qb - qa * qc;
    if disc >= 0.0 {
        let root = sqrt(disc);
        let q = -(qb + select(root, -root, qb < 0.0));
        for (var k = 0u; k < 2u; k++) {
            let local = select(q / qa, qc / q, k == 1u);
            let s = along_o + local * along_d;
            let t = local + shift;
            if abs(local) < infinite() && s >= 0.0 && s <= len && t > t_min && t < t_max && t < best.x {
                best = vec2f(t, s / len);
            }
        }
    }
    if along_d != 0.0 {
        for (var k = 0u; k < 2u; k++) {
            if (caps & (1u << k)) == 0u {
                continue;
            }
            let end = select(a, b, k == 1u);
            let local = dot(end.xyz - a.xyz - oc, axis) / along_d;
            let off = oc + d * local - (end.xyz - a.xyz);
            let t = local + shift;
            if dot(off, off) <= end.w * end.w && t > t_min && t < t_max && t < best.x {
                best = vec2f(t, f32(k));
            }
        }
    }
    return best;
}

// The cone joining the spheres a and b tangentially, as its two ends
// (radius in w); a zero-length axis where one sphere holds the other
// (tangent_cone()).
fn tangent_cone(a: vec4f, b: vec4f) -> array<vec4f, 2> {
    let len = distance(a.xyz, b.xyz);
    let along = (a.w - b.w) / len;
    if !(abs(along) < 1.0) {
        return array<vec4f, 2>(a, a);
    }
    let across = sqrt(1.0 - along * along);
    let axis = (b.xyz - a.xyz) / len;
    return array<vec4f, 2>(vec4f(a.xyz + axis * (a.w * along), a.w * across), vec4f(b.xyz + axis * (b.w * along), b.w * across));
}

// The first t in (t_min, t_max) on the round curve segment from sphere a
// to sphere b, and how far along it the hit lies (curve()).
fn hit_curve(o: vec3f, d: vec3f, a: vec4f, b: vec4f, t_min: f32, t_max: f32) -> vec2f {
    var best = vec2f(infinite(), 0.0);
    let ta = hit_sphere(o, d, a.xyz, a.w, t_min, t_max);
    if ta < best.x {
        best = vec2f(ta, 0.0);
    }
    let tb = hit_sphere(o, d, b.xyz, b.w, t_min, min(t_max, best.x));
    if tb < best.x {
        best = vec2f(tb, 1.0);
    }
    let side = tangent_cone(a, b);
    if any(side[0].xyz != side[1].xyz) {
        let h = hit_cone(o, d, side[0], side[1], 0u, t_min, min(t_max, best.x));
        if h.x < best.x {
            let axis = b.xyz - a.xyz;
            best = vec2f(h.x, clamp(dot(o + d * h.x - a.xyz, axis) / dot(axis, axis), 0.0, 1.0));
        }
    }
    return best;
}

// The outward normal at q on the cone from a to b; a point inside the
// rim of an end is on that end's disc (cone_normal()).
fn cone_normal(a: vec4f, b: vec4f, q: vec3f, caps: bool) -> vec3f {
    let len = distance(a.xyz, b.xyz);
    let axis = (b.xyz - a.xyz) / len;
    let p = q - a.xyz;
    let s = dot(p, axis);
    let radial = p - axis * s;
    let slope = (b.w - a.w) / len;
    let r = a.w + slope * clamp(s, 0.0, len);
    let rl = length(radial);
    if caps && rl < r * (1.0 - 1e-4) {
        return select(axis, -axis, s < 0.5 * len);
    }
    var unit = vec3f(0.0);
    if rl > 0.0 {
        unit = radial / rl;
    }
    return unit - axis * slope;
}

// The outward normal at q on the round curve segment a to b
// (curve_normal()).
fn curve_normal(a: vec4f, b: vec4f, q: vec3f) -> vec3f {
    let side = tangent_cone(a, b);
    if all(side[0].xyz == side[1].xyz) {
        return q - select(b.xyz, a.xyz, a.w >= b.w);
    }
    let axis = b.xyz - a.xyz;
    let s = dot(q - a.xyz, axis);
    if s <= dot(side[0].xyz - a.xyz, axis) {
        return q - a.xyz;
    }
    if s >= dot(side[1].xyz - a.xyz, axis) {
        return q - b.xyz;
    }
    return cone_normal(side[0], side[1], q, false);
}

// Slot `slot`'s primitive along o + t d: (t, bary), t infinite on a miss.
fn hit_slot(slot: u32, o: vec3f, d: vec3f, t_min: f32, t_max: f32) -> vec3f {
    let w0 = prim_word(slot, 0u);
    let w1 = prim_word(slot, 1u);
    let header = bitcast<u32>(w1.w);
    let shape = header >> 4u;
    switch header & 3u {
        case KIND_TRIANGLE: {
            let h = hit_triangle(o, d, w0.xyz, w1.xyz, prim_word(slot, 2u).xyz);
            if h.x > t_min && h.x < t_max {
                return h;
            }
            return vec3f(infinite(), 0.0, 0.0);
        }
        case KIND_SPHERE: {
            let oo = to_object(shape, vec4f(o, 1.0));
            let od = to_object(shape, vec4f(d, 0.0));
            return vec3f(hit_sphere(oo, od, w0.xyz, w0.w, t_min, t_max), 0.0, 0.0);
        }
        case KIND_CONE: {
            let oo = to_object(shape, vec4f(o, 1.0));
            let od = to_object(shape, vec4f(d, 0.0));
            let b = vec4f(w1.xyz, prim_word(slot, 2u).x);
            let h = hit_cone(oo, od, w0, b, (header >> 2u) & 3u, t_min, t_max);
            return vec3f(h.x, h.y, 0.0);
        }
        default: {
            let oo = to_object(shape, vec4f(o, 1.0));
            let od = to_object(shape, vec4f(d, 0.0));
            let h = hit_curve(oo, od, w0, vec4f(w1.xyz, prim_word(slot, 2u).x), t_min, t_max);
            return vec3f(h.x, h.y, 0.0);
        }
    }
}

// Slot `slot`'s primitive where first hit and drawn along o + t d: past
// the points its opacity hides (ShapeSet::shown).
fn shown_slot(slot: u32, o: vec3f, d: vec3f, t_min: f32, t_max: f32) -> vec3f {
    var after = t_min;
    // A primitive meets a ray at most four times.
    for (var k = 0u; k < 4u; k++) {
        let h = hit_slot(slot, o, d, after, t_max);
        if !(h.x < t_max) || surface_alpha(SurfaceHit(h.x, slot, h.yz)) > 0.0 {
            return h;
        }
        after = h.x;
    }
    return vec3f(infinite(), 0.0, 0.0);
}

// The nearest surface with t in (t_min, t_max) along o + t d.
fn nearest_surface(o: vec3f, d: vec3f, t_min: f32, t_max: f32) -> SurfaceHit {
    var best = SurfaceHit(infinite(), NO_SLOT, vec2f(0.0));
    if !SURFACES || params.surface_nodes == 0u || !(t_max > t_min) {
        return best;
    }
    let inv = vec3f(safe_inverse(d.x), safe_inverse(d.y), safe_inverse(d.z));
    var limit = t_max;
    // Nodes to visit later, with where the ray enters them.
    var stack: array<u32, TRAVERSAL_STACK>;
    var entries: array<f32, TRAVERSAL_STACK>;
    var depth = 0u;
    var node = 0u;
    if box_entry(o, inv, surface_word(0u).xyz, surface_word(1u).xyz, t_min, limit) == infinite() {
        return best;
    }
    loop {
        let lo = surface_word(2u * node);
        let hi = surface_word(2u * node + 1u);
        let count = bitcast<u32>(lo.w);
        let first = bitcast<u32>(hi.w);
        var descend = false;
        if count > 0u {
            for (var j = first; j < first + count; j++) {
                let h = shown_slot(j, o, d, t_min, limit);
                if h.x < limit {
                    limit = h.x;
                    best = SurfaceHit(h.x, j, h.yz);
                }
            }
        } else {
            let ta = box_entry(o, inv, surface_word(2u * first).xyz, surface_word(2u * first + 1u).xyz, t_min, limit);
            let tb = box_entry(o, inv, surface_word(2u * first + 2u).xyz, surface_word(2u * first + 3u).xyz, t_min, limit);
            let b_first = tb < ta;
            let near = min(ta, tb);
            let far = max(ta, tb);
            if near < infinite() {
                if far < infinite() && depth < TRAVERSAL_STACK {
                    stack[depth] = select(first + 1u, first, b_first);
                    entries[depth] = far;
                    depth++;
                }
                node = select(first, first + 1u, b_first);
                descend = true;
            }
        }
        if descend {
            continue;
        }
        // The next node kept that a nearer hit has not ruled out.
        var next = NO_SLOT;
        while depth > 0u {
            depth--;
            if entries[depth] < limit {
                next = stack[depth];
                break;
            }
        }
        if next == NO_SLOT {
            break;
        }
        node = next;
    }
    return best;
}

// The world-space unit normal at hit h (point p) facing against d.
fn surface_normal(h: SurfaceHit, p: vec3f, d: vec3f) -> vec3f {
    let w0 = prim_word(h.slot, 0u);
    let w1 = prim_word(h.slot, 1u);
    let w2 = prim_word(h.slot, 2u);
    let header = bitcast<u32>(w1.w);
    let shape = header >> 4u;
    var n: vec3f;
    switch header & 3u {
        case KIND_TRIANGLE: {
            let flags = bitcast<u32>(shape_word(shape, 7u).x);
            if (flags & FLAG_NORMALS) != 0u {
                let at = shading_at(shape, bitcast<u32>(w2.w)) + select(0u, 3u, (flags & (FLAG_ALBEDO | FLAG_IMAGE)) != 0u);
                let weights = vec3f(1.0 - h.bary.x - h.bary.y, h.bary.x, h.bary.y);
                n = surface_shading[at].xyz * weights.x + surface_shading[at + 1u].xyz * weights.y + surface_shading[at + 2u].xyz * weights.z;
            } else {
                n = cross(w1.xyz - w0.xyz, w2.xyz - w0.xyz);
            }
        }
        case KIND_SPHERE: {
            n = normal_to_world(shape, to_object(shape, vec4f(p, 1.0)) - w0.xyz);
        }
        case KIND_CONE: {
            let q = to_object(shape, vec4f(p, 1.0));
            n = normal_to_world(shape, cone_normal(w0, vec4f(w1.xyz, w2.x), q, true));
        }
        default: {
            let q = to_object(shape, vec4f(p, 1.0));
            n = normal_to_world(shape, curve_normal(w0, vec4f(w1.xyz, w2.x), q));
        }
    }
    // A normal the host gave may be zero: then face the ray.
    let len = length(n);
    if !(len > 0.0) || !(len < infinite()) {
        return -d;
    }
    n = n / len;
    if dot(n, d) > 0.0 {
        return -n;
    }
    return n;
}

// Where shape's shading data for kept primitive `index` begins.
fn shading_at(shape: u32, index: u32) -> u32 {
    let flags = bitcast<u32>(shape_word(shape, 7u).x);
    let stride = select(0u, 3u, (flags & (FLAG_ALBEDO | FLAG_IMAGE)) != 0u) + select(0u, 3u, (flags & FLAG_NORMALS) != 0u) + select(0u, 1u, (flags & FLAG_OPACITY) != 0u) + select(0u, 3u, (flags & FLAG_OPACITY_IMAGE) != 0u);
    return bitcast<u32>(shape_word(shape, 6u).w) + stride * index;
}

// Shape's kept primitive at slot.
fn slot_shape(slot: u32) -> u32 {
    return bitcast<u32>(prim_word(slot, 1u).w) >> 4u;
}

fn slot_index(slot: u32) -> u32 {
    return bitcast<u32>(prim_word(slot, 2u).w);
}

// Three corner words from `at` weighted by h's barycentrics.
fn at_corners(at: u32, h: SurfaceHit) -> vec4f {
    let weights = vec3f(1.0 - h.bary.x - h.bary.y, h.bary.x, h.bary.y);
    return surface_shading[at] * weights.x + surface_shading[at + 1u] * weights.y + surface_shading[at + 2u] * weights.z;
}

// The material's color at h, its fourth component the color's alpha
// where it varies (ShapeSet::read).
fn surface_rgba(h: SurfaceHit) -> vec4f {
    let shape = slot_shape(h.slot);
    let flags = bitcast<u32>(shape_word(shape, 7u).x);
    if (flags & (FLAG_ALBEDO | FLAG_IMAGE)) == 0u {
        return vec4f(shape_word(shape, 6u).xyz, 1.0);
    }
    let v = at_corners(shading_at(shape, slot_index(h.slot)), h);
    if (flags & FLAG_IMAGE) == 0u {
        return v;
    }
    return image_sample(shape_at(shape) + COLOR_IMAGE, v);
}

fn surface_albedo(h: SurfaceHit) -> vec3f {
    return surface_rgba(h).xyz;
}

// The opacity of the surface at h after its alpha mode: 1 opaque, 0 not
// drawn (ShapeSet::opacity, AlphaMode::coverage).
fn surface_alpha(h: SurfaceHit) -> f32 {
    let shape = slot_shape(h.slot);
    let material = shape_word(shape, 7u);
    let flags = bitcast<u32>(material.x);
    if (flags & (FLAG_BLEND | FLAG_MASK)) == 0u {
        return 1.0;
    }
    var a = material.y;
    if (flags & (FLAG_OPACITY | FLAG_OPACITY_IMAGE)) != 0u {
        // After the color's and the normals' words.
        let skip = select(0u, 3u, (flags & (FLAG_ALBEDO | FLAG_IMAGE)) != 0u) + select(0u, 3u, (flags & FLAG_NORMALS) != 0u);
        let at = shading_at(shape, slot_index(h.slot)) + skip;
        if (flags & FLAG_OPACITY) != 0u {
            let weights = vec3f(1.0 - h.bary.x - h.bary.y, h.bary.x, h.bary.y);
            a *= dot(surface_shading[at].xyz, weights);
        } else {
            a *= image_sample(shape_at(shape) + OPACITY_IMAGE, at_corners(at, h)).x;
        }
    }
    if (flags & (FLAG_ALBEDO | FLAG_IMAGE)) != 0u {
        a *= surface_rgba(h).w;
    }
    a = select(0.0, min(a, 1.0), a > 0.0);
    if (flags & FLAG_MASK) != 0u {
        return select(0.0, 1.0, a >= shape_word(shape, 15u).w);
    }
    return a;
}

// Texel i of n after the wrap mode (Wrap::index).
fn wrap_index(mode: u32, i: i32, n: i32) -> i32 {
    switch mode {
        case 1u: {
            return ((i % n) + n) % n;
        }
        case 2u: {
            let m = ((i % (2 * n)) + 2 * n) % (2 * n);
            return select(m, 2 * n - 1 - m, m >= n);
        }
        default: {
            return clamp(i, 0, n - 1);
        }
    }
}

// The image sampler whose words begin at `block` at coordinates c,
// out-transformed (Image::at, Sampler::sample).
fn image_sample(block: u32, c: vec4f) -> vec4f {
    let info = surfaces[block];
    let dims = vec3i(vec3u(bitcast<u32>(info.x), bitcast<u32>(info.y), bitcast<u32>(info.z)));
    let base = bitcast<u32>(info.w);
    let mode = surfaces[block + 1u];
    let linear = bitcast<u32>(mode.x) != 0u;
    let wraps = vec3u(bitcast<u32>(mode.y), bitcast<u32>(mode.z), bitcast<u32>(mode.w));
    var lower: vec3i;
    var frac: vec3f;
    for (var k = 0u; k < 3u; k++) {
        // Texel centres at (i + 0.5) / n; far outside, an edge.
        let x = clamp(c[k] * f32(dims[k]) - 0.5, -16777216.0, 16777216.0);
        let f = floor(x);
        lower[k] = i32(f);
        frac[k] = x - f;
    }
    var sum = vec4f(0.0);
    for (var corner = 0u; corner < 8u; corner++) {
        var weight = 1.0;
        var index: vec3i;
        for (var k = 0u; k < 3u; k++) {
            let upper = ((corner >> k) & 1u) == 1u;
            if linear {
                weight *= select(1.0 - frac[k], frac[k], upper);
            } else if upper != (frac[k] >= 0.5) {
                weight = 0.0;
            }
            index[k] = wrap_index(wraps[k], lower[k] + select(0, 1, upper), dims[k]);
        }
        if weight != 0.0 {
            let i = u32(index.x + dims.x * (index.y + dims.y * index.z));
            sum += surface_shading[base + i] * weight;
        }
    }
    let v = vec4f(dot(surfaces[block + 2u], sum), dot(surfaces[block + 3u], sum), dot(surfaces[block + 4u], sum), dot(surfaces[block + 5u], sum));
    return v + surfaces[block + 6u];
}

// A translucent surface lit `lit`, of opacity a, at p (t along the ray)
// composited behind what `m` holds; true where it makes m's depth.
fn composite_surface(m: ptr<function, Marched>, lit: vec3f, a: f32, p: vec3f, t: f32) -> bool {
    let weight = (1.0 - (*m).color.a) * a;
    (*m).color = vec4f((*m).color.rgb + lit * weight, (*m).color.a + weight);
    if (*m).depth == infinite() && (*m).color.a >= params.depth_threshold {
        (*m).depth = depth_along(p, t);
        return true;
    }
    return false;
}

// Light reflected towards v per unit arriving from l, the cosine
// included: Lambertian, or where `pbr` the metallic-roughness model
// (brdf::reflected, operation for operation).
fn reflected(n: vec3f, v: vec3f, l: vec3f, albedo: vec3f, pbr: bool, metallic: f32, roughness: f32) -> vec3f {
    let nl = dot(n, l);
    if nl <= 0.0 {
        return vec3f(0.0);
    }
    if !pbr {
        return albedo * nl;
    }
    let nv = max(dot(n, v), 1e-4);
    let hl = length(l + v);
    var h = vec3f(0.0);
    if hl > 0.0 {
        h = (l + v) / hl;
    }
    let nh = max(dot(n, h), 0.0);
    let vh = clamp(dot(v, h), 0.0, 1.0);
    let r = max(roughness, MIN_ROUGHNESS);
    let a2 = (r * r) * (r * r);
    let x = nh * nh * (a2 - 1.0) + 1.0;
    let dist = a2 / (PI * x * x);
    let k = r * r / 2.0;
    let g = (nl / (nl * (1.0 - k) + k)) * (nv / (nv * (1.0 - k) + k));
    let f0 = mix(vec3f(0.04), albedo, metallic);
    let f = f0 + (vec3f(1.0) - f0) * pow(1.0 - vh, 5.0);
    let specular = f * (PI * dist * g / (4.0 * nv));
    return albedo * (1.0 - metallic) * nl + specular;
}

// Hit h of ray o + t d, shaded (ShapeSet::shade): the reference device's
// eye light blended with the color, or the world's directional light (or
// a light at the eye where it has none) and its point and spot lights
// reflected, plus the ambient light; and what the surface emits.
fn surface_color(h: SurfaceHit, o: vec3f, d: vec3f) -> vec3f {
    let p = o + d * h.t;
    let n = surface_normal(h, p, d);
    let v = -normalize(d);
    let albedo = surface_albedo(h);
    let shape = bitcast<u32>(prim_word(h.slot, 1u).w) >> 4u;
    let material = shape_word(shape, 7u);
    let pbr = (bitcast<u32>(material.x) & FLAG_PBR) != 0u;
    let emitted = shape_word(shape, 15u).xyz;
    if params.surface_lighting == SURFACE_LIT_EYE_BLEND {
        let facing = min(abs(dot(n, v)), 1.0);
        return albedo * (params.eye_blend * facing + 1.0 - params.eye_blend) + emitted;
    }
    var light = vec3f(0.0);
    if params.surface_lighting == SURFACE_LIT_FROM_EYE {
        light = reflected(n, v, v, albedo, pbr, material.z, material.w);
    } else if params.surface_lighting == SURFACE_LIT_DIRECTIONAL {
        light = params.surface_light_color * reflected(n, v, params.surface_light, albedo, pbr, material.z, material.w);
    }
    for (var i = 0u; i < params.lamp_count; i++) {
        let lamp = params.lamps[i];
        let offset = lamp.position - p;
        let d2 = max(dot(offset, offset), 1e-12);
        let towards = offset / sqrt(d2);
        var strength = 1.0 / d2;
        if lamp.spot != 0u {
            strength *= cone(lamp, -towards);
        }
        light += lamp.color * strength * reflected(n, v, towards, albedo, pbr, material.z, material.w);
    }
    return light + albedo * params.ambient + emitted;
}

// How much of a spot's light leaves along unit vector `out` (settings::cone).
fn cone(lamp: LampSlot, out: vec3f) -> f32 {
    let c = dot(out, lamp.direction);
    let lo = lamp.cos_outer;
    let hi = lamp.cos_inner;
    if hi <= lo {
        return select(0.0, 1.0, c >= lo);
    }
    let t = clamp((c - lo) / (hi - lo), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}
