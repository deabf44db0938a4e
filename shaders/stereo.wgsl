// What the re-projection and compositing passes share (docs/reprojection_stereo.md).
// Left column x writes its right-eye segments into layer
// L - (x mod L) - 1; right pixel j reads, front to back, the columns
// j - near .. j - far, of which there are at most L, so no two columns it
// reads share a layer.

struct Stereo {
    // Right-eye pixel x of world point p: dot(right_x, p1) / dot(right_w, p1).
    right_x: vec4f,
    right_w: vec4f,
    // x: nearest offset (right pixel minus left column, in whole pixels),
    // y: farthest offset, z: layers, w: first left column cast.
    offsets: vec4i,
    // x, y: image size; z: left columns cast; w: colour format.
    size: vec4u,
    // Straight RGBA behind the volume.
    background: vec4f,
    // x: opacity at which a right pixel stops compositing.
    termination: vec4f,
}

fn layer_of(column: i32) -> i32 {
    let n = stereo.offsets.z;
    return n - 1 - (((column % n) + n) % n);
}

// Right-eye pixels column `column` wrote, as [first, last]; first > last
// if none. Texels outside that span hold stale data from earlier frames
// and are never read, which is what spares the layers a clear.
fn span_index(column: i32, row: u32) -> u32 {
    return row * stereo.size.z + u32(column - stereo.offsets.w);
}
