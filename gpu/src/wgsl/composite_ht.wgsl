
@compute @workgroup_size(64)
fn composite(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = gid.y * composite_params.pitch + gid.x;
    let range = composite_range(p);
    if (range.x > range.y) {
        return;
    }
    var head: array<vec2<u32>, HT_K>;
    for (var j = 0u; j < HT_K; j++) {
        head[j] = select(composite_rows[composite_slot(p, j, HT_K + 1u)], MLAB_EMPTY_ROW, composite_params.first == 0u);
    }
    var tail = select(composite_rows[composite_slot(p, HT_K, HT_K + 1u)], MLAB_EMPTY_TAIL, composite_params.first == 0u);
    for (var i = range.x; i < range.y; i++) {
        ht_insert(&head, &tail, composite_fragment_at(i).row);
    }
    for (var j = 0u; j < HT_K; j++) {
        composite_rows[composite_slot(p, j, HT_K + 1u)] = head[j];
    }
    composite_rows[composite_slot(p, HT_K, HT_K + 1u)] = tail;
}
