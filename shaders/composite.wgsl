// The right eye from the re-projection layers: per right pixel, the left
// columns whose rays crossed it, nearest first (after colour.wgsl and
// stereo.wgsl).

@group(0) @binding(0) var<uniform> stereo: Stereo;
@group(0) @binding(1) var layers: texture_2d_array<f32>;
@group(0) @binding(2) var<storage, read> spans: array<vec2i>;
@group(0) @binding(3) var<storage, read_write> color_out: array<u32>;

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3u) {
    if id.x >= stereo.width || id.y >= stereo.height {
        return;
    }
    let pixel = i32(id.x);
    var acc = vec4f(0.0);
    // Nearer points shift less to the right, so the columns further right
    // hold the nearer segments.
    for (var offset = stereo.near_offset; offset <= stereo.far_offset; offset++) {
        let column = pixel - offset;
        let span = spans[span_index(column, id.y)];
        if pixel < span.x || pixel > span.y {
            continue;
        }
        let segment = textureLoad(layers, vec2i(pixel, i32(id.y)), layer_of(column), 0);
        acc = acc + (1.0 - acc.a) * segment;
        if acc.a >= stereo.termination {
            break;
        }
    }
    store_color(id.y * stereo.width + id.x, over(acc, stereo.background), stereo.color_format);
}
