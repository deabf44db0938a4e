// #import constants
// What the re-projection and compositing passes share
// (docs/reprojection_stereo.md, src/render/stereo/epipolar.rs).
//
// A left pixel p's right-eye image moves with depth along g(p), its
// epipolar line. Lines nearer the rows than the columns are cut at
// right-eye columns (family 0), the others at right-eye rows (family 1).
// The ray of left pixel p writes family 0 into texel (right column, p.y)
// of layer p.x mod L, family 1 into texel (p.x, right row) of layer
// p.y mod L, after family 0's L layers where both are in use. The rays one texel could receive lie on one line, fewer
// than L pixels apart along it, so no two of them share a layer.

// `Stereo` is generated from src/render/gpu/uniforms.rs, which documents
// its fields; the entry file's bindings declare `stereo`.

fn g_of(p: vec2i) -> vec2f {
    return stereo.epipole.z * vec2f(p) - stereo.epipole.xy;
}

// The coordinate of p along family `axis` (x for 0, y for 1), and across.
fn along(p: vec2i, axis: u32) -> i32 {
    return select(p.x, p.y, axis == 1u);
}
fn alongf(v: vec2f, axis: u32) -> f32 {
    return select(v.x, v.y, axis == 1u);
}
fn acrossf(v: vec2f, axis: u32) -> f32 {
    return select(v.y, v.x, axis == 1u);
}

// The rows family's layers follow the columns family's, if there are any.
fn layer_of(p: vec2i, axis: u32) -> i32 {
    let n = stereo.layers;
    let k = along(p, axis);
    let after_columns = axis == 1u && (stereo.families & 1u) != 0u;
    return ((k % n) + n) % n + select(0, n, after_columns);
}

// The texel of left pixel p's segment at right coordinate `at` along `axis`.
fn texel_of(p: vec2i, at: i32, axis: u32) -> vec2i {
    if axis == 0u {
        return vec2i(at, p.y - stereo.first.y);
    }
    return vec2i(p.x - stereo.first.x, at);
}

// The right-eye columns (x, y) and rows (z, w) left pixel p wrote this
// frame, first > last if none. Texels outside them hold stale data from
// earlier frames and are never read, which is what spares the layers a
// clear.
fn span_index(p: vec2i) -> u32 {
    let c = p - stereo.first;
    return u32(c.y) * stereo.cast_pixels.x + u32(c.x);
}

fn is_cast(p: vec2i) -> bool {
    let c = p - stereo.first;
    return all(c >= vec2i(0)) && all(vec2u(c) < stereo.cast_pixels);
}
