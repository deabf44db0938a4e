// Emission-absorption volume ray casting: the march along one primary ray.
// Mirrors src/render/cpu/ (the reference) operation for operation, so the
// two agree to rounding; all derived numbers arrive in `params`. Its
// struct `Params` and the constants (SHADE_, TABLE_SIZE, ...) are declared
// in front of this file from src/render/gpu/uniforms.rs, which documents
// the fields.
// Entry points live in raycast.wgsl and reproject.wgsl, each concatenated
// after this file with colour.wgsl; each defines `on_sample`, which sees
// every sample that contributes (the re-projection path splits the ray into
// right-eye segments there).

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var volume: texture_3d<f32>;
@group(0) @binding(2) var table: texture_2d<f32>;
@group(0) @binding(3) var<storage, read> directions: array<vec4f>;
@group(0) @binding(4) var<storage, read_write> color_out: array<u32>;
@group(0) @binding(5) var<storage, read_write> depth_out: array<f32>;
// Volume samples per pixel (primary and shading), summed on the host.
@group(0) @binding(6) var<storage, read_write> samples_out: array<u32>;
@group(0) @binding(7) var background_image: texture_2d<f32>;

// What lies behind pixel `pixel` of the frame: the flat colour, or the
// background image stretched over the frame, sampled bilinearly at the
// pixel's centre as BackgroundImage::at does.
fn background_at(pixel: vec2u) -> vec4f {
    if params.has_background_image == 0u {
        return params.background;
    }
    let n = textureDimensions(background_image);
    let frame = vec2f(f32(params.width), f32(params.height));
    let c = clamp((vec2f(pixel) + 0.5) / frame * vec2f(n) - 0.5, vec2f(0.0), vec2f(n - 1u));
    let i0 = min(vec2u(floor(c)), n - 1u);
    let i1 = min(i0 + 1u, n - 1u);
    let f = c - vec2f(i0);
    let bottom = textureLoad(background_image, vec2u(i0.x, i0.y), 0) * (1.0 - f.x)
        + textureLoad(background_image, vec2u(i1.x, i0.y), 0) * f.x;
    let top = textureLoad(background_image, vec2u(i0.x, i1.y), 0) * (1.0 - f.x)
        + textureLoad(background_image, vec2u(i1.x, i1.y), 0) * f.x;
    return bottom * (1.0 - f.y) + top * f.y;
}

var<private> samples: u32;

fn voxel(i: vec3i) -> f32 {
    return textureLoad(volume, i, 0).r;
}

// Trilinear interpolation of the vertex-centred grid, by hand: R32Float
// is not filterable everywhere, and the reference does the same. Or the
// nearest vertex, halves rounded up as the reference rounds them.
fn sample_volume(p: vec3f) -> f32 {
    samples += 1u;
    let hi = vec3i(params.dims) - vec3i(1);
    let g = clamp((p - params.box_lo) * params.inv_spacing, vec3f(0.0), vec3f(hi));
    if params.sampling == FILTER_NEAREST {
        return voxel(min(vec3i(floor(g + vec3f(0.5))), hi));
    }
    let i0 = min(vec3i(floor(g)), max(hi - vec3i(1), vec3i(0)));
    let f = g - vec3f(i0);
    let i1 = min(i0 + vec3i(1), hi);
    let x00 = mix(voxel(vec3i(i0.x, i0.y, i0.z)), voxel(vec3i(i1.x, i0.y, i0.z)), f.x);
    let x10 = mix(voxel(vec3i(i0.x, i1.y, i0.z)), voxel(vec3i(i1.x, i1.y, i0.z)), f.x);
    let x01 = mix(voxel(vec3i(i0.x, i0.y, i1.z)), voxel(vec3i(i1.x, i0.y, i1.z)), f.x);
    let x11 = mix(voxel(vec3i(i0.x, i1.y, i1.z)), voxel(vec3i(i1.x, i1.y, i1.z)), f.x);
    return mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z);
}

fn classify(v: f32) -> vec4f {
    let last = f32(TABLE_SIZE - 1u);
    let t = clamp((v - params.value_lo) * params.value_scale, 0.0, 1.0) * last;
    let i = min(u32(t), TABLE_SIZE - 2u);
    let f = t - f32(i);
    let a = textureLoad(table, vec2i(i32(i), 0), 0);
    let b = textureLoad(table, vec2i(i32(i) + 1, 0), 0);
    return a * (1.0 - f) + b * f;
}

fn inside(p: vec3f) -> bool {
    return all(p >= params.box_lo) && all(p <= params.box_hi);
}

fn opacity_at(p: vec3f) -> f32 {
    if inside(p) {
        return classify(sample_volume(p)).a;
    }
    return 0.0;
}

fn correct(a: f32, exponent: f32) -> f32 {
    if a >= 1.0 {
        return 1.0;
    }
    return 1.0 - pow(1.0 - a, exponent);
}

fn transmittance(p: vec3f, dir: vec3f, steps: u32, exponent: f32) -> f32 {
    var t = 1.0;
    for (var k = 1u; k <= steps; k++) {
        let q = p + dir * (params.shading_step * f32(k));
        if !inside(q) {
            break;
        }
        t *= 1.0 - correct(opacity_at(q), exponent);
    }
    return t;
}

fn shadow(p: vec3f, exponent: f32) -> f32 {
    let t = transmittance(p, params.light, SHADOW_STEPS, exponent);
    return SHADOW_AMBIENT + (1.0 - SHADOW_AMBIENT) * t;
}

fn ambient_occlusion(p: vec3f) -> f32 {
    let n = params.direction_count;
    var occluded = 0.0;
    for (var i = 0u; i < n; i++) {
        occluded += opacity_at(p + directions[i].xyz * params.ao_radius);
    }
    return 1.0 - occluded / f32(n);
}

fn shade(p: vec3f) -> f32 {
    let exponent = params.shading_step * params.inv_unit_distance;
    let n = params.direction_count;
    switch params.shading {
        case SHADE_SHADOWS: {
            return shadow(p, exponent);
        }
        case SHADE_AO: {
            return ambient_occlusion(p);
        }
        case SHADE_SHADOWS_AO: {
            return shadow(p, exponent) * ambient_occlusion(p);
        }
        case SHADE_DIRECTIONAL: {
            if n == 0u {
                return 1.0;
            }
            var sum = 0.0;
            for (var i = 0u; i < n; i++) {
                sum += transmittance(p, directions[i].xyz, DIRECTIONAL_STEPS, exponent);
            }
            return sum / f32(n);
        }
        default: {
            return 1.0;
        }
    }
}

fn safe_inverse(x: f32) -> f32 {
    if abs(x) < 1e-20 {
        return 1.0 / select(1e-20, -1e-20, x < 0.0);
    }
    return 1.0 / x;
}

// The ray of pixel (fx, fy); columns outside the image are allowed.
struct Marched {
    // Premultiplied colour and opacity accumulated front to back.
    color: vec4f,
    // Distance along the unit ray to the first contributing sample.
    depth: f32,
}

fn march(fx: f32, fy: f32) -> Marched {
    let o = params.ray_origin + fx * params.ray_origin_dx + fy * params.ray_origin_dy;
    let d = normalize(params.ray_dir + fx * params.ray_dir_dx + fy * params.ray_dir_dy);

    let step = params.step;
    var acc = vec4f(0.0);
    var depth = bitcast<f32>(0x7f800000u);
    var hit = false;

    let inv = vec3f(safe_inverse(d.x), safe_inverse(d.y), safe_inverse(d.z));
    let ta = (params.box_lo - o) * inv;
    let tb = (params.box_hi - o) * inv;
    let tn = min(ta, tb);
    let tf = max(ta, tb);
    var t0 = max(max(max(tn.x, tn.y), tn.z), params.t_near);
    var t1 = min(min(min(tf.x, tf.y), tf.z), params.t_far);
    // Clip planes (n, d) keep dot(n, o + t d) < d, as the reference does.
    for (var i = 0u; i < params.clip_count; i++) {
        let plane = params.clip[i];
        let along = dot(plane.xyz, d);
        let at = plane.w - dot(plane.xyz, o);
        if along > 0.0 {
            t1 = min(t1, at / along);
        } else if along < 0.0 {
            t0 = max(t0, at / along);
        } else if at <= 0.0 {
            t1 = t0;
        }
    }
    if t1 > t0 {
        let len = t1 - t0;
        let n = u32(ceil(len / step));
        for (var k = 0u; k < n; k++) {
            let start = f32(k) * step;
            let seg = max(min(step, len - start), 0.0);
            let t = t0 + start + 0.5 * seg;
            let p = o + d * t;
            let c = classify(sample_volume(p));
            if c.a <= 0.0 {
                continue;
            }
            let a = correct(c.a, seg * params.inv_unit_distance);
            let lit = c.rgb * shade(p) * params.light_color;
            on_sample(p, lit, a);
            let weight = (1.0 - acc.a) * a;
            acc = vec4f(acc.rgb + lit * weight, acc.a + weight);
            if !hit && acc.a >= params.depth_threshold {
                depth = t;
                if params.has_eye != 0u {
                    depth = length(p - params.eye);
                }
                hit = true;
            }
            if acc.a >= params.termination {
                break;
            }
        }
    }
    return Marched(acc, depth);
}
