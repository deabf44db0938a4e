// One eye, one invocation per pixel (after volume.wgsl and colour.wgsl).

fn on_sample(p: vec3f, lit: vec3f, a: f32) {}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = vec2u(params.width, params.height);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let m = march(f32(id.x), f32(id.y));
    let i = id.y * size.x + id.x;
    depth_out[i] = m.depth;
    samples_out[i] = samples;
    store_color(i, over(m.color, background_at(id.xy)), params.color_format);
}
