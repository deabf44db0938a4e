// What the re-projection and compositing passes share (docs/reprojection_stereo.md).
// Left column x writes its right-eye segments into layer
// L - (x mod L) - 1; right pixel j reads, front to back, the columns
// j - near .. j - far, of which there are at most L, so no two columns it
// reads share a layer.

// `Stereo` is declared in front of this file from src/render/gpu/uniforms.rs,
// which documents its fields.

fn layer_of(column: i32) -> i32 {
    let n = stereo.layers;
    return n - 1 - (((column % n) + n) % n);
}

// Right-eye pixels column `column` wrote, as [first, last]; first > last
// if none. Texels outside that span hold stale data from earlier frames
// and are never read, which is what spares the layers a clear.
fn span_index(column: i32, row: u32) -> u32 {
    return row * stereo.columns + u32(column - stereo.first_column);
}
