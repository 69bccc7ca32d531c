
// The integer RGBA8 resolve of every image pixel of the dispatch (padding lanes skipped), after
// the `composite` dispatches: the bytes of the kernel's Framebuffer::resolve_rgba8 for HT (head
// rows in slots 0 .. HT_K, the tail in slot HT_K).
@compute @workgroup_size(64)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = gid.y * composite_params.pitch + gid.x;
    let i = composite_image_index(p);
    if (i == COMPOSITE_NONE) {
        return;
    }
    var head: array<vec2<u32>, HT_K>;
    for (var j = 0u; j < HT_K; j++) {
        head[j] = composite_rows[composite_slot(p, j, HT_K + 1u)];
    }
    let tail = composite_rows[composite_slot(p, HT_K, HT_K + 1u)];
    composite_image[i] = ht_resolve_rgba8(&head, tail, composite_params.background);
}
