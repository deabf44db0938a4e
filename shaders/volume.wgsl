// #import constants, volume_bindings, cells, amr, nanovdb
// Emission-absorption volume ray casting: the march along one primary ray.
// Mirrors src/render/cpu/ (the reference) operation for operation, so the
// two agree to rounding; all derived numbers arrive in `params`. Its
// struct `RayUniforms` and the constants (SHADE_, TABLE_SIZE, ...) are
// generated from src/render/gpu/uniforms.rs, which documents the fields;
// the bindings (`params`, `volume0`, `table`, ...) from the ray caster's
// table in src/render/gpu/raycast.rs.
// Entry points live in raycast.wgsl, capture.wgsl and reproject.wgsl; each
// defines `on_sample(p, t, lit, a)`, which sees every sample that
// contributes, at p = o + t d along its ray (the re-projection path splits
// the ray into right-eye segments there), and `surface_pass(p, d, reach)`,
// the light the first surface within `reach` of p along d lets through
// (1: none there), which shadow and AO rays meet.

// Filtered sampling (RenderSettings::sampling): one hardware-filtered fetch
// per volume sample, and for primary samples one filtered fetch of the
// table row whose opacities are already corrected for a full step
// (table rows MAX_VOLUMES + v). A second pipeline sets it; the stereo
// passes keep the exact path.
override FILTERED: bool = false;
// Set where the scene has one volume: every loop over the volumes runs
// once and every switch over them takes volume 0, which the compiler can
// then see (software Vulkan runs the general form several times slower).
override ONE_VOLUME: bool = false;
// Set where a volume of the scene is paged (read through its page table
// from a pool of bricks, src/render/gpu/paging.rs): without it the
// compiler drops the page arithmetic, whose mere presence halves the
// march's speed on software Vulkan.
override PAGED: bool = false;

fn volume_count() -> u32 {
    if ONE_VOLUME {
        return 1u;
    }
    return params.volume_count;
}

// What lies behind pixel `pixel` of the frame: the flat color, or the
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

// The field's value of what volume v's texture holds, interpolated or
// not: the texture holds the stored numbers (normalised where they are
// integers), the slot the map back. Linear, so it is applied once a
// sample, after interpolation, as the reference does.
fn value_of(v: u32, t: f32) -> f32 {
    return t * params.volumes[v].texel_scale + params.volumes[v].texel_offset;
}

// Volume v's texel i, as stored.
fn voxel(v: u32, i: vec3i) -> f32 {
    if ONE_VOLUME {
        return textureLoad(volume0, i, 0).r;
    }
    switch v {
        case 0u: { return textureLoad(volume0, i, 0).r; }
        case 1u: { return textureLoad(volume1, i, 0).r; }
        case 2u: { return textureLoad(volume2, i, 0).r; }
        case 3u: { return textureLoad(volume3, i, 0).r; }
        case 4u: { return textureLoad(volume4, i, 0).r; }
        case 5u: { return textureLoad(volume5, i, 0).r; }
        case 6u: { return textureLoad(volume6, i, 0).r; }
        default: { return textureLoad(volume7, i, 0).r; }
    }
}

fn is_paged(v: u32) -> bool {
    return PAGED && params.volumes[v].levels != 0u;
}

// Voxels of level l of volume v's chain per axis: level l halves level
// l - 1, rounding up.
fn level_dims(v: u32, l: u32) -> vec3u {
    return max((params.volumes[v].dims + vec3u((1u << l) - 1u)) >> vec3u(l), vec3u(1u));
}

// Where a paged volume's sample is read: at grid point g of level
// `level` (the level's voxel i is the full-detail point (i + 0.5) 2^l -
// 0.5), the low corner i0 of its trilinear cell, the level's last voxel
// hi, and what to add to the level's voxel indices to address the pool:
// the cell lies in the brick of its low corner, whose texels reach one
// voxel past its side.
struct Page {
    g: vec3f,
    i0: vec3i,
    hi: vec3i,
    at: vec3i,
}

fn page_cell(v: u32, grid: vec3f, l: u32) -> Page {
    let hi = vec3i(level_dims(v, l)) - 1;
    var q = grid;
    if l > 0u {
        q = (grid + 0.5) / f32(1u << l) - 0.5;
    }
    let g = clamp(q, vec3f(0.0), vec3f(hi));
    let i0 = min(vec3i(floor(g)), max(hi - 1, vec3i(0)));
    return Page(g, i0, hi, vec3i(0));
}

// Volume v's page entry for the brick holding cell `c` of level l: its
// pool slot + 1, or 0 where it is not resident.
fn page_entry(v: u32, l: u32, c: Page) -> u32 {
    let m = params.volumes[v];
    let side = vec3u(m.brick_side);
    let b = vec3u(c.i0) / side;
    let n = (vec3u(c.hi + 1) + side - 1u) / side;
    return pages[m.page_offset + pages[m.page_offset + l] + b.x + n.x * (b.y + n.y * b.z)];
}

// Grid point `grid` of paged volume v at level `level`, or at the nearest
// coarser level whose brick there is resident (the coarsest always is).
fn page_of(v: u32, grid: vec3f, level: u32) -> Page {
    let m = params.volumes[v];
    var l = min(level, m.levels - 1u);
    var c = page_cell(v, grid, l);
    var e = page_entry(v, l, c);
    while e == 0u && l + 1u < m.levels {
        l += 1u;
        c = page_cell(v, grid, l);
        e = page_entry(v, l, c);
    }
    let side = vec3i(m.brick_side);
    let texels = side + select(vec3i(0), vec3i(1), vec3i(m.dims) > side);
    let a = vec2i(m.atlas_bricks);
    let k = i32(max(e, 1u) - 1u);
    let place = vec3i(k % a.x, (k / a.x) % a.y, k / (a.x * a.y));
    c.at = place * texels - (c.i0 / side) * side;
    return c;
}

// Grid coordinates of world point p in volume v.
fn grid_of(v: u32, p: vec3f) -> vec3f {
    let m = params.volumes[v];
    let q = vec4f(p, 1.0);
    return vec3f(dot(m.world_to_grid_x, q), dot(m.world_to_grid_y, q), dot(m.world_to_grid_z, q));
}

fn grid_direction(v: u32, d: vec3f) -> vec3f {
    let m = params.volumes[v];
    return vec3f(dot(m.world_to_grid_x.xyz, d), dot(m.world_to_grid_y.xyz, d), dot(m.world_to_grid_z.xyz, d));
}

fn last_vertex(v: u32) -> vec3f {
    return vec3f(params.volumes[v].dims - vec3u(1u));
}

fn contains(v: u32, g: vec3f) -> bool {
    return all(g >= vec3f(0.0)) && all(g <= last_vertex(v));
}

// Volume v at grid point g by the texture unit (vertex i is texel centre
// i), from mip level `level` (0: full detail), or for a paged volume from
// the level of its chain the page table gives for the whole level.
fn filtered_value(v: u32, grid: vec3f, level: f32) -> f32 {
    if is_paged(v) {
        let p = page_of(v, grid, u32(level));
        let c = (p.g + vec3f(p.at) + 0.5) / vec3f(volume_size(v));
        return value_of(v, texture_value(v, linear, c, 0.0));
    }
    let n = vec3f(params.volumes[v].dims);
    let c = (clamp(grid, vec3f(0.0), n - 1.0) + 0.5) / n;
    var t: f32;
    if level <= 0.0 {
        t = texture_value(v, linear, c, 0.0);
    } else {
        t = texture_value(v, linear_mips, c, level);
    }
    return value_of(v, t);
}

fn volume_size(v: u32) -> vec3u {
    if ONE_VOLUME {
        return textureDimensions(volume0);
    }
    switch v {
        case 0u: { return textureDimensions(volume0); }
        case 1u: { return textureDimensions(volume1); }
        case 2u: { return textureDimensions(volume2); }
        case 3u: { return textureDimensions(volume3); }
        case 4u: { return textureDimensions(volume4); }
        case 5u: { return textureDimensions(volume5); }
        case 6u: { return textureDimensions(volume6); }
        default: { return textureDimensions(volume7); }
    }
}

// Volume v's texture at normalised coordinates c through sampler s.
fn texture_value(v: u32, s: sampler, c: vec3f, level: f32) -> f32 {
    if ONE_VOLUME {
        return textureSampleLevel(volume0, s, c, level).r;
    }
    switch v {
        case 0u: { return textureSampleLevel(volume0, s, c, level).r; }
        case 1u: { return textureSampleLevel(volume1, s, c, level).r; }
        case 2u: { return textureSampleLevel(volume2, s, c, level).r; }
        case 3u: { return textureSampleLevel(volume3, s, c, level).r; }
        case 4u: { return textureSampleLevel(volume4, s, c, level).r; }
        case 5u: { return textureSampleLevel(volume5, s, c, level).r; }
        case 6u: { return textureSampleLevel(volume6, s, c, level).r; }
        default: { return textureSampleLevel(volume7, s, c, level).r; }
    }
}

// The mip level a primary sample t along its ray reads under level of
// detail: where a pixel's footprint grows past 1 / lod voxels, one level
// per doubling.
fn lod_level(t: f32) -> f32 {
    let footprint = params.ray_width + t * params.ray_spread;
    let level = log2(max(params.lod * footprint / params.shading_step, 1.0));
    return min(level, f32(LOD_LEVELS - 1u));
}

// sample_volume for the samples of the ray being marched (mesh_begin),
// at p, t along it.
fn sample_along(v: u32, p: vec3f, t: f32) -> f32 {
    if MESHES && params.volumes[v].sampling == FILTER_CELLS {
        samples += 1u;
        return mesh_value_along(v, grid_of(v, p), t);
    }
    return sample_volume(v, grid_of(v, p));
}

// Trilinear interpolation of the vertex-centred grid, by hand: R32Float
// is not filterable everywhere, and the reference does the same (filtered
// sampling leaves it to the texture unit). Or the nearest vertex, halves
// rounded up as the reference rounds them.
fn sample_volume(v: u32, grid: vec3f) -> f32 {
    samples += 1u;
    if MESHES && params.volumes[v].sampling == FILTER_CELLS {
        return mesh_value(v, grid);
    }
    if AMR && params.volumes[v].sampling == FILTER_AMR {
        return amr_value(v, grid);
    }
    if VDB && params.volumes[v].sampling == FILTER_VDB {
        return vdb_value(v, grid);
    }
    if FILTERED && params.volumes[v].sampling != FILTER_NEAREST {
        return filtered_value(v, grid, 0.0);
    }
    var p: Page;
    if is_paged(v) {
        p = page_of(v, grid, 0u);
    } else {
        p = page_cell(v, grid, 0u);
    }
    if params.volumes[v].sampling == FILTER_NEAREST {
        let i = min(vec3i(floor(p.g + vec3f(0.5))), p.hi);
        return value_of(v, voxel(v, i + p.at));
    }
    let f = p.g - vec3f(p.i0);
    let i0 = p.i0 + p.at;
    let i1 = min(p.i0 + vec3i(1), p.hi) + p.at;
    let x00 = mix(voxel(v, vec3i(i0.x, i0.y, i0.z)), voxel(v, vec3i(i1.x, i0.y, i0.z)), f.x);
    let x10 = mix(voxel(v, vec3i(i0.x, i1.y, i0.z)), voxel(v, vec3i(i1.x, i1.y, i0.z)), f.x);
    let x01 = mix(voxel(v, vec3i(i0.x, i0.y, i1.z)), voxel(v, vec3i(i1.x, i0.y, i1.z)), f.x);
    let x11 = mix(voxel(v, vec3i(i0.x, i1.y, i1.z)), voxel(v, vec3i(i1.x, i1.y, i1.z)), f.x);
    return value_of(v, mix(mix(x00, x10, f.y), mix(x01, x11, f.y), f.z));
}

fn classify(v: u32, value: f32) -> vec4f {
    if (MESHES || AMR) && value <= MESH_OUTSIDE {
        return vec4f(0.0);
    }
    let m = params.volumes[v];
    let last = f32(TABLE_SIZE - 1u);
    let t = clamp((value - m.value_lo) * m.value_scale, 0.0, 1.0) * last;
    let i = min(u32(t), TABLE_SIZE - 2u);
    let f = t - f32(i);
    let a = textureLoad(table, vec2i(i32(i), i32(v)), 0);
    let b = textureLoad(table, vec2i(i32(i) + 1, i32(v)), 0);
    return a * (1.0 - f) + b * f;
}

// A primary sample's color and opacity: under filtered sampling from the
// stepped table by the texture unit, its opacity already a full step's.
fn classify_step(v: u32, value: f32) -> vec4f {
    if !FILTERED || ((MESHES || AMR) && value <= MESH_OUTSIDE) {
        return classify(v, value);
    }
    let m = params.volumes[v];
    let t = clamp((value - m.value_lo) * m.value_scale, 0.0, 1.0);
    let x = (t * f32(TABLE_SIZE - 1u) + 0.5) / f32(TABLE_SIZE);
    let y = (f32(MAX_VOLUMES + v) + 0.5) / f32(2u * MAX_VOLUMES);
    return textureSampleLevel(table, linear, vec2f(x, y), 0.0);
}

// The opacity of a primary segment `seg` long: the table's, corrected;
// under filtered sampling, already a full step's (re-corrected only for
// the last, shorter segment).
fn segment_opacity(v: u32, a: f32, seg: f32) -> f32 {
    if FILTERED {
        if seg == params.step {
            return a;
        }
        return correct(a, seg / params.step);
    }
    return correct(a, seg * params.volumes[v].inv_unit_distance);
}

// Overlapping volumes at one sample as one medium, as the reference's
// Mixture: opacities combine as independent absorbers, colors in
// proportion to opacity, whatever the volumes' order.
struct Mixture {
    emitted: vec3f,
    weight: f32,
    alpha: f32,
}

fn mixture_add(m: ptr<function, Mixture>, rgb: vec3f, a: f32) {
    (*m).emitted += rgb * a;
    (*m).weight += a;
    (*m).alpha += (1.0 - (*m).alpha) * a;
}

fn inside(p: vec3f) -> bool {
    for (var v = 0u; v < volume_count(); v++) {
        if contains(v, grid_of(v, p)) {
            return true;
        }
    }
    return false;
}

// The mixed opacity at p, each volume's corrected to a segment `length`
// long, or as the table gives it where `per_unit`.
fn opacity_at(p: vec3f, length: f32, per_unit: bool) -> f32 {
    var m = Mixture(vec3f(0.0), 0.0, 0.0);
    for (var v = 0u; v < volume_count(); v++) {
        let g = grid_of(v, p);
        if !contains(v, g) {
            continue;
        }
        var a = classify(v, sample_volume(v, g)).a;
        if !per_unit {
            a = correct(a, length * params.volumes[v].inv_unit_distance);
        }
        mixture_add(&m, vec3f(0.0), a);
    }
    return m.alpha;
}

fn correct(a: f32, exponent: f32) -> f32 {
    if a >= 1.0 {
        return 1.0;
    }
    return 1.0 - pow(1.0 - a, exponent);
}

fn transmittance(p: vec3f, dir: vec3f, steps: u32) -> f32 {
    var t = 1.0;
    for (var k = 1u; k <= steps; k++) {
        let q = p + dir * (params.shading_step * f32(k));
        if !inside(q) {
            break;
        }
        t *= 1.0 - opacity_at(q, params.shading_step, false);
    }
    return t;
}

// The light factor of the sample at p under the shading mode: every
// shading ray (the shadow ray, then the AO rays, or the directional
// rays) in one loop, so that the surfaces' traversal, which each ray
// begins with, is compiled once (software Vulkan inlines every call).
fn shade(p: vec3f) -> f32 {
    let n = params.direction_count;
    var shadow_rays = 0u;
    var ao_rays = 0u;
    var steps = DIRECTIONAL_STEPS;
    switch params.shading {
        case SHADE_SHADOWS: {
            shadow_rays = 1u;
        }
        case SHADE_AO: {
            ao_rays = n;
        }
        case SHADE_SHADOWS_AO: {
            shadow_rays = 1u;
            ao_rays = n;
        }
        case SHADE_DIRECTIONAL: {}
        default: {
            return 1.0;
        }
    }
    let directional = params.shading == SHADE_DIRECTIONAL;
    let rays = select(shadow_rays + ao_rays, n, directional);
    if rays == 0u {
        return 1.0;
    }
    var shadowed = 1.0;
    var occluded = 0.0;
    var sum = 0.0;
    for (var r = 0u; r < rays; r++) {
        let ao = !directional && r >= shadow_rays;
        var d = directions[select(r, r - shadow_rays, ao)].xyz;
        var reach = params.ao_radius;
        if !ao {
            if !directional {
                d = params.light;
                steps = SHADOW_STEPS;
            }
            reach = params.shading_step * f32(steps);
        }
        let passed = surface_pass(p, d, reach);
        if ao {
            occluded += (1.0 - passed) + passed * opacity_at(p + d * params.ao_radius, 0.0, true);
            continue;
        }
        var t = 0.0;
        if passed > 0.0 {
            t = passed * transmittance(p, d, steps);
        }
        if directional {
            sum += t;
        } else {
            shadowed = SHADOW_AMBIENT + (1.0 - SHADOW_AMBIENT) * t;
        }
    }
    if directional {
        return sum / f32(n);
    }
    return shadowed * select(1.0, 1.0 - occluded / f32(ao_rays), ao_rays > 0u);
}

fn safe_inverse(x: f32) -> f32 {
    if abs(x) < 1e-20 {
        return 1.0 / select(1e-20, -1e-20, x < 0.0);
    }
    return 1.0 / x;
}

// The stretch of volume v's grid around grid point g whose state the
// bricks know, as EmptySpace::region: x 1 where clear (0: could show), y
// how far (in t) a ray with grid direction gd stays in it.
fn brick_region(v: u32, g: vec3f, gd: vec3f) -> vec2f {
    let m = params.volumes[v];
    let hi = vec3i(m.dims) - vec3i(1);
    // Truncation is floor for the clamped, non-negative g.
    let cell = min(vec3i(clamp(g, vec3f(0.0), vec3f(hi))), max(hi - vec3i(1), vec3i(0)));
    let b = cell / i32(BRICK);
    let n = vec3i(m.bricks);
    let d = i32(bricks[m.brick_offset + u32(b.x + n.x * (b.y + n.y * b.z))]);
    let r = max(d - 1, 0);
    let lo = vec3f((b - vec3i(r)) * i32(BRICK));
    let up = vec3f((b + vec3i(r + 1)) * i32(BRICK));
    // Margins shorten a leap and lengthen a stretch to sample, as
    // EmptySpace::region explains.
    var clear = bitcast<f32>(0x7f800000u);
    var busy = clear;
    for (var k = 0; k < 3; k++) {
        var room: f32;
        if gd[k] > 0.0 {
            room = (up[k] - g[k]) / gd[k];
        } else if gd[k] < 0.0 {
            room = (g[k] - lo[k]) / -gd[k];
        } else {
            continue;
        }
        let margin = LEAP_MARGIN / abs(gd[k]);
        clear = min(clear, room - margin);
        busy = min(busy, room + margin);
    }
    if d > 0 {
        return vec2f(1.0, max(clear, 0.0));
    }
    return vec2f(0.0, busy);
}

// What the primary ray o + t d meets from its sample at p (t along it), as
// Field::region: x 1 where every volume is clear (leap), 0 where one could
// show (sample), y for how long.
fn region(spans: ptr<function, array<vec2f, MAX_VOLUMES>>, p: vec3f, d: vec3f, t: f32) -> vec2f {
    var clear = bitcast<f32>(0x7f800000u);
    var busy = clear;
    for (var v = 0u; v < volume_count(); v++) {
        let span = (*spans)[v];
        if span.y <= span.x || t > span.y {
            continue;
        }
        if t < span.x {
            clear = min(clear, span.x - t);
            continue;
        }
        let r = brick_region(v, grid_of(v, p), grid_direction(v, d));
        if r.x > 0.0 {
            clear = min(clear, r.y);
        } else {
            busy = min(busy, r.y);
        }
    }
    if busy < bitcast<f32>(0x7f800000u) {
        return vec2f(0.0, busy);
    }
    return vec2f(1.0, clear);
}

// A primary ray o + t d, d of unit length.
struct Ray {
    o: vec3f,
    d: vec3f,
}

// The ray of pixel (fx, fy); columns outside the image are allowed.
// The ray of pixel (fx, fy) from the ray of pixel (0, 0) and its change
// per pixel (RayGen), for either eye.
fn ray_through(fx: f32, fy: f32, o: vec3f, o_dx: vec3f, o_dy: vec3f, d: vec3f, d_dx: vec3f, d_dy: vec3f) -> Ray {
    return Ray(o + fx * o_dx + fy * o_dy, normalize(d + fx * d_dx + fy * d_dy));
}

fn primary_ray(fx: f32, fy: f32) -> Ray {
    return ray_through(fx, fy, params.ray_origin, params.ray_origin_dx, params.ray_origin_dy, params.ray_dir, params.ray_dir_dx, params.ray_dir_dy);
}

// What one ray gathered.
struct Marched {
    // Premultiplied color and opacity accumulated front to back.
    color: vec4f,
    // Distance along the unit ray to the first contributing sample.
    depth: f32,
}

// Where the ray o + t d enters and leaves the box [lo, hi], clipped to
// (near, far): (t0, t1), empty unless t1 > t0.
fn enter_exit(o: vec3f, d: vec3f, lo: vec3f, hi: vec3f, near: f32, far: f32) -> vec2f {
    let inv = vec3f(safe_inverse(d.x), safe_inverse(d.y), safe_inverse(d.z));
    let ta = (lo - o) * inv;
    let tb = (hi - o) * inv;
    let tn = min(ta, tb);
    let tf = max(ta, tb);
    return vec2f(max(max(max(tn.x, tn.y), tn.z), near), min(min(min(tf.x, tf.y), tf.z), far));
}

// Under data-parallel rendering: the ray o + t d in the parts' frame.
fn part_frame(o: vec3f, d: vec3f) -> array<vec3f, 2> {
    let q = vec4f(o, 1.0);
    return array<vec3f, 2>(
        vec3f(dot(params.part_x, q), dot(params.part_y, q), dot(params.part_z, q)),
        vec3f(dot(params.part_x.xyz, d), dot(params.part_y.xyz, d), dot(params.part_z.xyz, d)),
    );
}

// Where step k of a march from t0 over len is sampled, as
// march_plan::sample_t: the parts split the steps by it.
fn part_sample_t(t0: f32, len: f32, step: f32, k: u32) -> f32 {
    let start = f32(k) * step;
    return t0 + start + 0.5 * max(min(step, len - start), 0.0);
}

// The first of the n steps sampled at or beyond r.
fn part_first_at(r: f32, t0: f32, len: f32, n: u32, step: f32) -> u32 {
    var k = min(u32(clamp(ceil((r - t0) / step - 0.5), 0.0, f32(n))), n);
    while k > 0u && part_sample_t(t0, len, step, k - 1u) >= r {
        k--;
    }
    while k < n && part_sample_t(t0, len, step, k) < r {
        k++;
    }
    return k;
}

fn march(ray: Ray) -> Marched {
    return march_segment(ray, params.t_near, params.t_far, Marched(vec4f(0.0), bitcast<f32>(0x7f800000u)));
}

// The march of the stretch (start, stop) of the ray, composited behind
// what `carried` holds (a translucent surface's segments follow one
// another), as march::march_segment.
fn march_segment(ray: Ray, start: f32, stop: f32, carried: Marched) -> Marched {
    let o = ray.o;
    let d = ray.d;
    if carried.color.a >= params.termination {
        return carried;
    }
    let near = max(start, params.t_near);
    let far = min(stop, params.t_far);

    let step = params.step;
    var acc = carried.color;
    var depth = carried.depth;

    // Each volume's span along the ray, found in its grid (the affine map
    // keeps t), and their union, which the march covers.
    var spans: array<vec2f, MAX_VOLUMES>;
    var t0 = bitcast<f32>(0x7f800000u);
    var t1 = -t0;
    for (var v = 0u; v < volume_count(); v++) {
        spans[v] = enter_exit(grid_of(v, o), grid_direction(v, d), vec3f(0.0), last_vertex(v), near, far);
        if MESHES && params.volumes[v].sampling == FILTER_CELLS {
            mesh_begin(v, o, d);
        }
        if spans[v].y > spans[v].x {
            t0 = min(t0, spans[v].x);
            t1 = max(t1, spans[v].y);
        }
    }
    // A data-parallel part lays its steps along the whole's span.
    var owned = vec2f(0.0);
    if params.has_part != 0u {
        let f = part_frame(o, d);
        let whole = enter_exit(f[0], f[1], params.whole_lo, params.whole_hi, near, far);
        t0 = whole.x;
        t1 = whole.y;
        owned = enter_exit(f[0], f[1], params.owned_lo, params.owned_hi, -bitcast<f32>(0x7f800000u), bitcast<f32>(0x7f800000u));
    }
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
    if FILTERED && params.lod > 0.0 && t1 > t0 {
        // Steps that lengthen with the level are not split by sample: a
        // part marches its own stretch.
        if params.has_part != 0u {
            return march_lod(o, d, &spans, max(t0, owned.x), min(t1, owned.y), carried);
        }
        return march_lod(o, d, &spans, t0, t1, carried);
    }
    if t1 > t0 {
        let len = t1 - t0;
        // f32 to u32 saturates; the cap holds where t has lost its precision.
        var n = u32(ceil(len / step));
        var k = 0u;
        if params.has_part != 0u && owned.y > owned.x {
            let first = part_first_at(owned.x, t0, len, n, step);
            n = max(part_first_at(owned.y, t0, len, n, step), first);
            k = first;
        } else if params.has_part != 0u {
            n = 0u;
        }
        n = min(n, k + min(params.max_steps, 0xffffffffu - k));
        // Up to here, the last look at the bricks said some could show.
        var busy_until = -bitcast<f32>(0x7f800000u);
        while k < n {
            let start = f32(k) * step;
            k++;
            let seg = max(min(step, len - start), 0.0);
            let t = t0 + start + 0.5 * seg;
            let p = o + d * t;
            if params.skipping != 0u && t >= busy_until {
                let r = region(&spans, p, d, t);
                if r.x > 0.0 {
                    // Samples up to t + r.y are clear: go on from the last
                    // one at or before it (an endless leap ends the ray).
                    let last_clear = min(floor((t + r.y - t0) / step - 0.5), f32(n));
                    k = max(k, u32(last_clear));
                    continue;
                }
                busy_until = t + r.y;
            }
            var m = Mixture(vec3f(0.0), 0.0, 0.0);
            for (var v = 0u; v < volume_count(); v++) {
                let span = spans[v];
                if span.y <= span.x || t < span.x || t > span.y {
                    continue;
                }
                let c = classify_step(v, sample_along(v, p, t));
                if c.a > 0.0 {
                    mixture_add(&m, c.rgb, segment_opacity(v, c.a, seg));
                }
            }
            if m.weight <= 0.0 {
                continue;
            }
            if composite(&acc, &depth, m, p, t) {
                break;
            }
        }
    }
    return Marched(acc, depth);
}

// The depth of point p, t along its ray, as RayGen::depth_at measures it.
fn depth_along(p: vec3f, t: f32) -> f32 {
    if params.has_eye != 0u {
        return length(p - params.eye);
    }
    return t;
}

// Shades the mixture m sampled at p, t along the ray, and composites it
// behind `acc` front to back, taking the depth where the opacity first
// reaches the depth threshold; true once the ray may stop.
fn composite(acc: ptr<function, vec4f>, depth: ptr<function, f32>, m: Mixture, p: vec3f, t: f32) -> bool {
    let lit = m.emitted / m.weight * shade(p) * params.light_color;
    let a = m.alpha;
    on_sample(p, t, lit, a);
    let weight = (1.0 - (*acc).a) * a;
    *acc = vec4f((*acc).rgb + lit * weight, (*acc).a + weight);
    if *depth == bitcast<f32>(0x7f800000u) && (*acc).a >= params.depth_threshold {
        *depth = depth_along(p, t);
    }
    return (*acc).a >= params.termination;
}

// The march under level of detail (filtered sampling only): segment
// lengths step * 2^level grow with the level the ray's footprint asks for,
// volumes are read from that mip level, opacities are the stepped table's
// re-corrected for each segment's length, and leaps end where the bricks'
// clear region does. An approximation of the full-detail march, whose
// cost `bench raycast --lod` measures by SSIM.
fn march_lod(
    o: vec3f,
    d: vec3f,
    spans: ptr<function, array<vec2f, MAX_VOLUMES>>,
    t0: f32,
    t1: f32,
    carried: Marched,
) -> Marched {
    var acc = carried.color;
    var depth = carried.depth;
    var busy_until = -bitcast<f32>(0x7f800000u);
    var t = t0;
    for (var k = 0u; k < params.max_steps && t < t1; k++) {
        let level = lod_level(t);
        let seg = min(params.step * exp2(level), t1 - t);
        let tm = t + 0.5 * seg;
        t += seg;
        let p = o + d * tm;
        if params.skipping != 0u && tm >= busy_until {
            let r = region(spans, p, d, tm);
            if r.x > 0.0 {
                t = max(t, tm + r.y);
                continue;
            }
            busy_until = tm + r.y;
        }
        var m = Mixture(vec3f(0.0), 0.0, 0.0);
        for (var v = 0u; v < volume_count(); v++) {
            let span = (*spans)[v];
            if span.y <= span.x || tm < span.x || tm > span.y {
                continue;
            }
            let g = grid_of(v, p);
            var value: f32;
            if params.volumes[v].sampling != FILTER_LINEAR {
                value = sample_volume(v, g);
            } else {
                samples += 1u;
                value = filtered_value(v, g, level);
            }
            let c = classify_step(v, value);
            if c.a > 0.0 {
                mixture_add(&m, c.rgb, correct(c.a, seg / params.step));
            }
        }
        if m.weight <= 0.0 {
            continue;
        }
        if composite(&acc, &depth, m, p, tm) {
            break;
        }
    }
    return Marched(acc, depth);
}
