// #import volume, color, stereo, reproject_bindings, band_bindings
// The left eye, ray cast over the image plus the pixels the right eye
// needs beyond its borders, writing each ray's right-eye segments into the
// re-projection layers, whose storage format is the binding table's.

const NO_PIXEL: i32 = -2147483647;
const INFINITY: f32 = 3.4028235e38;

// One family's open segment.
struct Open {
    // Whether this ray writes the family at all.
    on: bool,
    // The right pixel the segment is in, and the first the ray wrote.
    pixel: i32,
    first: i32,
    // Premultiplied color; the right eye's distance to the segment's
    // first sample, to its last, and to where its own opacity reaches the
    // depth threshold.
    color: vec4f,
    depth: vec3f,
    // +1 or -1: the way the right pixel moves as the ray goes deeper.
    dir: i32,
    // The offsets (right minus left) the ray's samples may have.
    lo: i32,
    hi: i32,
}

var<private> left: vec2i;
var<private> open: array<Open, 2>;

fn emit(axis: u32, at: i32, value: vec4f, depth: vec3f) {
    let size = select(i32(stereo.width), i32(stereo.height), axis == 1u);
    if at < 0 || at >= size {
        return;
    }
    let texel = texel_of(left, at, axis);
    let layer = layer_of(left, axis);
    textureStore(layers, texel, layer, value);
    if stereo.has_depth != 0u {
        textureStore(depths, texel, layer, vec4f(depth, 0.0));
    }
}

fn on_sample(p: vec3f, lit: vec3f, a: f32) {
    let h = vec4f(p, 1.0);
    let right = vec2f(dot(stereo.right_x, h), dot(stereo.right_y, h)) / dot(stereo.right_w, h);
    for (var axis = 0u; axis < 2u; axis++) {
        if !open[axis].on {
            continue;
        }
        let own = along(left, axis);
        // Clamped in float first: converting an out-of-range float is undefined.
        let offset = clamp(alongf(right, axis) - f32(own), f32(open[axis].lo), f32(open[axis].hi));
        var pixel = own + i32(round(offset));
        let dir = open[axis].dir;
        // The sample stands for the stretch of ray since the last one; where
        // that stretch crosses several right pixels (the volume near the
        // eyes), each gets the opacity of its share of the stretch rather
        // than one getting all and the others none.
        var share = a;
        let distance = length(p - stereo.right_eye);
        if open[axis].first == NO_PIXEL {
            open[axis].first = pixel;
            open[axis].pixel = pixel;
        } else {
            // Rounding noise must not step back into a written pixel.
            pixel = select(min(pixel, open[axis].pixel), max(pixel, open[axis].pixel), dir > 0);
            if pixel != open[axis].pixel {
                emit(axis, open[axis].pixel, open[axis].color, open[axis].depth);
                let gap = abs(pixel - open[axis].pixel);
                if gap > 1 {
                    share = 1.0 - pow(1.0 - min(a, 1.0), 1.0 / f32(gap));
                }
                let crossed = select(INFINITY, distance, share >= stereo.depth_threshold);
                // Every texel inside the span is this frame's: the pixels
                // stepped over get their share.
                for (var k = 1; k < gap; k++) {
                    emit(axis, open[axis].pixel + k * dir, vec4f(lit * share, share), vec3f(distance, distance, crossed));
                }
                open[axis].color = vec4f(0.0);
                open[axis].depth = vec3f(INFINITY);
                open[axis].pixel = pixel;
            }
        }
        if open[axis].depth.x == INFINITY {
            open[axis].depth.x = distance;
        }
        open[axis].depth.y = distance;
        // The same arithmetic as the left eye's accumulation, so a single
        // segment (e = 0) equals the left pixel exactly.
        let s = open[axis].color;
        let weight = (1.0 - s.a) * share;
        open[axis].color = vec4f(s.rgb + lit * weight, s.a + weight);
        if open[axis].depth.z == INFINITY && open[axis].color.a >= stereo.depth_threshold {
            open[axis].depth.z = distance;
        }
    }
}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(global_invocation_id) invocation: vec3u) {
    let id = vec3u(invocation.x, invocation.y + band.x, 0u);
    if id.x >= stereo.cast_pixels.x || id.y >= stereo.cast_pixels.y {
        return;
    }
    left = vec2i(id.xy) + stereo.first;
    let g = g_of(left);
    let spread = stereo.lambda_far - stereo.lambda_near;
    for (var axis = 0u; axis < 2u; axis++) {
        let major = alongf(g, axis);
        let minor = acrossf(g, axis);
        let near = i32(round(stereo.lambda_near * major));
        let far = i32(round(stereo.lambda_far * major));
        open[axis] = Open(
            (stereo.families & (1u << axis)) != 0u && abs(major) >= abs(minor) - abs(stereo.epipole.z),
            NO_PIXEL,
            NO_PIXEL,
            vec4f(0.0),
            vec3f(INFINITY),
            select(-1, 1, spread * major >= 0.0),
            min(near, far),
            max(near, far),
        );
    }
    let m = march(f32(left.x), f32(left.y));
    var span = vec4i(1, 0, 1, 0);
    for (var axis = 0u; axis < 2u; axis++) {
        if !open[axis].on || open[axis].first == NO_PIXEL {
            continue;
        }
        emit(axis, open[axis].pixel, open[axis].color, open[axis].depth);
        let lo = min(open[axis].first, open[axis].pixel);
        let hi = max(open[axis].first, open[axis].pixel);
        if axis == 0u {
            span = vec4i(lo, hi, span.z, span.w);
        } else {
            span = vec4i(span.x, span.y, lo, hi);
        }
    }
    spans[span_index(left)] = span;

    if left.x >= 0 && left.x < i32(stereo.width) && left.y >= 0 && left.y < i32(stereo.height) {
        let i = u32(left.y) * stereo.width + u32(left.x);
        depth_out[i] = m.depth;
        samples_out[i] = samples;
        store_color(i, over(m.color, background_at(vec2u(left))), params.color_format);
    }
}

// Zeroes every texel: what the span scheme avoids, kept to measure it.
@compute @workgroup_size(WORKGROUP, WORKGROUP, 1)
fn clear(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(layers);
    if id.x >= size.x || id.y >= size.y || id.z >= textureNumLayers(layers) {
        return;
    }
    textureStore(layers, vec2u(id.xy), id.z, vec4f(0.0));
}
