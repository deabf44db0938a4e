// `caveray view`: the rig's walls as textured quads (seen from an observer,
// from the tracked head, or laid flat at their pixel size), lines (wall
// edges, the head, the volume's box), and the canvas copied to the window.

struct Wall {
    // Rig space (or, laid flat, the canvas's clip space) to clip space.
    clip: mat4x4<f32>,
    // Lower-left, lower-right, upper-right, upper-left corner.
    corners: array<vec4<f32>, 4>,
    // 0: left eye, 1: right eye, 2: red-cyan anaglyph, 3: side by side.
    stereo: u32,
    // Bit 0: a left image is bound; bit 1: a right image; bit 2: texel
    // exact (laid flat at 1:1), else filtered.
    flags: u32,
    _pad: vec2<u32>,
}

@group(0) @binding(0) var<uniform> wall: Wall;
@group(0) @binding(1) var left_image: texture_2d<f32>;
@group(0) @binding(2) var right_image: texture_2d<f32>;
@group(0) @binding(3) var smooth_sampler: sampler;

struct WallOut {
    @builtin(position) position: vec4<f32>,
    // (0, 0) at the wall's lower-left corner, (1, 1) at its upper-right.
    @location(0) uv: vec2<f32>,
}

@vertex
fn wall_vs(@builtin(vertex_index) i: u32) -> WallOut {
    var uvs = array<vec2<f32>, 6>(
        vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(1.0, 1.0),
        vec2(0.0, 0.0), vec2(1.0, 1.0), vec2(0.0, 1.0),
    );
    let uv = uvs[i];
    let ll = wall.corners[0].xyz;
    let p = ll + (wall.corners[1].xyz - ll) * uv.x + (wall.corners[3].xyz - ll) * uv.y;
    var out: WallOut;
    out.position = wall.clip * vec4(p, 1.0);
    out.uv = uv;
    return out;
}

// The images are stored top row first, as the PNGs `caveray render` writes.
fn image_at(image: texture_2d<f32>, uv: vec2<f32>) -> vec4<f32> {
    let st = vec2(uv.x, 1.0 - uv.y);
    if (wall.flags & 4u) != 0u {
        let size = vec2<i32>(textureDimensions(image));
        let texel = clamp(vec2<i32>(floor(st * vec2<f32>(size))), vec2(0), size - 1);
        return textureLoad(image, texel, 0);
    }
    return textureSampleLevel(image, smooth_sampler, st, 0.0);
}

@fragment
fn wall_fs(in: WallOut) -> @location(0) vec4<f32> {
    let has_left = (wall.flags & 1u) != 0u;
    let has_right = (wall.flags & 2u) != 0u;
    // A wall with one image (a mono wall, or the other eye not yet
    // rendered) shows it in every mode.
    if !has_left && !has_right {
        return vec4(0.08, 0.08, 0.1, 1.0);
    }
    var uv = in.uv;
    var use_left = has_left;
    switch wall.stereo {
        case 1u: {
            use_left = !has_right;
        }
        case 2u: {
            if has_left && has_right {
                let l = image_at(left_image, uv);
                let r = image_at(right_image, uv);
                return vec4(l.r, r.g, r.b, 1.0);
            }
        }
        case 3u: {
            if uv.x >= 0.5 {
                use_left = !has_right;
                uv.x = 2.0 * uv.x - 1.0;
            } else {
                use_left = has_left;
                uv.x = 2.0 * uv.x;
            }
        }
        default: {}
    }
    var c: vec4<f32>;
    if use_left {
        c = image_at(left_image, uv);
    } else {
        c = image_at(right_image, uv);
    }
    return vec4(c.rgb, 1.0);
}

struct Lines {
    clip: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> lines: Lines;

struct LineOut {
    @builtin(position) position: vec4<f32>,
    @location(0) color: vec4<f32>,
}

@vertex
fn line_vs(@location(0) p: vec3<f32>, @location(1) color: vec4<f32>) -> LineOut {
    var out: LineOut;
    out.position = lines.clip * vec4(p, 1.0);
    out.color = color;
    return out;
}

@fragment
fn line_fs(in: LineOut) -> @location(0) vec4<f32> {
    return in.color;
}

@group(0) @binding(0) var canvas: texture_2d<f32>;

@vertex
fn blit_vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32(i32(i & 1u) * 4 - 1);
    let y = f32(i32(i >> 1u) * 4 - 1);
    return vec4(x, y, 0.0, 1.0);
}

// Texel for pixel: the window shows the canvas exactly, as screenshots do.
@fragment
fn blit_fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<i32>(textureDimensions(canvas));
    let texel = clamp(vec2<i32>(p.xy), vec2(0), size - 1);
    return textureLoad(canvas, texel, 0);
}
