// #import constants, color, iso_bindings, band
// Isosurface ray casting, the port of src/render/iso/ (its reference):
// fixed steps to the first crossing of the iso-value, secant steps within
// it, the trilinear field (with central differences) or the cubic
// B-spline (the march's values from 8 trilinear fetches, the hit's
// gradient and Hessian from the 4x4x4 weights), Blinn-Phong, flat or by
// mean curvature. Multi-view panels are iso_panel.wgsl's.

fn voxel(i: vec3i) -> f32 {
    let hi = vec3i(iso.dims.xyz) - vec3i(1);
    return textureLoad(volume, clamp(i, vec3i(0), hi), 0).r * iso.texel_scale + iso.texel_offset;
}

fn last_vertex() -> vec3f {
    return vec3f(iso.dims.xyz - vec3u(1u));
}

fn trilinear(p: vec3f) -> f32 {
    let g = clamp(p, vec3f(0.0), last_vertex());
    let i0 = floor(g);
    let f = g - i0;
    let i = vec3i(i0);
    let x00 = mix(voxel(i), voxel(i + vec3i(1, 0, 0)), f.x);
    let x10 = mix(voxel(i + vec3i(0, 1, 0)), voxel(i + vec3i(1, 1, 0)), f.x);
    let x01 = mix(voxel(i + vec3i(0, 0, 1)), voxel(i + vec3i(1, 0, 1)), f.x);
    let x11 = mix(voxel(i + vec3i(0, 1, 1)), voxel(i + vec3i(1, 1, 1)), f.x);
    return mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z);
}

// The cubic B-spline's weights at fraction t (value, first, second
// derivative), as columns w0..w3.
fn weights(t: f32) -> mat4x3f {
    let s = 1.0 - t;
    let t2 = t * t;
    let t3 = t2 * t;
    return mat4x3f(
        vec3f(s * s * s / 6.0, -0.5 * s * s, s),
        vec3f((3.0 * t3 - 6.0 * t2 + 4.0) / 6.0, 1.5 * t2 - 2.0 * t, 3.0 * t - 2.0),
        vec3f((-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0, -1.5 * t2 + t + 0.5, -3.0 * t + 1.0),
        vec3f(t3 / 6.0, 0.5 * t2, t),
    );
}

// The B-spline's value from 8 trilinear fetches (Sigg and Hadwiger): per
// axis the four weights fold into two fetch positions and two weights.
fn bspline_value(p: vec3f) -> f32 {
    let g = clamp(p, vec3f(0.0), last_vertex());
    let i = floor(g);
    let f = g - i;
    var w0 = vec3f(0.0);
    var w1 = vec3f(0.0);
    var w2 = vec3f(0.0);
    var w3 = vec3f(0.0);
    for (var a = 0; a < 3; a++) {
        let w = weights(f[a]);
        w0[a] = w[0].x;
        w1[a] = w[1].x;
        w2[a] = w[2].x;
        w3[a] = w[3].x;
    }
    let g0 = w0 + w1;
    let g1 = w2 + w3;
    let h0 = i - 1.0 + w1 / g0;
    let h1 = i + 1.0 + w3 / g1;
    var v = 0.0;
    for (var c = 0u; c < 8u; c++) {
        let pick = vec3<bool>((c & 1u) != 0u, (c & 2u) != 0u, (c & 4u) != 0u);
        let at = select(h0, h1, pick);
        let wt = select(g0, g1, pick);
        v += wt.x * wt.y * wt.z * trilinear(at);
    }
    return v;
}

fn value(p: vec3f) -> f32 {
    if iso.filtering == 1u {
        return bspline_value(p);
    }
    return trilinear(p);
}

struct Derivatives {
    gradient: vec3f,
    hessian: mat3x3f,
}

fn trilinear_gradient(p: vec3f) -> vec3f {
    return 0.5 * vec3f(
        trilinear(p + vec3f(1.0, 0.0, 0.0)) - trilinear(p - vec3f(1.0, 0.0, 0.0)),
        trilinear(p + vec3f(0.0, 1.0, 0.0)) - trilinear(p - vec3f(0.0, 1.0, 0.0)),
        trilinear(p + vec3f(0.0, 0.0, 1.0)) - trilinear(p - vec3f(0.0, 0.0, 1.0)),
    );
}

// Grid-space gradient and Hessian at `p`.
fn derivatives(p: vec3f, with_hessian: bool) -> Derivatives {
    if iso.filtering == 0u {
        let grad = trilinear_gradient(p);
        if !with_hessian {
            return Derivatives(grad, mat3x3f());
        }
        let hx = 0.5 * (trilinear_gradient(p + vec3f(1.0, 0.0, 0.0)) - trilinear_gradient(p - vec3f(1.0, 0.0, 0.0)));
        let hy = 0.5 * (trilinear_gradient(p + vec3f(0.0, 1.0, 0.0)) - trilinear_gradient(p - vec3f(0.0, 1.0, 0.0)));
        let hz = 0.5 * (trilinear_gradient(p + vec3f(0.0, 0.0, 1.0)) - trilinear_gradient(p - vec3f(0.0, 0.0, 1.0)));
        let h = mat3x3f(hx, hy, hz);
        return Derivatives(grad, 0.5 * (h + transpose(h)));
    }
    let g = clamp(p, vec3f(0.0), last_vertex());
    let i0 = floor(g);
    let f = g - i0;
    let wx = weights(f.x);
    let wy = weights(f.y);
    let wz = weights(f.z);
    let base = vec3i(i0) - vec3i(1);
    var grad = vec3f(0.0);
    var hd = vec3f(0.0);
    var ho = vec3f(0.0);
    for (var c = 0; c < 4; c++) {
        for (var b = 0; b < 4; b++) {
            for (var a = 0; a < 4; a++) {
                let v = voxel(base + vec3i(a, b, c));
                let x = wx[a];
                let y = wy[b];
                let z = wz[c];
                grad += v * vec3f(x.y * y.x * z.x, x.x * y.y * z.x, x.x * y.x * z.y);
                hd += v * vec3f(x.z * y.x * z.x, x.x * y.z * z.x, x.x * y.x * z.z);
                ho += v * vec3f(x.y * y.y * z.x, x.y * y.x * z.y, x.x * y.y * z.y);
            }
        }
    }
    let h = mat3x3f(vec3f(hd.x, ho.x, ho.y), vec3f(ho.x, hd.y, ho.z), vec3f(ho.y, ho.z, hd.z));
    return Derivatives(grad, h);
}

// Principal curvatures (larger first) for the normal -g/|g| (see
// src/render/iso/field.rs).
fn curvatures(g: vec3f, h: mat3x3f) -> vec2f {
    let len = length(g);
    if len <= 1.17549435e-38 {
        return vec2f(0.0);
    }
    let n = -g / len;
    let p = mat3x3f(vec3f(1.0, 0.0, 0.0), vec3f(0.0, 1.0, 0.0), vec3f(0.0, 0.0, 1.0)) - mat3x3f(n * n.x, n * n.y, n * n.z);
    let gm = (p * h * p) * (-1.0 / len);
    let t = gm[0].x + gm[1].y + gm[2].z;
    let f2 = dot(gm[0], gm[0]) + dot(gm[1], gm[1]) + dot(gm[2], gm[2]);
    let root = sqrt(max(2.0 * f2 - t * t, 0.0));
    return vec2f((t + root) / 2.0, (t - root) / 2.0);
}

fn safe(x: f32) -> f32 {
    if abs(x) < 1e-20 {
        return select(-1e-20, 1e-20, x >= 0.0);
    }
    return x;
}

fn curvature_color(mean: f32) -> vec3f {
    let s = clamp(mean * iso.radius, -1.0, 1.0);
    let white = vec3f(0.95);
    if s >= 0.0 {
        return mix(white, vec3f(1.0, 0.45, 0.1), s);
    }
    return mix(white, vec3f(0.15, 0.35, 1.0), -s);
}

struct Cast {
    color: vec4f,
    depth: f32,
    // Along the unit ray; negative where nothing was hit.
    t: f32,
}

// A ray in grid space and its span through the grid.
struct Span {
    go: vec3f,
    gd: vec3f,
    t0: f32,
    t1: f32,
}

fn grid_to_world() -> mat3x3f {
    return mat3x3f(iso.to_grid_x.xyz, iso.to_grid_y.xyz, iso.to_grid_z.xyz);
}

fn span(o: vec3f, d: vec3f) -> Span {
    let m = transpose(grid_to_world());
    let go = m * o + vec3f(iso.to_grid_x.w, iso.to_grid_y.w, iso.to_grid_z.w);
    let gd = m * d;
    let inv = 1.0 / vec3f(safe(gd.x), safe(gd.y), safe(gd.z));
    let ta = (iso.box_lo.xyz - go) * inv;
    let tb = (iso.box_hi.xyz - go) * inv;
    let t0 = max(max(max(min(ta.x, tb.x), min(ta.y, tb.y)), min(ta.z, tb.z)), iso.near);
    let t1 = min(min(min(max(ta.x, tb.x), max(ta.y, tb.y)), max(ta.z, tb.z)), iso.far);
    return Span(go, gd, t0, t1);
}

fn missed() -> Cast {
    return Cast(iso.background, bitcast<f32>(0x7f800000u), -1.0);
}

// The surface at `t` along the ray, shaded.
fn hit_at(o: vec3f, d: vec3f, eye: vec4f, sp: Span, t: f32) -> Cast {
    let p = o + d * t;
    let depth = select(t, length(p - eye.xyz), eye.w != 0.0);
    return Cast(shade_hit(sp.go + sp.gd * t, d, grid_to_world()), depth, t);
}

// The first crossing along the ray's span from its march step `k0`, where
// the field minus the iso-value is `f0`, to its step `last` at most. Every
// march takes its steps from the span's start, so a search that starts
// later finds the whole march's crossing, to the bit.
fn march_span(o: vec3f, d: vec3f, eye: vec4f, sp: Span, k0: u32, f0: f32, last: u32) -> Cast {
    var a = sp.t0 + f32(k0) * iso.step;
    var fa = f0;
    let steps = min(u32(min(ceil((sp.t1 - sp.t0) / iso.step), 1e6)), last);
    for (var k = k0 + 1u; k <= steps; k++) {
        let b = min(sp.t0 + f32(k) * iso.step, sp.t1);
        let fb = value(sp.go + sp.gd * b) - iso.isovalue;
        if fa == 0.0 || (fa < 0.0) != (fb < 0.0) {
            return hit_at(o, d, eye, sp, refine(sp.go, sp.gd, a, fa, b, fb));
        }
        a = b;
        fa = fb;
    }
    return missed();
}

// Whole march steps from the span's start that fit in `length`.
fn steps_before(sp: Span, length: f32) -> u32 {
    return u32(clamp(floor(min(length, sp.t1 - sp.t0) / iso.step), 0.0, 1e6));
}

// One ray at the isosurface: its shaded color (or the background), depth
// from `eye` (w: 1 if it has one, else along the ray) and t.
fn cast_ray(o: vec3f, d: vec3f, eye: vec4f) -> Cast {
    let sp = span(o, d);
    if !(sp.t1 > sp.t0) {
        return missed();
    }
    let entry = value(sp.go + sp.gd * sp.t0) - iso.isovalue;
    return march_span(o, d, eye, sp, 0u, entry, 0xffffffffu);
}

// The first crossing in [start_t, until] (from the last march step at or
// before `start_t`), if the ray is on the same side of the iso-value there
// as where it enters the grid; else the whole ray (a crossing lies before).
fn cast_window(o: vec3f, d: vec3f, eye: vec4f, start_t: f32, until: f32) -> Cast {
    let sp = span(o, d);
    if !(sp.t1 > sp.t0) {
        return missed();
    }
    let k0 = steps_before(sp, start_t - sp.t0);
    let entry = value(sp.go + sp.gd * sp.t0) - iso.isovalue;
    var there = entry;
    if k0 > 0u {
        there = value(sp.go + sp.gd * (sp.t0 + f32(k0) * iso.step)) - iso.isovalue;
    }
    if (entry < 0.0) != (there < 0.0) {
        return march_span(o, d, eye, sp, 0u, entry, 0xffffffffu);
    }
    return march_span(o, d, eye, sp, k0, there, steps_before(sp, until - sp.t0) + 1u);
}

// Secant (regula falsi) steps within [a, b], whose ends differ in sign.
fn refine(go: vec3f, gd: vec3f, a: f32, fa: f32, b: f32, fb: f32) -> f32 {
    if fa == 0.0 {
        return a;
    }
    if iso.secant_steps == 0u {
        return b;
    }
    var ta = a;
    var va = fa;
    var tb = b;
    var vb = fb;
    for (var s = 0u; s < iso.secant_steps; s++) {
        var ts = 0.5 * (ta + tb);
        if vb != va {
            ts = ta - va * (tb - ta) / (vb - va);
        }
        let vs = value(go + gd * ts) - iso.isovalue;
        if vs == 0.0 {
            return ts;
        }
        if (vs < 0.0) == (va < 0.0) {
            ta = ts;
            va = vs;
        } else {
            tb = ts;
            vb = vs;
        }
    }
    if vb != va {
        return ta - va * (tb - ta) / (vb - va);
    }
    return 0.5 * (ta + tb);
}

// The surface at a hit: its unit normal, facing the ray it was found
// along, and its principal curvatures as that ray sees them.
struct Surface {
    n: vec3f,
    k: vec2f,
}

// The surface at grid point `g` found along `d`; `mt` is the transpose of
// the world-to-grid map's linear part.
fn surface_at(g: vec3f, d: vec3f, mt: mat3x3f) -> Surface {
    let hessian = iso.filtering == 1u || iso.curvature == 1u;
    let dv = derivatives(g, hessian);
    let grad = mt * dv.gradient;
    let hess = mt * dv.hessian * transpose(mt);
    var k = vec2f(0.0);
    if hessian {
        k = curvatures(grad, hess);
    }
    var n = -grad / max(length(grad), 1.17549435e-38);
    if dot(n, d) > 0.0 {
        n = -n;
        k = vec2f(-k.y, -k.x);
    }
    return Surface(n, k);
}

// Blinn-Phong on surface `s` seen along `d`.
fn shade_surface(s: Surface, d: vec3f) -> vec4f {
    var base = iso.color.rgb;
    if iso.curvature == 1u {
        base = curvature_color(0.5 * (s.k.x + s.k.y));
    }
    var l = -d;
    if iso.light.w != 0.0 {
        l = normalize(iso.light.xyz);
    }
    let half = l - d;
    var h = vec3f(0.0);
    if length(half) > 0.0 {
        h = normalize(half);
    }
    let diffuse = max(dot(s.n, l), 0.0);
    let specular = pow(max(dot(s.n, h), 0.0), iso.shading.w);
    let rgb = base * (iso.shading.x + iso.shading.y * diffuse) + vec3f(iso.shading.z * specular);
    return vec4f(min(rgb, vec3f(1.0)), 1.0);
}

// Blinn-Phong at grid point `g` seen along `d`.
fn shade_hit(g: vec3f, d: vec3f, mt: mat3x3f) -> vec4f {
    return shade_surface(surface_at(g, d, mt), d);
}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(workgroup_id) group: vec3u, @builtin(local_invocation_id) local: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let id = vec3u(band_pixel(group, local, groups), 0u);
    if id.x >= iso.width || id.y >= iso.height {
        return;
    }
    let i = id.y * iso.width + id.x;
    let fx = f32(id.x);
    let fy = f32(id.y);
    let o = iso.ray_origin.xyz + fx * iso.ray_origin_dx.xyz + fy * iso.ray_origin_dy.xyz;
    let d = normalize(iso.ray_dir.xyz + fx * iso.ray_dir_dx.xyz + fy * iso.ray_dir_dy.xyz);
    let c = cast_ray(o, d, iso.eye);
    depth_out[i] = c.depth;
    store_color(i, c.color, iso.color_format);
}
