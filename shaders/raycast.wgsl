// #import trace, color, band
// One eye, one invocation per pixel.

// The march's hooks: nothing is recorded.
fn on_sample(p: vec3f, t: f32, lit: vec3f, a: f32) {}
fn on_surface(t: f32, lit: vec3f, a: f32) {}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(workgroup_id) group: vec3u, @builtin(local_invocation_id) local: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let size = vec2u(params.width, params.height);
    let pixel = band_pixel(group, local, groups);
    if pixel.x >= size.x || pixel.y >= size.y {
        return;
    }
    let ray = primary_ray(f32(pixel.x), f32(pixel.y));
    let traced = trace(ray);
    let m = traced.m;
    let surface_depth = traced.surface_depth;
    let first = traced.first;
    var behind = background_at(pixel);
    if traced.opaque.a > 0.0 {
        behind = traced.opaque;
    }
    let i = pixel.y * size.x + pixel.x;
    let depth = min(m.depth, surface_depth);
    depth_out[i] = depth;
    samples_out[i * params.pixel_words] = samples;
    if params.pixel_words > 1u {
        store_hit(i * params.pixel_words + 1u, first, ray, depth);
    }
    store_color(i, over(m.color, behind), params.color_format);
}

// The pixel's HitRecord (render/hits.rs) from word `at` of samples_out:
// the surface hit `first` if it set the depth, else what the volumes show
// at the depth (as the CPU's Field::record), else nothing.
fn store_hit(at: u32, first: SurfaceHit, ray: Ray, depth: f32) {
    var what = WHAT_NOTHING;
    var index = 0u;
    var normal = vec3f(0.0);
    var albedo = vec3f(0.0);
    if first.slot != NO_SLOT {
        what = bitcast<u32>(prim_word(first.slot, 1u).w) >> 4u;
        index = bitcast<u32>(prim_word(first.slot, 2u).w);
        normal = surface_normal(first, ray.o + ray.d * first.t, ray.d);
        albedo = surface_albedo(first);
    } else if depth < infinite() && volume_count() > 0u {
        let p = select(ray.o, params.eye, params.has_eye != 0u) + ray.d * depth;
        var v = 0u;
        var nearest = infinite();
        for (var k = 0u; k < volume_count(); k++) {
            let g = grid_of(k, p);
            let out = max(-g, vec3f(0.0)) + max(g - last_vertex(k), vec3f(0.0));
            if dot(out, out) < nearest {
                nearest = dot(out, out);
                v = k;
            }
        }
        // These fetches are not the march's: the count stays the CPU's.
        let counted = samples;
        let h = params.step;
        albedo = classify(v, sample_volume(v, grid_of(v, p))).rgb;
        let gradient = vec3f(
            sample_volume(v, grid_of(v, p + vec3f(h, 0.0, 0.0))) - sample_volume(v, grid_of(v, p - vec3f(h, 0.0, 0.0))),
            sample_volume(v, grid_of(v, p + vec3f(0.0, h, 0.0))) - sample_volume(v, grid_of(v, p - vec3f(0.0, h, 0.0))),
            sample_volume(v, grid_of(v, p + vec3f(0.0, 0.0, h))) - sample_volume(v, grid_of(v, p - vec3f(0.0, 0.0, h))),
        );
        samples = counted;
        what = WHAT_VOLUME | v;
        let len = length(gradient);
        normal = select(-ray.d, gradient / len, len > 0.0);
        if dot(normal, ray.d) > 0.0 {
            normal = -normal;
        }
    }
    samples_out[at] = what;
    samples_out[at + 1u] = index;
    for (var k = 0u; k < 3u; k++) {
        samples_out[at + 2u + k] = bitcast<u32>(normal[k]);
        samples_out[at + 5u + k] = bitcast<u32>(albedo[k]);
    }
}
