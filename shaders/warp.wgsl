// #import constants, warp_bindings
// Image warping (src/render/warp/): the quad, grid and layers warps, each
// the port of its CPU reference, which the tests hold it to.

fn infinity() -> f32 {
    return bitcast<f32>(0x7f800000u);
}

// A view's rays and its projector (src/render/warp/project.rs).
struct View {
    origin: vec3f,
    origin_dx: vec3f,
    origin_dy: vec3f,
    direction: vec3f,
    direction_dx: vec3f,
    direction_dy: vec3f,
    eye: vec4f,
    inverse: mat3x3f,
    centre: vec4f,
}

fn source_view() -> View {
    return View(w.from_origin.xyz, w.from_origin_dx.xyz, w.from_origin_dy.xyz,
        w.from_direction.xyz, w.from_direction_dx.xyz, w.from_direction_dy.xyz, w.from_eye,
        mat3x3f(w.from_inverse_x.xyz, w.from_inverse_y.xyz, w.from_inverse_z.xyz), w.from_centre);
}

fn target_view() -> View {
    return View(w.to_origin.xyz, w.to_origin_dx.xyz, w.to_origin_dy.xyz,
        w.to_direction.xyz, w.to_direction_dx.xyz, w.to_direction_dy.xyz, w.to_eye,
        mat3x3f(w.to_inverse_x.xyz, w.to_inverse_y.xyz, w.to_inverse_z.xyz), w.to_centre);
}

struct Ray {
    o: vec3f,
    d: vec3f,
}

fn pixel_ray(v: View, x: f32, y: f32) -> Ray {
    let o = v.origin + x * v.origin_dx + y * v.origin_dy;
    let d = normalize(v.direction + x * v.direction_dx + y * v.direction_dy);
    return Ray(o, d);
}

fn depth_at(v: View, p: vec3f, t: f32) -> f32 {
    if v.eye.w != 0.0 {
        return length(p - v.eye.xyz);
    }
    return t;
}

struct Located {
    at: vec2f,
    along: f32,
    direction: vec3f,
    ok: bool,
}

// Where `p` appears in the view's image (pixels) and how far along that
// position's unit ray; not ok behind a pinhole's eye.
fn locate(v: View, p: vec3f) -> Located {
    let q = v.inverse * (p - v.centre.xyz);
    var px = q.x;
    var py = q.y;
    if v.centre.w == 0.0 {
        if q.x <= 0.0 {
            return Located(vec2f(0.0), 0.0, vec3f(0.0), false);
        }
        px = q.y / q.x;
        py = q.z / q.x;
    }
    let r = pixel_ray(v, px, py);
    let at = vec2f(px + 0.5, py + 0.5);
    let finite = all(abs(at) < vec2f(1e30));
    return Located(at, dot(p - r.o, r.d), r.d, finite);
}

fn texel(x: i32, y: i32) -> vec4f {
    let size = vec2i(w.from_size);
    if x < 0 || y < 0 || x >= size.x || y >= size.y {
        return vec4f(0.0);
    }
    return color[u32(y) * w.from_size.x + u32(x)];
}

// Source color at image position `s`, bilinear between pixel centres,
// transparent outside the image.
fn color_at(s: vec2f) -> vec4f {
    if !(all(s >= vec2f(0.0)) && all(s <= vec2f(w.from_size))) {
        return vec4f(0.0);
    }
    let q = s - vec2f(0.5);
    let base = floor(q);
    let f = q - base;
    let b = vec2i(base);
    let bottom = mix(texel(b.x, b.y), texel(b.x + 1, b.y), f.x);
    let top = mix(texel(b.x, b.y + 1), texel(b.x + 1, b.y + 1), f.x);
    return mix(bottom, top, f.y);
}

// Target pixel `id`'s index, its outputs cleared (transparent, infinitely
// far); -1 outside the image.
fn begin_pixel(id: vec3u) -> i32 {
    if id.x >= w.to_size.x || id.y >= w.to_size.y {
        return -1;
    }
    let i = id.y * w.to_size.x + id.x;
    out_color[i] = vec4f(0.0);
    out_depth[i] = infinity();
    return i32(i);
}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn quad(@builtin(global_invocation_id) id: vec3u) {
    let i = begin_pixel(id);
    if i < 0 {
        return;
    }
    let seen_to = target_view();
    let r = pixel_ray(seen_to, f32(id.x), f32(id.y));
    let n = w.normal.xyz;
    let facing = dot(r.d, n);
    if abs(facing) < 1e-12 {
        return;
    }
    let t = dot(w.focus.xyz - r.o, n) / facing;
    if !(t > w.near && t < w.far) {
        return;
    }
    let p = r.o + r.d * t;
    let l = locate(source_view(), p);
    if !l.ok {
        return;
    }
    let c = color_at(l.at);
    out_color[i] = c;
    if c.a >= w.depth_threshold {
        out_depth[i] = depth_at(seen_to, p, t);
    }
}

fn safe(x: f32) -> f32 {
    if abs(x) < 1e-20 {
        return select(-1e-20, 1e-20, x >= 0.0);
    }
    return x;
}

// Premultiplied color and opacity of the stretch [lo, hi] of source
// pixel `px`'s ray, for a target step `c` times longer: each overlapping
// layer absorbs and emits over its share, front to back, exactly; a
// surface's layer counts whole where the ray crossed it since `crossed`,
// an opaque one also within a stretch's length before (through_layers).
fn through(px: vec2f, crossed: f32, lo: f32, hi: f32, c: f32) -> vec4f {
    if any(px < vec2f(0.0)) || any(px >= vec2f(w.from_size)) {
        return vec4f(0.0);
    }
    let base = (u32(px.y) * w.from_size.x + u32(px.x)) * w.layers;
    var s = vec4f(0.0);
    for (var k = 0u; k < w.layers; k++) {
        let span = layers[2u * (base + k) + 1u];
        let col = layers[2u * (base + k)];
        var alpha: f32;
        var emitted: vec3f;
        if span.z != 0.0 {
            let a = min(col.a, 1.0);
            var since = crossed;
            if a >= SOLID {
                since = min(crossed, 2.0 * lo - hi);
            }
            let met = span.y <= hi && span.y > since;
            if !met || a <= 0.0 {
                continue;
            }
            alpha = a;
            emitted = col.rgb / a;
        } else {
            let overlap = (min(span.y, hi) - max(span.x, lo)) / c;
            if !(overlap > 0.0) {
                continue;
            }
            let len = span.y - span.x;
            let a = min(col.a, 0.999999);
            if a <= 0.0 || len <= 0.0 {
                continue;
            }
            let sigma = -log(1.0 - a) / len;
            alpha = 1.0 - exp(-sigma * overlap);
            emitted = col.rgb / a;
        }
        let weight = (1.0 - s.a) * alpha;
        s = vec4f(s.rgb + emitted * weight, s.a + weight);
    }
    return s;
}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn layer_march(@builtin(global_invocation_id) id: vec3u) {
    let i = begin_pixel(id);
    if i < 0 {
        return;
    }
    let seen_to = target_view();
    let seen_from = source_view();
    let r = pixel_ray(seen_to, f32(id.x), f32(id.y));
    let inv = 1.0 / vec3f(safe(r.d.x), safe(r.d.y), safe(r.d.z));
    let ta = (w.lo.xyz - r.o) * inv;
    let tb = (w.hi.xyz - r.o) * inv;
    let lo = min(ta, tb);
    let hi = max(ta, tb);
    let t0 = max(max(max(lo.x, lo.y), lo.z), w.near);
    let t1 = min(min(min(hi.x, hi.y), hi.z), w.far);
    if !(t1 > t0) {
        return;
    }
    let step = (t1 - t0) / f32(w.steps);
    var acc = vec4f(0.0);
    var first = infinity();
    // Where the previous step's stretch ended (march's `since`).
    var since = infinity();
    for (var s = 0u; s < w.steps; s++) {
        let t = t0 + (f32(s) + 0.5) * step;
        let p = r.o + r.d * t;
        let l = locate(seen_from, p);
        if !l.ok {
            continue;
        }
        // The stretch of the source ray this step covers, through the four
        // source pixels around the point, blended bilinearly.
        let c = max(abs(dot(r.d, l.direction)), 1e-3);
        let lo_along = l.along - 0.5 * step * c;
        let hi_along = l.along + 0.5 * step * c;
        let crossed = min(since, lo_along);
        since = hi_along;
        let q = l.at - vec2f(0.5);
        let base = floor(q);
        let f = q - base;
        let bottom = mix(through(base, crossed, lo_along, hi_along, c), through(base + vec2f(1.0, 0.0), crossed, lo_along, hi_along, c), f.x);
        let top = mix(through(base + vec2f(0.0, 1.0), crossed, lo_along, hi_along, c), through(base + vec2f(1.0, 1.0), crossed, lo_along, hi_along, c), f.x);
        let st = mix(bottom, top, f.y);
        if st.a <= 0.0 {
            continue;
        }
        acc = acc + (1.0 - acc.a) * st;
        if first == infinity() && acc.a >= w.depth_threshold {
            first = depth_at(seen_to, p, t);
        }
        if acc.a >= 0.99 {
            break;
        }
    }
    out_color[i] = acc;
    out_depth[i] = first;
}

// One mesh vertex a node: the source pixel every `spacing` pixels (the
// last row and column clamped), raised to its first-hit depth or, where
// nothing was hit, to the quad's plane, and projected into the target.
@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn grid_nodes(@builtin(global_invocation_id) id: vec3u) {
    if id.x >= w.nodes.x || id.y >= w.nodes.y {
        return;
    }
    let k = id.y * w.nodes.x + id.x;
    mesh[k] = vec4f(0.0);
    let x = min(id.x * w.spacing, w.from_size.x - 1u);
    let y = min(id.y * w.spacing, w.from_size.y - 1u);
    let seen_from = source_view();
    let r = pixel_ray(seen_from, f32(x), f32(y));
    let d = depth[y * w.from_size.x + x];
    var p: vec3f;
    if d < infinity() {
        p = select(r.o, seen_from.eye.xyz, seen_from.eye.w != 0.0) + r.d * d;
    } else {
        let n = w.normal.xyz;
        let facing = dot(r.d, n);
        if abs(facing) <= 1.1920929e-7 {
            return;
        }
        let t = dot(w.focus.xyz - r.o, n) / facing;
        if !(t > 0.0) {
            return;
        }
        p = r.o + r.d * t;
    }
    let l = locate(target_view(), p);
    if l.ok {
        mesh[k] = vec4f(l.at, l.along, 1.0);
    }
}

fn node_from(i: u32, j: u32) -> vec2f {
    let x = min(i * w.spacing, w.from_size.x - 1u);
    let y = min(j * w.spacing, w.from_size.y - 1u);
    return vec2f(f32(x) + 0.5, f32(y) + 0.5);
}

fn edge(a: vec2f, b: vec2f, p: vec2f) -> f32 {
    let e = b - a;
    let q = p - a;
    return e.x * q.y - e.y * q.x;
}

// Triangle `tri` of the mesh (two a grid cell), rasterised at the target's
// pixel centres: the depth pass keeps each pixel's nearest distance, the
// pick pass gives the pixel the source position of the triangle that won.
fn raster(tri: u32, pick: bool) {
    let cols = w.nodes.x - 1u;
    if tri >= 2u * cols * (w.nodes.y - 1u) {
        return;
    }
    let q = tri / 2u;
    let i = q % cols;
    let j = q / cols;
    var idx = array<vec2u, 3>(vec2u(i, j), vec2u(i + 1u, j), vec2u(i + 1u, j + 1u));
    if tri % 2u == 1u {
        idx = array<vec2u, 3>(vec2u(i, j), vec2u(i + 1u, j + 1u), vec2u(i, j + 1u));
    }
    var v: array<vec4f, 3>;
    for (var k = 0u; k < 3u; k++) {
        v[k] = mesh[idx[k].y * w.nodes.x + idx[k].x];
        if v[k].w == 0.0 {
            return;
        }
    }
    let area = edge(v[0].xy, v[1].xy, v[2].xy);
    if abs(area) < 1e-12 || !(abs(area) < 1e30) {
        return;
    }
    let lo = min(min(v[0].xy, v[1].xy), v[2].xy);
    let hi = max(max(v[0].xy, v[1].xy), v[2].xy);
    let first = max(ceil(lo - vec2f(0.5)), vec2f(0.0));
    let last = min(floor(hi - vec2f(0.5)), vec2f(w.to_size) - vec2f(1.0));
    if first.x > last.x || first.y > last.y {
        return;
    }
    for (var y = u32(first.y); y <= u32(last.y); y++) {
        for (var x = u32(first.x); x <= u32(last.x); x++) {
            let p = vec2f(f32(x) + 0.5, f32(y) + 0.5);
            let b = vec3f(edge(v[1].xy, v[2].xy, p), edge(v[2].xy, v[0].xy, p), edge(v[0].xy, v[1].xy, p)) / area;
            if min(min(b.x, b.y), b.z) < -1e-6 {
                continue;
            }
            let z = b.x * v[0].z + b.y * v[1].z + b.z * v[2].z;
            if !(z > 0.0) {
                continue;
            }
            let k = y * w.to_size.x + x;
            let key = ~bitcast<u32>(z);
            if !pick {
                atomicMax(&nearest[k], key);
            } else if atomicLoad(&nearest[k]) == key {
                from_at[k] = b.x * node_from(idx[0].x, idx[0].y) + b.y * node_from(idx[1].x, idx[1].y)
                    + b.z * node_from(idx[2].x, idx[2].y);
            }
        }
    }
}

@compute @workgroup_size(64)
fn grid_depth(@builtin(global_invocation_id) id: vec3u) {
    raster(id.x, false);
}

@compute @workgroup_size(64)
fn grid_pick(@builtin(global_invocation_id) id: vec3u) {
    raster(id.x, true);
}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn grid_color(@builtin(global_invocation_id) id: vec3u) {
    let i = begin_pixel(id);
    if i < 0 {
        return;
    }
    let key = atomicLoad(&nearest[i]);
    if key == 0u {
        return;
    }
    let c = color_at(from_at[i]);
    out_color[i] = c;
    if c.a >= w.depth_threshold {
        let z = bitcast<f32>(~key);
        let seen_to = target_view();
        let r = pixel_ray(seen_to, f32(id.x), f32(id.y));
        out_depth[i] = depth_at(seen_to, r.o + r.d * z, z);
    }
}
