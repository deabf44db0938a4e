// #import iso, iso_constants, iso_panel_bindings
// A multi-view panel's image, every subpixel from its own view
// (src/render/iso/multiview.rs): one ray a subpixel, or the geometric
// pass (each pixel's green ray) then the spectral one, which finds red's
// and blue's own hits or shades green's.

fn view_ray(v: u32, fx: f32, fy: f32) -> Ray {
    let r = 7u * v;
    let o = view_rays[r].xyz + fx * view_rays[r + 1u].xyz + fy * view_rays[r + 2u].xyz;
    let d = normalize(view_rays[r + 3u].xyz + fx * view_rays[r + 4u].xyz + fy * view_rays[r + 5u].xyz);
    return Ray(o, d, view_rays[r + 6u]);
}

struct Ray {
    o: vec3f,
    d: vec3f,
    eye: vec4f,
}

fn view_of(packed: u32, c: u32) -> u32 {
    return (packed >> (8u * c)) & 0xffu;
}

// The geometric pass: each pixel's green ray in full.
@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn geometric(@builtin(workgroup_id) group: vec3u, @builtin(local_invocation_id) local: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let id = vec3u(band_pixel(group, local, groups), 0u);
    if id.x >= iso.width || id.y >= iso.height {
        return;
    }
    let i = id.y * iso.width + id.x;
    let r = view_ray(view_of(pixel_views[i], 1u), f32(id.x), f32(id.y));
    green_t[i] = cast_ray(r.o, r.d, r.eye).t;
}

// Red and blue shade green's hit, each seen along its own view's ray,
// instead of finding their own: one view's march, and the colour of a
// point the channel's eye does not see there (MultiViewMethod::GreenGeometry).
override GREEN_GEOMETRY: bool = false;

// The spectral pass (src/render/iso/multiview.rs): green from its t, red
// and blue searched from where their own views' samples in the geometric
// pass met the surface (search_window), or shading green's hit.
@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn spectral(@builtin(workgroup_id) group: vec3u, @builtin(local_invocation_id) local: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let id = vec3u(band_pixel(group, local, groups), 0u);
    if id.x >= iso.width || id.y >= iso.height {
        return;
    }
    let i = id.y * iso.width + id.x;
    let fx = f32(id.x);
    let fy = f32(id.y);
    let packed = pixel_views[i];
    let tg = green_t[i];
    if GREEN_GEOMETRY {
        shade_green_hit(i, fx, fy, packed, tg);
        return;
    }
    let margin = SEARCH_MARGIN_STEPS * iso.step;
    // Green's hit, shaded once: any channel of green's view sees it so.
    let vg = view_of(packed, 1u);
    let rg = view_ray(vg, fx, fy);
    var green = missed();
    if tg >= 0.0 {
        green = hit_at(rg.o, rg.d, rg.eye, span(rg.o, rg.d), tg);
    }
    depth_out[i] = green.depth;
    var rgb = green.color.rgb;
    for (var c = 0u; c < 3u; c += 2u) {
        let v = view_of(packed, c);
        if v == vg {
            continue;
        }
        let r = view_ray(v, fx, fy);
        var hit = missed();
        let w = search_window(id.x, id.y, v, tg, margin);
        if w.y >= w.x {
            hit = cast_window(r.o, r.d, r.eye, w.x, w.y);
        }
        rgb[c] = hit.color[c];
    }
    store_color(i, vec4f(rgb, 1.0), iso.color_format);
}

// Pixel i's three channels from green's hit (none: the background), each
// shaded as its own view's ray sees it.
fn shade_green_hit(i: u32, fx: f32, fy: f32, packed: u32, tg: f32) {
    let rg = view_ray(view_of(packed, 1u), fx, fy);
    if tg < 0.0 {
        depth_out[i] = missed().depth;
        store_color(i, vec4f(missed().color.rgb, 1.0), iso.color_format);
        return;
    }
    let sp = span(rg.o, rg.d);
    let p = rg.o + rg.d * tg;
    depth_out[i] = select(tg, length(p - rg.eye.xyz), rg.eye.w != 0.0);
    // As hit_at shades it, with the derivatives taken once for all three.
    let surface = surface_at(sp.go + sp.gd * tg, rg.d, grid_to_world());
    var rgb = shade_surface(surface, rg.d).rgb;
    for (var c = 0u; c < 3u; c += 2u) {
        let r = view_ray(view_of(packed, c), fx, fy);
        rgb[c] = shade_surface(surface, r.d)[c];
    }
    store_color(i, vec4f(rgb, 1.0), iso.color_format);
}

// What the geometric pass saw of view `v` near pixel (x, y): green's t at
// the SAME_VIEW_SAMPLES nearest pixels whose green has view v, looked for
// in SAME_VIEW_OFFSETS' order (SameView in src/render/iso/multiview.rs).
struct SameView {
    seen: bool,
    // The nearest and farthest hit among them; negative: none.
    lo: f32,
    hi: f32,
}

fn same_view(x: u32, y: u32, v: u32) -> SameView {
    var near = SameView(false, -1.0, -1.0);
    var found = 0u;
    for (var k = 0u; k < SAME_VIEW_OFFSET_COUNT && found < SAME_VIEW_SAMPLES; k++) {
        let p = vec2i(i32(x), i32(y)) + SAME_VIEW_OFFSETS[k];
        if p.x < 0 || p.y < 0 || p.x >= i32(iso.width) || p.y >= i32(iso.height) {
            continue;
        }
        let j = u32(p.y) * iso.width + u32(p.x);
        if view_of(pixel_views[j], 1u) != v {
            continue;
        }
        near.seen = true;
        found++;
        let t = green_t[j];
        if t >= 0.0 {
            if near.lo < 0.0 {
                near.lo = t;
                near.hi = t;
            } else {
                near.lo = min(near.lo, t);
                near.hi = max(near.hi, t);
            }
        }
    }
    return near;
}

// Where a channel of view `v` searches its ray at pixel (x, y) (x: from,
// y: until; from > until: nowhere), as SameView::window and
// fallback_window choose on the CPU. `tg`: green's t there (negative:
// missed).
fn search_window(x: u32, y: u32, v: u32, tg: f32, margin: f32) -> vec2f {
    let inf = bitcast<f32>(0x7f800000u);
    let nowhere = vec2f(1.0, 0.0);
    let near = same_view(x, y, v);
    if near.seen {
        if near.lo >= 0.0 {
            if tg >= 0.0 {
                return vec2f(near.lo - margin, inf);
            }
            return vec2f(near.lo - margin, near.hi + 3.0 * margin);
        }
        if tg >= 0.0 {
            return vec2f(tg - margin, tg + 3.0 * margin);
        }
        return nowhere;
    }
    if tg >= 0.0 {
        return vec2f(tg - margin, inf);
    }
    var nearest = inf;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let xx = i32(x) + dx;
            let yy = i32(y) + dy;
            if xx >= 0 && yy >= 0 && xx < i32(iso.width) && yy < i32(iso.height) {
                let t = green_t[u32(yy) * iso.width + u32(xx)];
                if t >= 0.0 {
                    nearest = min(nearest, t);
                }
            }
        }
    }
    if nearest < inf {
        return vec2f(nearest - margin, nearest + 3.0 * margin);
    }
    return nowhere;
}

// One ray a subpixel, from that subpixel's view; depth is green's.
@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn per_subpixel(@builtin(workgroup_id) group: vec3u, @builtin(local_invocation_id) local: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let id = vec3u(band_pixel(group, local, groups), 0u);
    if id.x >= iso.width || id.y >= iso.height {
        return;
    }
    let i = id.y * iso.width + id.x;
    let fx = f32(id.x);
    let fy = f32(id.y);
    let packed = pixel_views[i];
    var rgb = vec3f(0.0);
    for (var c = 0u; c < 3u; c++) {
        let r = view_ray(view_of(packed, c), fx, fy);
        let hit = cast_ray(r.o, r.d, r.eye);
        rgb[c] = hit.color[c];
        if c == 1u {
            depth_out[i] = hit.depth;
        }
    }
    store_color(i, vec4f(rgb, 1.0), iso.color_format);
}
