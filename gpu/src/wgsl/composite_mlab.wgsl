
// MLAB's composite_pixel: the MLAB_M rows, each fragment inserted by Listing 1 (mlab_insert).
fn composite_pixel(p: u32, range: vec2<u32>) {
    var b: array<vec2<u32>, MLAB_M>;
    for (var j = 0u; j < MLAB_M; j++) {
        b[j] = composite_load(p, j, MLAB_M, MLAB_EMPTY_ROW);
    }
    for (var i = range.x; i < range.y; i++) {
        let f = composite_fragment_at(i);
        mlab_insert(&b, f.row, f.h);
    }
    for (var j = 0u; j < MLAB_M; j++) {
        composite_rows[composite_slot(p, j, MLAB_M)] = b[j];
    }
}
