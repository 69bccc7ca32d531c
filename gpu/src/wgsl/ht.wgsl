// Listing 2 (Salvi & Vaidyanathan 2014) on HT_K head rows and a tail: a one-pass bubble insert
// into the head, then the row pushed out is added to the tail (ht_tail_add: the tail layout
// chosen by the generated header) unless it is invisible (no color, T = 255).
fn ht_insert(head: ptr<function, array<vec2<u32>, HT_K>>, tail: ptr<function, vec2<u32>>, row: vec2<u32>) {
    var f = row;
    for (var i = 0u; i < HT_K; i++) {
        let r = (*head)[i];
        let swap = mlab_depth_le(f.y, r.y);
        (*head)[i] = select(r, f, swap);
        f = select(f, r, swap);
    }
    *tail = ht_tail_add(*tail, f);
}
