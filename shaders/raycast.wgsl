// One eye, one invocation per pixel (after volume.wgsl and color.wgsl).

fn on_sample(p: vec3f, lit: vec3f, a: f32) {}

// x: the first row of this band (the frame is cast a band of rows at a
// time, so a discard can stop it between bands).
@group(1) @binding(0) var<uniform> band: vec4u;

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = vec2u(params.width, params.height);
    let pixel = vec2u(id.x, id.y + band.x);
    if pixel.x >= size.x || pixel.y >= size.y {
        return;
    }
    let m = march(f32(pixel.x), f32(pixel.y));
    let i = pixel.y * size.x + pixel.x;
    depth_out[i] = m.depth;
    samples_out[i] = samples;
    store_color(i, over(m.color, background_at(pixel)), params.color_format);
}
