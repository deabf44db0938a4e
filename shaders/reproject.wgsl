// The left eye, ray cast over the image plus the columns the right eye
// needs beyond its borders, writing each ray's right-eye segments into the
// re-projection layers (after volume.wgsl, colour.wgsl and stereo.wgsl).
// LAYER_FORMAT is replaced by the layers' storage format before compiling.

@group(1) @binding(0) var<uniform> stereo: Stereo;
@group(1) @binding(1) var layers: texture_storage_2d_array<LAYER_FORMAT, write>;
@group(1) @binding(2) var<storage, read_write> spans: array<vec2i>;

const NO_PIXEL: i32 = -2147483647;

var<private> column: i32;
var<private> row: i32;
var<private> layer: i32;
// The open segment: its right pixel and premultiplied colour.
var<private> segment_pixel: i32 = NO_PIXEL;
var<private> segment: vec4f;
var<private> first_pixel: i32 = NO_PIXEL;

fn right_pixel(p: vec3f) -> i32 {
    let q = vec4f(p, 1.0);
    let x = dot(stereo.right_x, q) / dot(stereo.right_w, q) - f32(column);
    // Clamped in float first: converting an out-of-range float is undefined.
    let offset = clamp(x, f32(stereo.near_offset), f32(stereo.far_offset));
    return column + i32(round(offset));
}

fn emit(pixel: i32, value: vec4f) {
    if pixel >= 0 && pixel < i32(stereo.width) {
        textureStore(layers, vec2i(pixel, row), layer, value);
    }
}

fn on_sample(p: vec3f, lit: vec3f, a: f32) {
    // Depth grows along the ray and the offset with it; max() keeps
    // rounding noise from stepping back into a written pixel.
    let pixel = max(right_pixel(p), segment_pixel);
    if first_pixel == NO_PIXEL {
        first_pixel = pixel;
        segment_pixel = pixel;
    } else if pixel != segment_pixel {
        emit(segment_pixel, segment);
        // Pixels the ray stepped over get empty segments, so every texel
        // inside the span is this frame's.
        for (var q = segment_pixel + 1; q < pixel; q++) {
            emit(q, vec4f(0.0));
        }
        segment = vec4f(0.0);
        segment_pixel = pixel;
    }
    // The same arithmetic as the left eye's accumulation, so a single
    // segment (e = 0) equals the left pixel exactly.
    let weight = (1.0 - segment.a) * a;
    segment = vec4f(segment.rgb + lit * weight, segment.a + weight);
}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3u) {
    if id.x >= stereo.columns || id.y >= stereo.height {
        return;
    }
    column = i32(id.x) + stereo.first_column;
    row = i32(id.y);
    layer = layer_of(column);
    let m = march(f32(column), f32(row));
    var span = vec2i(1, 0);
    if first_pixel != NO_PIXEL {
        emit(segment_pixel, segment);
        span = vec2i(first_pixel, segment_pixel);
    }
    spans[span_index(column, id.y)] = span;

    let width = i32(stereo.width);
    if column >= 0 && column < width {
        let i = id.y * stereo.width + u32(column);
        depth_out[i] = m.depth;
        samples_out[i] = samples;
        store_color(i, over(m.color, background_at(vec2u(u32(column), id.y))), params.color_format);
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
