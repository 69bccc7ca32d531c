
@compute @workgroup_size(64)
fn composite(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = gid.y * composite_params.pitch + gid.x;
    if (p >= composite_params.pixels) {
        return;
    }
    var b: array<vec2<u32>, MLAB_M>;
    for (var j = 0u; j < MLAB_M; j++) {
        b[j] = MLAB_EMPTY_ROW;
    }
    let end = composite_offsets[p + 1u];
    for (var i = composite_offsets[p]; i < end; i++) {
        mlab_insert(&b, composite_row(i));
    }
    for (var j = 0u; j < MLAB_M; j++) {
        composite_rows[composite_slot(p, j, MLAB_M)] = b[j];
    }
}
