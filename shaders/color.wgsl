// #import constants
// Writes one pixel of `color_out` in the frame's format; the pass's
// bindings declare `color_out` (array<u32>). Passes that write another
// buffer store `encoded` themselves.

fn linear_to_srgb(x: f32) -> f32 {
    if x <= 0.0031308 {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}


// Premultiplied `acc` over a straight background.
fn over(acc: vec4f, bg: vec4f) -> vec4f {
    return vec4f(acc.rgb + (1.0 - acc.a) * bg.rgb, acc.a + (1.0 - acc.a) * bg.a);
}

// The words of pixel `out` in `format`: one of 8-bit colour, four of
// float colour (color_words).
fn encoded(out: vec4f, format: u32) -> vec4u {
    switch format {
        case FORMAT_RGBA8: {
            return vec4u(pack4x8unorm(out), 0u, 0u, 0u);
        }
        case FORMAT_SRGBA8: {
            let s = vec4f(linear_to_srgb(out.r), linear_to_srgb(out.g), linear_to_srgb(out.b), out.a);
            return vec4u(pack4x8unorm(s), 0u, 0u, 0u);
        }
        default: {
            return bitcast<vec4u>(out);
        }
    }
}

fn color_words(format: u32) -> u32 {
    return select(4u, 1u, format == FORMAT_RGBA8 || format == FORMAT_SRGBA8);
}

fn store_color(i: u32, out: vec4f, format: u32) {
    let words = encoded(out, format);
    let n = color_words(format);
    for (var k = 0u; k < n; k++) {
        color_out[n * i + k] = words[k];
    }
}
