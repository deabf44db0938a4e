// #import volume, surface, color, band_bindings
// One eye, one invocation per pixel.

fn on_sample(p: vec3f, t: f32, lit: vec3f, a: f32) {}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = vec2u(params.width, params.height);
    let pixel = vec2u(id.x, id.y + band.x);
    if pixel.x >= size.x || pixel.y >= size.y {
        return;
    }
    let ray = primary_ray(f32(pixel.x), f32(pixel.y));
    // The nearest surface ends the march and lies behind what it gathers.
    let hit = nearest_surface(ray.o, ray.d, params.t_near, params.t_far);
    var behind = background_at(pixel);
    var surface_depth = infinite();
    if hit.slot != NO_SLOT {
        march_stop = hit.t;
        behind = vec4f(surface_color(hit, ray.o, ray.d), 1.0);
        surface_depth = depth_along(ray.o + ray.d * hit.t, hit.t);
    }
    let m = march(ray);
    let i = pixel.y * size.x + pixel.x;
    depth_out[i] = min(m.depth, surface_depth);
    samples_out[i] = samples;
    store_color(i, over(m.color, behind), params.color_format);
}
