// #import trace, color, capture_bindings, band
// A view as image warping needs it: color over nothing, first-hit depth,
// and the emission-absorption layers of src/render/warp/layers.rs,
// recorded sample by sample and surface by surface as the CPU's
// LayerBuilder does.

const MAX_KEPT: u32 = 8u;

var<private> current: u32;
var<private> total: f32;
// Whether the next sample starts a layer of its own (after a surface).
var<private> sealed: bool;
var<private> kept: array<vec4f, 16>;

fn layer_count() -> u32 {
    return min(capture.x, MAX_KEPT);
}

// Moves on to the next layer if the current one holds anything and one
// is left (LayerBuilder::open).
fn open_layer() {
    if kept[2u * current].a > 0.0 && current + 1u < layer_count() {
        current += 1u;
    }
}

// Adds opacity a of color lit over [begin, end] to the current layer; the
// ray's opacity is then `total`. A layer's span keeps in z whether it
// holds one surface alone (Layer::surface).
fn keep(begin: f32, end: f32, lit: vec3f, a: f32, surface: bool) {
    var c = kept[2u * current];
    var span = kept[2u * current + 1u];
    if c.a == 0.0 {
        span = vec4f(begin, end, select(0.0, 1.0, surface), 0.0);
    } else {
        span.y = max(span.y, end);
        span.z = 0.0;
    }
    let weight = (1.0 - c.a) * a;
    kept[2u * current] = vec4f(c.rgb + lit * weight, c.a + weight);
    kept[2u * current + 1u] = span;
    total = total + (1.0 - total) * a;
    if total >= f32(current + 1u) / f32(layer_count()) && current + 1u < layer_count() {
        current += 1u;
    }
}

fn on_sample(p: vec3f, t: f32, lit: vec3f, a: f32) {
    if layer_count() == 0u {
        return;
    }
    if sealed {
        open_layer();
        sealed = false;
    }
    // Every segment is taken as a full step (the last one of a ray is
    // shorter on the CPU).
    let seg = params.step;
    keep(t - 0.5 * seg, t + 0.5 * seg, lit, a, false);
}

// A surface in a layer of its own where one is left, capture.y deep,
// ending where it is hit (LayerBuilder::add_surface).
fn on_surface(t: f32, lit: vec3f, a: f32) {
    if layer_count() == 0u {
        return;
    }
    open_layer();
    keep(t - bitcast<f32>(capture.y), t, lit, a, true);
    sealed = true;
}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(workgroup_id) group: vec3u, @builtin(local_invocation_id) local: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let size = vec2u(params.width, params.height);
    let pixel = band_pixel(group, local, groups);
    if pixel.x >= size.x || pixel.y >= size.y {
        return;
    }
    current = 0u;
    total = 0.0;
    sealed = false;
    for (var k = 0u; k < 2u * MAX_KEPT; k++) {
        kept[k] = vec4f(0.0);
    }
    let traced = trace(primary_ray(f32(pixel.x), f32(pixel.y)));
    let i = pixel.y * size.x + pixel.x;
    depth_out[i] = min(traced.m.depth, traced.surface_depth);
    samples_out[i * params.pixel_words] = samples;
    store_color(i, over(traced.m.color, traced.opaque), FORMAT_RGBA32F);
    let k = layer_count();
    for (var l = 0u; l < 2u * k; l++) {
        layer_out[2u * i * k + l] = kept[l];
    }
}
