
// HT's composite_resolve_pixel: the kernel's Framebuffer::resolve_rgba8 pixel for HT of stored
// pixel p (head rows in slots 0 .. HT_K, the tail in slot HT_K).
fn composite_resolve_pixel(p: u32) -> u32 {
    var head: array<vec2<u32>, HT_K>;
    for (var j = 0u; j < HT_K; j++) {
        head[j] = composite_rows[composite_slot(p, j, HT_K + 1u)];
    }
    let tail = composite_rows[composite_slot(p, HT_K, HT_K + 1u)];
    return ht_resolve_rgba8(&head, tail, composite_params.background);
}
