
// The integer RGBA8 resolve of every image pixel of the dispatch (padding lanes skipped), after
// the `composite` dispatches: the bytes of the kernel's Framebuffer::resolve_rgba8 for MLAB.
@compute @workgroup_size(64)
fn resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = gid.y * composite_params.pitch + gid.x;
    let i = composite_image_index(p);
    if (i == COMPOSITE_NONE) {
        return;
    }
    var b: array<vec2<u32>, MLAB_M>;
    for (var j = 0u; j < MLAB_M; j++) {
        b[j] = composite_rows[composite_slot(p, j, MLAB_M)];
    }
    composite_image[i] = mlab_resolve_rgba8(&b, composite_params.background);
}
