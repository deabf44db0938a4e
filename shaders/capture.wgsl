// #import volume, color, capture_bindings, band_bindings
// A view as image warping needs it: color over nothing, first-hit depth,
// and the emission-absorption layers of src/render/warp/layers.rs,
// recorded sample by sample as the CPU's LayerBuilder does.

const MAX_KEPT: u32 = 8u;

var<private> current: u32;
var<private> total: f32;
var<private> kept: array<vec4f, 16>;

// Worlds with surfaces are not captured or re-projected (the engine
// renders them whole), so no surface stands in a shadow ray's way.
fn surface_pass(p: vec3f, d: vec3f, reach: f32) -> f32 {
    return 1.0;
}

fn on_sample(p: vec3f, t: f32, lit: vec3f, a: f32) {
    let k = min(capture.x, MAX_KEPT);
    if k == 0u {
        return;
    }
    // Every segment is taken as a full step (the last one of a ray is
    // shorter on the CPU).
    let seg = params.step;
    var c = kept[2u * current];
    var span = kept[2u * current + 1u];
    if c.a == 0.0 {
        span.x = t - 0.5 * seg;
    }
    span.y = t + 0.5 * seg;
    let weight = (1.0 - c.a) * a;
    kept[2u * current] = vec4f(c.rgb + lit * weight, c.a + weight);
    kept[2u * current + 1u] = span;
    total = total + (1.0 - total) * a;
    if total >= f32(current + 1u) / f32(k) && current + 1u < k {
        current += 1u;
    }
}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let size = vec2u(params.width, params.height);
    let pixel = vec2u(id.x, id.y + band.x);
    if pixel.x >= size.x || pixel.y >= size.y {
        return;
    }
    current = 0u;
    total = 0.0;
    for (var k = 0u; k < 2u * MAX_KEPT; k++) {
        kept[k] = vec4f(0.0);
    }
    let m = march(primary_ray(f32(pixel.x), f32(pixel.y)));
    let i = pixel.y * size.x + pixel.x;
    depth_out[i] = m.depth;
    samples_out[i * params.pixel_words] = samples;
    store_color(i, m.color, FORMAT_RGBA32F);
    let k = min(capture.x, MAX_KEPT);
    for (var l = 0u; l < 2u * k; l++) {
        layer_out[2u * i * k + l] = kept[l];
    }
}
