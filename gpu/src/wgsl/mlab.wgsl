// Listing 1 (Salvi & Vaidyanathan 2014) on MLAB_M rows, front to back: a one-pass bubble
// insert (`f.z <= B[i].z`: a new fragment goes in front of rows at its depth), then the merge of
// the last two rows (mlab_merge: the arithmetic chosen by the generated header).
fn mlab_insert(b: ptr<function, array<vec2<u32>, MLAB_M>>, row: vec2<u32>) {
    var f = row;
    for (var i = 0u; i < MLAB_M; i++) {
        let r = (*b)[i];
        let swap = mlab_depth_le(f.y, r.y);
        let front = select(r, f, swap);
        f = select(f, r, swap);
        if (i + 1u < MLAB_M) {
            (*b)[i] = front;
        } else {
            (*b)[i] = mlab_merge(front, f);
        }
    }
}
