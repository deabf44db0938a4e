// #import volume, surface, color, stereo, composite_bindings
// The right eye from the re-projection layers: per right pixel, the left
// rays on its epipolar line whose segments crossed it, nearest first, each
// blended from the two rays the line passes between. Surfaces are the
// right eye's own: its ray traces them as raycast.wgsl does, and each
// takes its place among the segments by its distance (a surface seen at a
// slant would leave cracks between the points the left eye's rays hit).

// Left pixels are summarised in blocks of BLOCK x BLOCK (one workgroup of
// the march): the right coordinates any of their rays wrote, per family.
// A right pixel steps along its line a block at a time and reads rays only
// in blocks that wrote its coordinate; elsewhere (the bounding range's
// empty depths) it reads nothing.
const BLOCK: i32 = i32(WORKGROUP);

// Reads every offset of the bounding range, as if every block had
// written: what the summary spares, kept to measure and check it.
override EVERY_OFFSET: bool = false;

fn block_of(p: vec2i) -> vec2i {
    let c = p - stereo.first;
    // Floor division: cast pixels start at 0, but a line runs past them.
    return vec2i(floor(vec2f(c) / f32(BLOCK)));
}

fn blocks_across() -> u32 {
    return (stereo.cast_pixels.x + u32(BLOCK) - 1u) / u32(BLOCK);
}

fn block_count() -> vec2i {
    return vec2i(vec2u(blocks_across(), (stereo.cast_pixels.y + u32(BLOCK) - 1u) / u32(BLOCK)));
}

// The union of the spans of block b's rays.
@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn summarise(@builtin(global_invocation_id) id: vec3u) {
    let b = vec2i(id.xy);
    if any(b >= block_count()) {
        return;
    }
    var all_spans = vec4i(1, 0, 1, 0);
    let start = b * BLOCK;
    let end = min(start + BLOCK, vec2i(stereo.cast_pixels));
    for (var y = start.y; y < end.y; y++) {
        for (var x = start.x; x < end.x; x++) {
            let span = spans[u32(y) * stereo.cast_pixels.x + u32(x)];
            if span.x <= span.y {
                all_spans = select(vec4i(min(all_spans.x, span.x), max(all_spans.y, span.y), all_spans.zw), vec4i(span.xy, all_spans.zw), all_spans.x > all_spans.y);
            }
            if span.z <= span.w {
                all_spans = select(vec4i(all_spans.xy, min(all_spans.z, span.z), max(all_spans.w, span.w)), vec4i(all_spans.xy, span.zw), all_spans.z > all_spans.w);
            }
        }
    }
    blocks[u32(b.y) * blocks_across() + u32(b.x)] = all_spans;
}

// Whether a ray of block b all_spans right coordinate `at` of family `axis`.
fn block_wrote(b: vec2i, at: i32, axis: u32) -> bool {
    if any(b < vec2i(0)) || any(b >= block_count()) {
        return false;
    }
    let all_spans = blocks[u32(b.y) * blocks_across() + u32(b.x)];
    let lo = select(all_spans.x, all_spans.z, axis == 1u);
    let hi = select(all_spans.y, all_spans.w, axis == 1u);
    return at >= lo && at <= hi;
}

// The march's hooks (volume.wgsl): nothing is marched here.
fn on_sample(p: vec3f, t: f32, lit: vec3f, a: f32) {}
fn surface_pass(p: vec3f, d: vec3f, reach: f32) -> f32 {
    return 1.0;
}

// The right pixel's ray and the next surface along it, with its distance
// from the right eye (infinite where none is left).
var<private> right_ray: Ray;
// How far along it the right eye can see: to its first opaque surface,
// where first_opaque found one.
var<private> right_reach: f32;
var<private> next: SurfaceHit;
var<private> next_distance: f32;
var<private> looked: u32;
var<private> translucent: u32;
// What an opaque surface leaves behind the pixel's color.
var<private> behind: vec4f;
// Set once an opaque surface or the pixel's opacity ends it.
var<private> ended: bool;
// Set where the right eye's only surface is the opaque one first_opaque
// found, lit `known_color`: no traversal again.
var<private> known: bool;
var<private> known_color: vec3f;

fn find_next(t_min: f32) {
    next = SurfaceHit(infinite(), NO_SLOT, vec2f(0.0));
    if SURFACES && looked < SURFACE_PASSES {
        next = nearest_surface(right_ray.o, right_ray.d, t_min, right_reach);
        looked++;
    }
    next_distance = infinite();
    if next.slot != NO_SLOT {
        next_distance = length(right_ray.o + right_ray.d * next.t - stereo.right_eye);
    }
}

fn right_ray_of(q: vec2i) -> Ray {
    return ray_through(
        f32(q.x), f32(q.y),
        stereo.right_origin.xyz, stereo.right_origin_dx.xyz, stereo.right_origin_dy.xyz,
        stereo.right_dir.xyz, stereo.right_dir_dx.xyz, stereo.right_dir_dy.xyz,
    );
}

// Per right pixel, the distance from the right eye to its first opaque
// surface (infinite where none), translucent ones passed: before the
// march, so that its rays march on behind the left eye's surfaces only
// where the right eye sees further (reproject.wgsl).
@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn first_opaque(@builtin(global_invocation_id) id: vec3u) {
    if id.x >= stereo.width || id.y >= stereo.height {
        return;
    }
    right_ray = right_ray_of(vec2i(id.xy));
    right_reach = stereo.right_t_far;
    looked = 0u;
    var found = vec4f(0.0, 0.0, 0.0, infinite());
    var passed = false;
    find_next(stereo.right_t_near);
    while next.slot != NO_SLOT {
        if surface_alpha(next) >= 1.0 {
            found = vec4f(surface_color(next, right_ray.o, right_ray.d), next_distance);
            break;
        }
        passed = true;
        find_next(next.t);
    }
    if passed {
        found.w = -found.w;
    }
    right_opaque[id.y * stereo.width + id.x] = found;
}

// The next surface behind `acc`, as raycast.wgsl's loop takes it: an
// opaque one ends the pixel, translucent ones past MAX_TRANSLUCENT pass.
fn take_surface(acc: ptr<function, vec4f>, depth: ptr<function, f32>) {
    if known {
        behind = vec4f(known_color, 1.0);
        *depth = min(*depth, next_distance);
        ended = true;
        return;
    }
    let lit = surface_color(next, right_ray.o, right_ray.d);
    let a = surface_alpha(next);
    if a >= 1.0 {
        behind = vec4f(lit, 1.0);
        *depth = min(*depth, next_distance);
        ended = true;
        return;
    }
    if translucent < MAX_TRANSLUCENT {
        let weight = (1.0 - (*acc).a) * a;
        *acc = vec4f((*acc).rgb + lit * weight, (*acc).a + weight);
        if *depth == infinite() && (*acc).a >= stereo.depth_threshold {
            *depth = next_distance;
        }
        translucent++;
        if (*acc).a >= stereo.termination {
            ended = true;
            return;
        }
    }
    find_next(next.t);
}

// Segment s (premultiplied) behind `acc`; d: its right-eye distances
// (first sample, last, where its own opacity crosses the depth threshold).
fn take_segment(acc: ptr<function, vec4f>, depth: ptr<function, f32>, s: vec4f, d: vec3f) {
    let before = (*acc).a;
    *acc = *acc + (1.0 - before) * s;
    if stereo.has_depth != 0u && *depth == infinite() && (*acc).a >= stereo.depth_threshold {
        // A segment that alone crosses the threshold (often the whole
        // ray, near the epipole) knows where; else the crossing is placed
        // between its first and last sample by the opacity it still
        // needed.
        let needed = (stereo.depth_threshold - before) / (1.0 - before);
        *depth = mix(d.x, d.y, clamp(needed / max(s.a, 1e-6), 0.0, 1.0));
        if before == 0.0 && d.z < 3.0e38 {
            *depth = d.z;
        }
    }
    if (*acc).a >= stereo.termination {
        ended = true;
    }
}

// The share f of segment s's stretch: the same absorption per length.
fn part_of(s: vec4f, f: f32) -> vec4f {
    if s.a <= 0.0 {
        return s * f;
    }
    let a = 1.0 - pow(max(1.0 - s.a, 0.0), f);
    return s * (a / s.a);
}

// Segment s with distances d behind `acc`, the surfaces in front of its
// end taken first, a segment that a surface cuts taken in two.
fn take_segment_among_surfaces(acc: ptr<function, vec4f>, depth: ptr<function, f32>, s: vec4f, d: vec3f) {
    if !SURFACES {
        take_segment(acc, depth, s, d);
        return;
    }
    var rest = s;
    var first = d.x;
    var crossed = d.z;
    while !ended && next_distance < d.y {
        if next_distance > first && d.y > first {
            let f = (next_distance - first) / (d.y - first);
            take_segment(acc, depth, part_of(rest, f), vec3f(first, next_distance, select(infinite(), crossed, crossed < next_distance)));
            rest = part_of(rest, 1.0 - f);
            first = next_distance;
            crossed = select(infinite(), crossed, crossed >= next_distance);
        }
        if !ended {
            take_surface(acc, depth);
        }
    }
    if !ended {
        take_segment(acc, depth, rest, vec3f(first, d.y, crossed));
    }
}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3u) {
    if id.x >= stereo.width || id.y >= stereo.height {
        return;
    }
    let q = vec2i(id.xy);
    let g = g_of(q);
    let axis = select(0u, 1u, abs(g.y) > abs(g.x));
    let major = alongf(g, axis);
    // The line's slope across the axis; 0 at the epipole itself.
    let slope = select(acrossf(g, axis) / major, 0.0, major == 0.0);
    let w = stereo.epipole.z;
    // The left rays read sit `offset` pixels before q along the axis:
    // from the nearest depth's to the farthest's, one past each end.
    let near = i32(round(stereo.lambda_near * major / (1.0 + stereo.lambda_near * w)));
    let far = i32(round(stereo.lambda_far * major / (1.0 + stereo.lambda_far * w)));
    let dir = select(-1, 1, far >= near);
    let count = abs(far - near) + 3;
    let at = along(q, axis);
    let own_across = f32(select(q.y, q.x, axis == 1u));
    let first_along = along(stereo.first, axis);
    var acc = vec4f(0.0);
    var depth = infinite();
    right_ray = right_ray_of(q);
    right_reach = stereo.right_t_far;
    looked = 0u;
    translucent = 0u;
    behind = stereo.background;
    ended = false;
    known = false;
    if SURFACES {
        let opaque = right_opaque[id.y * stereo.width + id.x];
        if params.surface_nodes != 0u && opaque.w >= 0.0 {
            // first_opaque saw all there is: one opaque surface or none.
            known = opaque.w < infinite();
            known_color = opaque.xyz;
            next = SurfaceHit(infinite(), select(NO_SLOT, 0u, known), vec2f(0.0));
            next_distance = opaque.w;
        } else {
            // Translucent surfaces first: the traversal need look no
            // further than the opaque one (a little past it, for
            // rounding); distances run from the eye, t from the ray's
            // origin.
            if params.surface_nodes != 0u && -opaque.w < infinite() {
                let from_eye = length(right_ray.o - stereo.right_eye);
                right_reach = min(right_reach, (-opaque.w - from_eye) * (1.0 + 1e-4) + 1e-6);
            }
            find_next(stereo.right_t_near);
        }
    }
    var k = 0;
    while k < count && !ended {
        // The offsets up to where the rays read leave their block along
        // the axis, and every block the line passes between meanwhile.
        let along_left = at - (near + (k - 1) * dir);
        let in_block = ((along_left - first_along) % BLOCK + BLOCK) % BLOCK;
        let chunk = min(select(BLOCK - in_block, in_block + 1, dir > 0), count - k);
        let across_first = own_across - f32(near + (k - 1) * dir) * slope;
        let across_last = own_across - f32(near + (k + chunk - 2) * dir) * slope;
        let lowest = i32(floor(min(across_first, across_last)));
        let highest = i32(floor(max(across_first, across_last))) + 1;
        let first_block = block_of(select(vec2i(along_left, lowest), vec2i(lowest, along_left), axis == 1u));
        let last_block = block_of(select(vec2i(along_left, highest), vec2i(highest, along_left), axis == 1u));
        let step = select(vec2i(0, 1), vec2i(1, 0), axis == 1u);
        var wrote = false;
        for (var b = first_block; all(b <= last_block) && !wrote; b += step) {
            wrote = block_wrote(b, at, axis);
        }
        if !wrote && !EVERY_OFFSET {
            k += chunk;
            continue;
        }
        for (var i = k; i < k + chunk; i++) {
            let offset = near + (i - 1) * dir;
            // The line crosses between two left rays: blend them by where.
            let across = own_across - f32(offset) * slope;
            let below = floor(across);
            let f = across - below;
            var segment = vec4f(0.0);
            var weight = 0.0;
            var d = vec3f(0.0);
            for (var j = 0; j < 2; j++) {
                let share = select(1.0 - f, f, j == 1);
                if share == 0.0 {
                    continue;
                }
                let c = i32(below) + j;
                let p = select(vec2i(q.x - offset, c), vec2i(c, q.y - offset), axis == 1u);
                if !is_cast(p) {
                    continue;
                }
                let span = spans[span_index(p)];
                let lo = select(span.x, span.z, axis == 1u);
                let hi = select(span.y, span.w, axis == 1u);
                if at < lo || at > hi {
                    continue;
                }
                let texel = texel_of(p, at, axis);
                let layer = layer_of(p, axis);
                segment += share * textureLoad(layers, texel, layer, 0);
                if stereo.segment_depths != 0u && share >= weight {
                    d = textureLoad(depths, texel, layer, 0).xyz;
                }
                weight += share;
            }
            if weight == 0.0 {
                continue;
            }
            segment /= weight;
            take_segment_among_surfaces(&acc, &depth, segment, d);
            if ended {
                break;
            }
        }
        k += chunk;
    }
    while SURFACES && !ended && next.slot != NO_SLOT {
        take_surface(&acc, &depth);
    }
    let i = id.y * stereo.width + id.x;
    let words = encoded(over(acc, behind), stereo.color_format);
    let n = color_words(stereo.color_format);
    for (var word = 0u; word < n; word++) {
        right_color[n * i + word] = words[word];
    }
    if stereo.has_depth != 0u {
        right_depth[i] = depth;
    }
}
