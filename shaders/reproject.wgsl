// #import volume, surface, color, stereo, reproject_bindings, band
// The left eye, ray cast over the image plus the pixels the right eye
// needs beyond its borders, writing each ray's right-eye segments into the
// re-projection layers, whose storage format is the binding table's.
// Surfaces are not re-projected: the composite ray traces the right
// eye's own (composite.wgsl). The left eye's image ends at its first
// opaque surface; the ray's segments go on behind it.

const NO_PIXEL: i32 = -2147483647;
const INFINITY: f32 = 3.4028235e38;

// Set where the plan uses both families of lines. Where it uses one, the
// state of a second stays out of the march: kept live across the loop,
// it costs software Vulkan about a quarter of the pass.
override BOTH_FAMILIES: bool = true;

// One family's open segment.
struct Open {
    // Whether this ray writes the family at all.
    on: bool,
    // The right pixel the segment is in, and the first the ray wrote.
    pixel: i32,
    first: i32,
    // +1 or -1: the way the right pixel moves as the ray goes deeper.
    dir: i32,
    // Premultiplied color.
    color: vec4f,
    // t along the left ray of the segment's first sample, and where its
    // own opacity reaches the depth threshold (INFINITY until then).
    // Right-eye distances are taken from t only where a segment is written.
    first_t: f32,
    crossed_t: f32,
    // The offsets (right minus left) the ray's samples may have.
    lo: f32,
    hi: f32,
    // The sample at t is (x + t y) / (z + t w) right pixels from the left
    // pixel along the family: the projection is linear in t before its
    // divide, so each sample pays one divide and two multiply-adds.
    line: vec4f,
}

var<private> left: vec2i;
// The ray's origin seen from the right eye, and its direction.
var<private> from_right: vec3f;
var<private> ray_d: vec3f;
// The t of the ray's last contributing sample: the end of every open
// segment.
var<private> last_t: f32;
// Columns, or the rows where they are the only family (`major_axis`); the
// rows where both are in use. Not an array: indexing private arrays by a
// variable sends them to memory on some compilers (lavapipe among them).
var<private> major: Open;
var<private> major_axis: u32;
var<private> rows: Open;

fn right_distance(t: f32) -> f32 {
    return length(from_right + ray_d * t);
}

// Writes a segment of the ray, from t.x to t.y, crossing the depth
// threshold at t.z, into right pixel `at` of family `axis`.
fn emit(axis: u32, at: i32, value: vec4f, t: vec3f) {
    let size = select(i32(stereo.width), i32(stereo.height), axis == 1u);
    if at < 0 || at >= size {
        return;
    }
    let texel = texel_of(left, at, axis);
    let layer = layer_of(left, axis);
    textureStore(layers, texel, layer, value);
    if stereo.segment_depths != 0u {
        let crossed = select(INFINITY, right_distance(t.z), t.z < INFINITY);
        textureStore(depths, texel, layer, vec4f(right_distance(t.x), right_distance(t.y), crossed, 0.0));
    }
}

fn advance(s: ptr<private, Open>, axis: u32, t: f32, lit: vec3f, a: f32) {
    if !(*s).on {
        return;
    }
    let line = (*s).line;
    // Clamped in float first: converting an out-of-range float is undefined.
    let offset = clamp((line.x + t * line.y) / (line.z + t * line.w), (*s).lo, (*s).hi);
    var pixel = along(left, axis) + i32(round(offset));
    let dir = (*s).dir;
    // The sample stands for the stretch of ray since the last one; where
    // that stretch crosses several right pixels (the volume near the
    // eyes), each gets the opacity of its share of the stretch rather
    // than one getting all and the others none.
    var share = a;
    if (*s).first == NO_PIXEL {
        (*s).first = pixel;
        (*s).pixel = pixel;
        (*s).first_t = t;
    } else {
        // Rounding noise must not step back into a written pixel.
        pixel = select(min(pixel, (*s).pixel), max(pixel, (*s).pixel), dir > 0);
        if pixel != (*s).pixel {
            emit(axis, (*s).pixel, (*s).color, vec3f((*s).first_t, last_t, (*s).crossed_t));
            let gap = abs(pixel - (*s).pixel);
            if gap > 1 {
                share = 1.0 - pow(1.0 - min(a, 1.0), 1.0 / f32(gap));
                // Every texel inside the span is this frame's: the pixels
                // stepped over get their share.
                let crossed = select(INFINITY, t, share >= stereo.depth_threshold);
                for (var k = 1; k < gap; k++) {
                    emit(axis, (*s).pixel + k * dir, vec4f(lit * share, share), vec3f(t, t, crossed));
                }
            }
            (*s).color = vec4f(0.0);
            (*s).first_t = t;
            (*s).crossed_t = INFINITY;
            (*s).pixel = pixel;
        }
    }
    // The same arithmetic as the left eye's accumulation, so a single
    // segment (e = 0) equals the left pixel exactly.
    let c = (*s).color;
    let weight = (1.0 - c.a) * share;
    (*s).color = vec4f(c.rgb + lit * weight, c.a + weight);
    if (*s).crossed_t == INFINITY && (*s).color.a >= stereo.depth_threshold {
        (*s).crossed_t = t;
    }
}

// As raycast.wgsl's: shadow and AO rays meet the surfaces.
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

fn on_sample(p: vec3f, t: f32, lit: vec3f, a: f32) {
    advance(&major, major_axis, t, lit, a);
    if BOTH_FAMILIES {
        advance(&rows, 1u, t, lit, a);
    }
    last_t = t;
}

// Right pixels a ray's path behind its opaque surface is checked at, at
// most: past them the march behind goes on unchecked.
const BEHIND_CHECKS: i32 = 64;

// Whether the right eye sees any point of `ray` behind t_s (its first
// opaque surface) before its own first opaque surface: checked where the
// path crosses each right pixel's centre along a family written.
fn seen_behind(ray: Ray, t_s: f32) -> bool {
    var s = major;
    if !s.on && BOTH_FAMILIES {
        s = rows;
    }
    if !s.on {
        return false;
    }
    let line = s.line;
    let end = select(s.lo, s.hi, s.dir > 0);
    var o = clamp(round((line.x + t_s * line.y) / (line.z + t_s * line.w)), s.lo, s.hi);
    for (var k = 0; k < BEHIND_CHECKS; k++) {
        if (s.dir > 0 && o > end) || (s.dir < 0 && o < end) {
            return false;
        }
        // Where the path's offset is o: linear in t before the divide.
        let t = (o * line.z - line.x) / (line.y - o * line.w);
        o += f32(s.dir);
        if !(t > t_s) || t > params.t_far {
            continue;
        }
        let x = vec4f(ray.o + ray.d * t, 1.0);
        let q = vec2i(round(vec2f(dot(stereo.right_x, x), dot(stereo.right_y, x)) / dot(stereo.right_w, x)));
        if any(q < vec2i(0)) || q.x >= i32(stereo.width) || q.y >= i32(stereo.height) {
            continue;
        }
        if abs(right_opaque[u32(q.y) * stereo.width + u32(q.x)].w) > length(x.xyz - stereo.right_eye) {
            return true;
        }
    }
    return true;
}

// Family `axis`'s segment state for the ray (o, d) of left pixel `left`.
fn open_family(axis: u32, o: vec3f, d: vec3f) -> Open {
    let g = g_of(left);
    let along_g = alongf(g, axis);
    let across_g = acrossf(g, axis);
    let near = round(stereo.lambda_near * along_g);
    let far = round(stereo.lambda_far * along_g);
    let spread = stereo.lambda_far - stereo.lambda_near;
    let row = select(stereo.right_x, stereo.right_y, axis == 1u);
    let own = f32(along(left, axis));
    let w = vec2f(dot(stereo.right_w, vec4f(o, 1.0)), dot(stereo.right_w.xyz, d));
    let x = vec2f(dot(row, vec4f(o, 1.0)), dot(row.xyz, d)) - own * w;
    return Open(
        (stereo.families & (1u << axis)) != 0u && abs(along_g) >= abs(across_g) - abs(stereo.epipole.z),
        NO_PIXEL,
        NO_PIXEL,
        select(-1, 1, spread * along_g >= 0.0),
        vec4f(0.0),
        INFINITY,
        INFINITY,
        min(near, far),
        max(near, far),
        vec4f(x, w),
    );
}

// Writes the family's last segment; the right coordinates the ray wrote,
// first > last if none.
fn close_family(s: ptr<private, Open>, axis: u32) -> vec2i {
    if !(*s).on || (*s).first == NO_PIXEL {
        return vec2i(1, 0);
    }
    emit(axis, (*s).pixel, (*s).color, vec3f((*s).first_t, last_t, (*s).crossed_t));
    return vec2i(min((*s).first, (*s).pixel), max((*s).first, (*s).pixel));
}

// The left ray's march among the surfaces (SURFACES only): up to each
// surface, a translucent one composited in its turn, the first opaque one
// ending it; the pass after the last looks at no surface. Behind the first
// opaque surface the ray marches on through the volumes alone
// (`behind_it`) where the right eye sees past it (near its edge): what the
// left eye does not see (disocclusion); its surfaces the right eye traces
// itself. One call of the march, which the compiler inlines at each.
// Returns what the ray gathered; `behind` and `surface_depth` get its
// first opaque surface's color and depth.
fn march_among_surfaces(ray: Ray, behind: ptr<function, vec4f>, surface_depth: ptr<function, f32>) -> Marched {
    var m = Marched(vec4f(0.0), infinite());
    var start = params.t_near;
    var composited = 0u;
    var behind_it = false;
    for (var looked = 0u; looked <= SURFACE_PASSES; looked++) {
        var hit = SurfaceHit(infinite(), NO_SLOT, vec2f(0.0));
        if looked < SURFACE_PASSES && !behind_it {
            hit = nearest_surface(ray.o, ray.d, start, params.t_far);
        }
        var carried = m;
        if behind_it {
            carried = Marched(vec4f(0.0), infinite());
        }
        let marched = march_segment(ray, start, hit.t, carried);
        if hit.slot == NO_SLOT {
            if !behind_it {
                m = marched;
            }
            break;
        }
        m = marched;
        let lit = surface_color(hit, ray.o, ray.d);
        let a = surface_alpha(hit);
        let p = ray.o + ray.d * hit.t;
        if a >= 1.0 {
            *behind = vec4f(lit, 1.0);
            *surface_depth = depth_along(p, hit.t);
            if m.color.a >= params.termination {
                break;
            }
            behind_it = seen_behind(ray, hit.t);
            if !behind_it {
                break;
            }
        } else if composited < MAX_TRANSLUCENT {
            _ = composite_surface(&m, lit, a, p, hit.t);
            composited++;
            if m.color.a >= params.termination {
                break;
            }
        }
        start = hit.t;
    }
    return m;
}

@compute @workgroup_size(WORKGROUP, WORKGROUP)
fn main(@builtin(workgroup_id) group: vec3u, @builtin(local_invocation_id) local: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let id = vec3u(band_pixel(group, local, groups), 0u);
    if id.x >= stereo.cast_pixels.x || id.y >= stereo.cast_pixels.y {
        return;
    }
    left = vec2i(id.xy) + stereo.first;
    let ray = primary_ray(f32(left.x), f32(left.y));
    from_right = ray.o - stereo.right_eye;
    ray_d = ray.d;
    major_axis = select(0u, 1u, stereo.families == 2u);
    major = open_family(major_axis, ray.o, ray.d);
    if BOTH_FAMILIES {
        rows = open_family(1u, ray.o, ray.d);
    }
    // The left eye's march as raycast.wgsl's, so that the left eye is the
    // image it renders alone.
    var m = Marched(vec4f(0.0), infinite());
    var behind = vec4f(0.0);
    var surface_depth = infinite();
    if SURFACES {
        m = march_among_surfaces(ray, &behind, &surface_depth);
    } else {
        m = march_segment(ray, params.t_near, infinite(), m);
    }
    let major_span = close_family(&major, major_axis);
    var span = select(vec4i(major_span, 1, 0), vec4i(1, 0, major_span), major_axis == 1u);
    if BOTH_FAMILIES {
        span = vec4i(span.xy, close_family(&rows, 1u));
    }
    spans[span_index(left)] = span;

    if left.x >= 0 && left.x < i32(stereo.width) && left.y >= 0 && left.y < i32(stereo.height) {
        let i = u32(left.y) * stereo.width + u32(left.x);
        depth_out[i] = min(m.depth, surface_depth);
        samples_out[i * params.pixel_words] = samples;
        if surface_depth == infinite() {
            behind = background_at(vec2u(left));
        }
        store_color(i, over(m.color, behind), params.color_format);
    }
}

// Zeroes every texel: what the span scheme avoids, kept to measure it.
@compute @workgroup_size(WORKGROUP, WORKGROUP, 1)
fn clear(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(layers);
    if id.x >= size.x || id.y >= size.y || id.z >= textureNumLayers(layers) {
        return;
    }
    textureStore(layers, vec2u(id.xy), id.z, vec4f(0.0));
}
