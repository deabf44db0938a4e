// #import volume, surface
// One primary ray through the volumes and the surfaces, as the CPU's
// through_surfaces (src/render/cpu/mod.rs): marched up to each surface, a
// translucent one composited in its turn, the first opaque one ending the
// ray. The ray caster and the warps' capture run it; each defines, besides
// the march's hooks (volume.wgsl), `on_surface(t, lit, a)`, which sees
// every surface composited, at t along the ray (a = 1: the opaque one that
// ends it).

struct Traced {
    // The volumes and the translucent surfaces, premultiplied.
    m: Marched,
    // The opaque surface's lit color, alpha 1; zero where none ends the ray.
    opaque: vec4f,
    // Its depth (infinite where none).
    surface_depth: f32,
    // The surface hit at the pixel's depth, if a surface set it.
    first: SurfaceHit,
}

fn trace(ray: Ray) -> Traced {
    let none = SurfaceHit(infinite(), NO_SLOT, vec2f(0.0));
    if !SURFACES {
        let m = march_segment(ray, params.t_near, infinite(), Marched(vec4f(0.0), infinite()));
        return Traced(m, vec4f(0.0), infinite(), none);
    }
    var m = Marched(vec4f(0.0), infinite());
    var opaque = vec4f(0.0);
    var surface_depth = infinite();
    var first = none;
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
            opaque = vec4f(lit, 1.0);
            surface_depth = depth_along(p, hit.t);
            if surface_depth <= m.depth {
                first = hit;
            }
            on_surface(hit.t, lit, 1.0);
            done = true;
            break;
        }
        if composited < MAX_TRANSLUCENT {
            if composite_surface(&m, lit, a, p, hit.t) {
                first = hit;
            }
            on_surface(hit.t, lit, a);
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
    return Traced(m, opaque, surface_depth, first);
}

// As the CPU's ShapeSet::passes: an opaque surface blocks the light, a
// translucent one lets 1 - opacity through.
fn surface_pass(p: vec3f, d: vec3f, reach: f32) -> f32 {
    if !SURFACES {
        return 1.0;
    }
    let hit = nearest_surface(p, d, 0.0, reach);
    if hit.slot == NO_SLOT {
        return 1.0;
    }
    return 1.0 - surface_alpha(hit);
}
