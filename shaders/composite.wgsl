// #import color, stereo, composite_bindings
// The right eye from the re-projection layers: per right pixel, the left
// rays on its epipolar line whose segments crossed it, nearest first, each
// blended from the two rays the line passes between.

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
    var acc = vec4f(0.0);
    var depth = bitcast<f32>(0x7f800000u);
    for (var k = 0; k < count; k++) {
        let offset = near + (k - 1) * dir;
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
            // A segment that alone crosses the threshold (often the whole
            // ray, near the epipole) knows where; else the crossing is
            // placed between its first and last sample by the opacity
            // it still needed.
            let needed = (stereo.depth_threshold - before) / (1.0 - before);
            depth = mix(d.x, d.y, clamp(needed / max(segment.a, 1e-6), 0.0, 1.0));
            if before == 0.0 && d.z < 3.0e38 {
                depth = d.z;
            }
        }
        if acc.a >= stereo.termination {
            break;
        }
    }
    let i = id.y * stereo.width + id.x;
    store_color(i, over(acc, stereo.background), stereo.color_format);
    if stereo.has_depth != 0u {
        depth_out[i] = depth;
    }
}
