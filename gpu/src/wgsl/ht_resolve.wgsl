// The integer RGBA8 resolve of HT (docs/layout.md, "Integer resolve of HT"): the MLAB integer
// resolve's loop over the HT_K head rows, then the tail as one more layer of light L_c and
// transmittance T (Q16), then mlab_resolve_pixel. u32 only; every product below 2^32 (the bound
// of each is noted), every division an exact truncating u32 division, no loop in the tail (the
// Horner sums and the six bit steps are written out), so no f32 rounding, no FMA and no loop
// limit can change a byte. Needs HT_K, ht_tail_fields (the tail layout, from the generated
// header) and KERNEL (mlab_q15, mlab_resolve_pixel).

// A tail's fields: the three color sums S_c, the alpha sum S_a and the count.
struct ht_fields {
    sums: vec3<u32>,
    alpha: u32,
    count: u32,
}

// PaperTail: word0 R 0..10 | G 10..20 | B 20..30 (spare bits ignored), word1 alpha 0..16 |
// count 16..32.
fn ht_tail_fields_paper(tail: vec2<u32>) -> ht_fields {
    let sums = vec3<u32>(tail.x & 0x3ffu, (tail.x >> 10u) & 0x3ffu, (tail.x >> 20u) & 0x3ffu);
    return ht_fields(sums, tail.y & 0xffffu, tail.y >> 16u);
}

// Tail (word0 | word1 << 32): R 0..13 | G 13..26 | B 26..39 | alpha 39..53 | count 53..64.
fn ht_tail_fields_wide(tail: vec2<u32>) -> ht_fields {
    let b = (tail.x >> 26u) | ((tail.y & 0x7fu) << 6u);
    let sums = vec3<u32>(tail.x & 0x1fffu, (tail.x >> 13u) & 0x1fffu, b);
    return ht_fields(sums, (tail.y >> 7u) & 0x3fffu, tail.y >> 21u);
}

// The rounded Q16 product (x * y + 32768) >> 16; every call below keeps x * y + 32768 < 2^32.
fn mlab_q16(x: u32, y: u32) -> u32 {
    return (x * y + 32768u) >> 16u;
}

// The polynomial c[0] + x (c[1] + x (c[2] + .. x c[7])) in Horner's steps from c[7] down, each
// product the rounded Q16 one; the steps are written out (no loop). A zero leading coefficient
// changes nothing (mlab_q16(0, x) = 0): a shorter table is padded with zeros. The caller bounds
// s * x + 32768 < 2^32 for every partial sum s.
fn ht_horner(c: array<u32, 8>, x: u32) -> u32 {
    var s = c[7];
    s = c[6] + mlab_q16(s, x);
    s = c[5] + mlab_q16(s, x);
    s = c[4] + mlab_q16(s, x);
    s = c[3] + mlab_q16(s, x);
    s = c[2] + mlab_q16(s, x);
    s = c[1] + mlab_q16(s, x);
    return c[0] + mlab_q16(s, x);
}

// The tail's (T, g) in Q16 (65536 = 1) from its alpha sum and count (each at most 65535, as the
// tails' fields are): T ~ (1 - m)^n and g ~ (1 - T) / (n m), m = S_a / (255 n). The kernel's
// resolve::int::tail, step for step; the constant tables H, EXP, EB, PSI of docs/layout.md
// are the coefficients of ht_horner, lowest first.
fn ht_tail_resolve(alpha: u32, count: u32) -> vec2<u32> {
    let n = max(count, 1u);
    let m = (257u * alpha) / n; // 257 S_a <= 16,842,495 < 2^24: exact
    let series = m <= 16384u; // route A: m <= 1/4, T = e^-u
    let mm = min(m, 16384u);
    // h(m) = -ln(1 - m) / m in units of 1/65793 (H); h <= 75,710: h * mm < 2^31.
    let h = ht_horner(array<u32, 8>(65793u, 32897u, 21931u, 16448u, 13159u, 10966u, 9399u, 8224u), mm);
    let u = (min(alpha, 4095u) * h + 128u) >> 8u; // optical depth, Q16; 4095 h < 2^29
    let j = u >> 15u; // floor(2 u)
    let y = 32768u - (u & 32767u); // 1/2 - r, in (0, 1/2]
    // e^(-r) (EXP); e_r <= 65537, y <= 32768: products < 2^32.
    let e_r = ht_horner(array<u32, 8>(39750u, 39750u, 19875u, 6625u, 1656u, 331u, 55u, 0u), y);
    let zero = select(n >= 64u, u >= 786432u, series); // A: u >= 12; B: (3/4)^64
    let bits = select(select(n, j, series), 0u, zero); // at most 6 bits when not zero
    // Route A: e^(-r) times EB[i] = e^(-2^i / 2) for each set bit i of j; route B: x^n by the
    // bits of n, x = b = 1 - m. p <= 65537 and EB[i] <= 39750, or p <= 65536 and b <= 65535:
    // p * factor + 32768 < 2^32; b * b < 2^32.
    var p = select(65536u, e_r, series);
    var b = 65535u - min(m, 65535u);
    p = select(p, mlab_q16(p, select(b, 39750u, series)), (bits & 1u) != 0u);
    b = mlab_q16(b, b);
    p = select(p, mlab_q16(p, select(b, 24109u, series)), (bits & 2u) != 0u);
    b = mlab_q16(b, b);
    p = select(p, mlab_q16(p, select(b, 8869u, series)), (bits & 4u) != 0u);
    b = mlab_q16(b, b);
    p = select(p, mlab_q16(p, select(b, 1200u, series)), (bits & 8u) != 0u);
    b = mlab_q16(b, b);
    p = select(p, mlab_q16(p, select(b, 22u, series)), (bits & 16u) != 0u);
    b = mlab_q16(b, b);
    p = select(p, mlab_q16(p, select(b, 0u, series)), (bits & 32u) != 0u);
    let t = select(min(p, 65536u), 0u, zero);
    // psi(u) = (e^u - 1) / u (PSI) on min(u, 32767); psi <= 85,028 (the maximum over every
    // input, as h <= 75,710 and e_r <= 65,537 are): psi * 32767 < 2^32.
    let psi = ht_horner(array<u32, 8>(65536u, 32768u, 10923u, 2731u, 546u, 91u, 0u, 0u), min(u, 32767u));
    let phi = ((t >> 1u) * psi + 16384u) >> 15u; // (1 - e^-u) / u; 32768 * 85,028 < 2^32
    // g = h(m) phi(u) (route A, u < 1/2; (h - 65793) phi < 2^30), else (1 - T) / s (< 2^24).
    let g_s = phi + (((((h - 65793u) * phi + 128u) >> 8u) * 255u + 32768u) >> 16u);
    let g_d = ((65536u - t) * 255u) / max(alpha, 1u);
    let g = min(65536u, select(g_d, g_s, series && u < 32768u));
    return vec2<u32>(t, g);
}

// One head row of the MLAB integer resolve: acc_c = min(32767, acc_c + q15(128 c, v)), then
// v = q15(floor(257 T / 2), v). Returns (acc, v).
fn ht_resolve_row(acc: vec3<u32>, v: u32, w: u32) -> vec4<u32> {
    let c = vec3<u32>(w & 0xffu, (w >> 8u) & 0xffu, (w >> 16u) & 0xffu) * 128u;
    let a = min(acc + vec3<u32>(mlab_q15(c.x, v), mlab_q15(c.y, v), mlab_q15(c.z, v)), vec3<u32>(32767u));
    return vec4<u32>(a, mlab_q15(((w >> 24u) * 257u) >> 1u, v));
}

// The tail behind the head: L_c = (S_c g + 256) >> 9 (128 * 255 C_tail, up to 20 bits: S_c g
// <= 8191 * 65536 < 2^30), acc_c = min(32767, acc_c + (L_c >> 15) v + q15(L_c & 32767, v)),
// then v = q16(T, v). Returns (acc, v).
fn ht_resolve_tail(acc: vec3<u32>, v: u32, f: ht_fields) -> vec4<u32> {
    let tg = ht_tail_resolve(f.alpha, f.count);
    let l = (f.sums * tg.y + vec3<u32>(256u)) >> vec3<u32>(9u);
    let lo = l & vec3<u32>(32767u);
    let q = vec3<u32>(mlab_q15(lo.x, v), mlab_q15(lo.y, v), mlab_q15(lo.z, v));
    let a = min(acc + (l >> vec3<u32>(15u)) * v + q, vec3<u32>(32767u));
    return vec4<u32>(a, mlab_q16(tg.x, v));
}

// The integer RGBA8 resolve of one HT pixel: its HT_K head rows front to back (every row, empty
// ones too), then its tail (the layout of ht_tail_fields), then mlab_resolve_pixel over `bg`
// (mlab_gpu::background_q15). Returns R | G << 8 | B << 16 | A << 24: the bytes of the kernel's
// resolve_rgba8 pixel.
fn ht_resolve_rgba8(head: ptr<function, array<vec2<u32>, HT_K>>, tail: vec2<u32>, bg: vec4<u32>) -> u32 {
    var s = vec4<u32>(64u, 64u, 64u, 32767u);
    for (var j = 0u; j < HT_K; j++) {
        s = ht_resolve_row(s.xyz, s.w, (*head)[j].x);
    }
    s = ht_resolve_tail(s.xyz, s.w, ht_tail_fields(tail));
    return mlab_resolve_pixel(s.xyz, s.w, bg);
}
