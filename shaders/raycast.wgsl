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
    // Marched up to each surface, a translucent one composited in its
    // turn, the first opaque one ending the ray in front of the
    // background (as the CPU's through_surfaces).
    var m = Marched(vec4f(0.0), infinite());
    var behind = background_at(pixel);
    var surface_depth = infinite();
    var start = params.t_near;
    var composited = 0u;
    var done = false;
    for (var looked = 0u; looked < SURFACE_PASSES; looked++) {
        let hit = nearest_surface(ray.o, ray.d, start, params.t_far);
        m = march_segment(ray, start, hit.t, m);
        if hit.slot == NO_SLOT {
            done = true;
            break;
        }
        let lit = surface_color(hit, ray.o, ray.d);
        let a = surface_alpha(hit);
        let p = ray.o + ray.d * hit.t;
        if a >= 1.0 {
            behind = vec4f(lit, 1.0);
            surface_depth = depth_along(p, hit.t);
            done = true;
            break;
        }
        if composited < MAX_TRANSLUCENT {
            let weight = (1.0 - m.color.a) * a;
            m.color = vec4f(m.color.rgb + lit * weight, m.color.a + weight);
            if m.depth == infinite() && m.color.a >= params.depth_threshold {
                m.depth = depth_along(p, hit.t);
            }
            composited++;
            if m.color.a >= params.termination {
                done = true;
                break;
            }
        }
        start = hit.t;
    }
    if !done {
        m = march_segment(ray, start, infinite(), m);
    }
    let i = pixel.y * size.x + pixel.x;
    depth_out[i] = min(m.depth, surface_depth);
    samples_out[i] = samples;
    store_color(i, over(m.color, behind), params.color_format);
}
