// #import constants, band_bindings
// Which pixel an invocation of a banded pass shades. A band is dispatched
// as groups.x by groups.y workgroups of WORKGROUP^2 pixels from row
// band.x on. Software Vulkan (lavapipe) hands each of its threads one
// contiguous run of a dispatch's workgroups in their linear order, so the
// thread given the rows that cross the volume does most of the work;
// band.y, a stride coprime to the workgroup count, deals the run's
// workgroups over the whole band instead (1 keeps them in order).

fn band_pixel(group: vec3u, local: vec3u, groups: vec3u) -> vec2u {
    let tile = (group.y * groups.x + group.x) * band.y % (groups.x * groups.y);
    let at = vec2u(tile % groups.x, tile / groups.x) * WORKGROUP + local.xy;
    return vec2u(at.x, at.y + band.x);
}
