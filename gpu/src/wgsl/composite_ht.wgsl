
@compute @workgroup_size(64)
fn composite(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = gid.y * composite_params.pitch + gid.x;
    if (p >= composite_params.pixels) {
        return;
    }
    let start = composite_offsets[p] + composite_params.first;
    let end = min(composite_offsets[p + 1u], start + COMPOSITE_CHUNK);
    if (composite_params.first != 0u && start >= end) {
        return; // this pixel had no more than `first` fragments: its rows are final
    }
    var head: array<vec2<u32>, HT_K>;
    for (var j = 0u; j < HT_K; j++) {
        head[j] = select(composite_rows[composite_slot(p, j, HT_K + 1u)], MLAB_EMPTY_ROW, composite_params.first == 0u);
    }
    var tail = select(composite_rows[composite_slot(p, HT_K, HT_K + 1u)], MLAB_EMPTY_TAIL, composite_params.first == 0u);
    for (var i = start; i < end; i++) {
        ht_insert(&head, &tail, composite_row(i));
    }
    for (var j = 0u; j < HT_K; j++) {
        composite_rows[composite_slot(p, j, HT_K + 1u)] = head[j];
    }
    composite_rows[composite_slot(p, HT_K, HT_K + 1u)] = tail;
}
