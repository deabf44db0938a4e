// #import constants
// Writes one pixel of `color_out` in the frame's format; the pass's
// bindings declare `color_out` (array<u32>).

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

fn store_color(i: u32, out: vec4f, format: u32) {
    switch format {
        case FORMAT_RGBA8: {
            color_out[i] = pack4x8unorm(out);
        }
        case FORMAT_SRGBA8: {
            let s = vec4f(linear_to_srgb(out.r), linear_to_srgb(out.g), linear_to_srgb(out.b), out.a);
            color_out[i] = pack4x8unorm(s);
        }
        default: {
            color_out[4u * i] = bitcast<u32>(out.r);
            color_out[4u * i + 1u] = bitcast<u32>(out.g);
            color_out[4u * i + 2u] = bitcast<u32>(out.b);
            color_out[4u * i + 3u] = bitcast<u32>(out.a);
        }
    }
}
