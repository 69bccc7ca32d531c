
// HT's composite_pixel: the HT_K head rows (slots 0 .. HT_K) and the tail (slot HT_K), each
// fragment inserted by Listing 2 (ht_insert).
fn composite_pixel(p: u32, range: vec2<u32>) {
    var head: array<vec2<u32>, HT_K>;
    for (var j = 0u; j < HT_K; j++) {
        head[j] = composite_load(p, j, HT_K + 1u, MLAB_EMPTY_ROW);
    }
    var tail = composite_load(p, HT_K, HT_K + 1u, MLAB_EMPTY_TAIL);
    for (var i = range.x; i < range.y; i++) {
        ht_insert(&head, &tail, composite_fragment_at(i).row);
    }
    for (var j = 0u; j < HT_K; j++) {
        composite_rows[composite_slot(p, j, HT_K + 1u)] = head[j];
    }
    composite_rows[composite_slot(p, HT_K, HT_K + 1u)] = tail;
}
