
// MLAB's composite_resolve_pixel: the kernel's Framebuffer::resolve_rgba8 pixel of the MLAB_M
// rows of stored pixel p.
fn composite_resolve_pixel(p: u32) -> u32 {
    var b: array<vec2<u32>, MLAB_M>;
    for (var j = 0u; j < MLAB_M; j++) {
        b[j] = composite_rows[composite_slot(p, j, MLAB_M)];
    }
    return mlab_resolve_rgba8(&b, composite_params.background);
}
