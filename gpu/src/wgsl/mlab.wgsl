// Listing 1 (Salvi & Vaidyanathan 2014) on MLAB_M rows, front to back: a one-pass bubble
// insert (`f.z <= B[i].z`: a new fragment goes in front of rows at its depth), then the merge of
// the last two rows (mlab_merge: the arithmetic chosen by the generated header), seeded by `h`,
// the inserted fragment's hash (mlab_fragment_hash; mlab_row_hash for a row without its
// fragment), as mlab::mlab::insert_hashed.
fn mlab_insert(b: ptr<function, array<vec2<u32>, MLAB_M>>, row: vec2<u32>, h: u32) {
    var f = row;
    // Rows 0 .. M - 1: the swaps (M - 1 iterations, a small body: lavapipe's loop limit counts
    // every iteration of a loop the compiler does not unroll).
    for (var i = 0u; i + 1u < MLAB_M; i++) {
        let r = (*b)[i];
        let swap = mlab_depth_le(f.y, r.y);
        (*b)[i] = select(r, f, swap);
        f = select(f, r, swap);
    }
    // Row M - 1: the nearer of it and the row pushed down, merged with the other behind it.
    let r = (*b)[MLAB_M - 1u];
    let swap = mlab_depth_le(f.y, r.y);
    (*b)[MLAB_M - 1u] = mlab_merge(select(r, f, swap), select(f, r, swap), h);
}

// The integer RGBA8 resolve of MLAB (docs/layout.md, "Integer resolve"): every row visited
// front to back, empty rows too; acc_c = min(32767, acc_c + q15(128 c, v)),
// v = q15(floor(257 T / 2), v); then mlab_resolve_pixel. Returns R | G << 8 | B << 16 | A << 24
// (the bytes of the kernel's resolve_rgba8 pixel).
fn mlab_resolve_rgba8(b: ptr<function, array<vec2<u32>, MLAB_M>>, bg: vec4<u32>) -> u32 {
    var acc = vec3<u32>(64u);
    var v = 32767u;
    for (var j = 0u; j < MLAB_M; j++) {
        let w = (*b)[j].x;
        let c = vec3<u32>(w & 0xffu, (w >> 8u) & 0xffu, (w >> 16u) & 0xffu) * 128u;
        acc = min(acc + vec3<u32>(mlab_q15(c.x, v), mlab_q15(c.y, v), mlab_q15(c.z, v)), vec3<u32>(32767u));
        v = mlab_q15(((w >> 24u) * 257u) >> 1u, v);
    }
    return mlab_resolve_pixel(acc, v, bg);
}
