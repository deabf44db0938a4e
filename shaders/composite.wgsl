// #import color, stereo, composite_bindings
// The right eye from the re-projection layers: per right pixel, the left
// rays on its epipolar line whose segments crossed it, nearest first, each
// blended from the two rays the line passes between.

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
    var depth = bitcast<f32>(0x7f800000u);
    var k = 0;
    var opaque = false;
    while k < count && !opaque {
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
                if stereo.has_depth != 0u && share >= weight {
                    d = textureLoad(depths, texel, layer, 0).xyz;
                }
                weight += share;
            }
            if weight == 0.0 {
                continue;
            }
            segment /= weight;
            let before = acc.a;
            acc = acc + (1.0 - acc.a) * segment;
            if stereo.has_depth != 0u && depth == bitcast<f32>(0x7f800000u) && acc.a >= stereo.depth_threshold {
                // A segment that alone crosses the threshold (often the
                // whole ray, near the epipole) knows where; else the
                // crossing is placed between its first and last sample by
                // the opacity it still needed.
                let needed = (stereo.depth_threshold - before) / (1.0 - before);
                depth = mix(d.x, d.y, clamp(needed / max(segment.a, 1e-6), 0.0, 1.0));
                if before == 0.0 && d.z < 3.0e38 {
                    depth = d.z;
                }
            }
            if acc.a >= stereo.termination {
                opaque = true;
                break;
            }
        }
        k += chunk;
    }
    let i = id.y * stereo.width + id.x;
    store_color(i, over(acc, stereo.background), stereo.color_format);
    if stereo.has_depth != 0u {
        depth_out[i] = depth;
    }
}
