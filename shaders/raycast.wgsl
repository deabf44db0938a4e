// #import volume, color, band_bindings
// One eye, one invocation per pixel.

fn on_sample(p: vec3f, t: f32, lit: vec3f, a: f32) {}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = vec2u(params.width, params.height);
    let pixel = vec2u(id.x, id.y + band.x);
    if pixel.x >= size.x || pixel.y >= size.y {
        return;
    }
    let m = march(primary_ray(f32(pixel.x), f32(pixel.y)));
    let i = pixel.y * size.x + pixel.x;
    depth_out[i] = m.depth;
    samples_out[i] = samples;
    store_color(i, over(m.color, background_at(pixel)), params.color_format);
}
