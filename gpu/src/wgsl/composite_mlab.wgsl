
@compute @workgroup_size(64)
fn composite(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = gid.y * composite_params.pitch + gid.x;
    let range = composite_range(p);
    if (range.x > range.y) {
        return;
    }
    var b: array<vec2<u32>, MLAB_M>;
    for (var j = 0u; j < MLAB_M; j++) {
        b[j] = select(composite_rows[composite_slot(p, j, MLAB_M)], MLAB_EMPTY_ROW, composite_params.first == 0u);
    }
    for (var i = range.x; i < range.y; i++) {
        let f = composite_fragment_at(i);
        mlab_insert(&b, f.row, f.h);
    }
    for (var j = 0u; j < MLAB_M; j++) {
        composite_rows[composite_slot(p, j, MLAB_M)] = b[j];
    }
}
