
@compute @workgroup_size(64)
fn composite(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = gid.y * composite_params.pitch + gid.x;
    if (p >= composite_params.pixels) {
        return;
    }
    var head: array<vec2<u32>, HT_K>;
    for (var j = 0u; j < HT_K; j++) {
        head[j] = MLAB_EMPTY_ROW;
    }
    var tail = MLAB_EMPTY_TAIL;
    let end = composite_offsets[p + 1u];
    for (var i = composite_offsets[p]; i < end; i++) {
        ht_insert(&head, &tail, composite_row(i));
    }
    for (var j = 0u; j < HT_K; j++) {
        composite_rows[composite_slot(p, j, HT_K + 1u)] = head[j];
    }
    composite_rows[composite_slot(p, HT_K, HT_K + 1u)] = tail;
}
