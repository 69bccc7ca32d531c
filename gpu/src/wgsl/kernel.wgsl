// mlab kernel, WGSL twin (docs/layout.md, docs/gpu.md). Integer arithmetic only: every f32 step
// of the CPU kernel (fragment quantization, the faint test, the depth comparison) is computed from
// the f32 bit patterns with u32 operations, so neither FMA contraction nor flushing of subnormals
// by a driver can change a byte.
//
// A row is a vec2<u32>: x = R | G << 8 | B << 16 | T << 24, y = bits of the f32 depth (Row::words).
// A tail is a vec2<u32>: the tail's two little-endian words.

const MLAB_EMPTY_ROW: vec2<u32> = vec2<u32>(0xff000000u, 0x7f800000u);
const MLAB_EMPTY_TAIL: vec2<u32> = vec2<u32>(0u, 0u);

// IEEE-754 `a <= b` on the bit patterns of two f32: false if either is NaN, -0 == +0.
fn mlab_depth_le(a: u32, b: u32) -> bool {
    let abs_a = a & 0x7fffffffu;
    let abs_b = b & 0x7fffffffu;
    if (abs_a > 0x7f800000u || abs_b > 0x7f800000u) {
        return false;
    }
    if ((abs_a | abs_b) == 0u) {
        return true;
    }
    // Order-preserving keys: positive values above negative ones, negative ones reversed.
    let ka = select(a | 0x80000000u, ~a, (a >> 31u) == 1u);
    let kb = select(b | 0x80000000u, ~b, (b >> 31u) == 1u);
    return ka <= kb;
}

// The 32-bit hash lowbias32 (mlab::lowbias32): x ^= x >> 16; x *= 0x7feb352d; x ^= x >> 15;
// x *= 0x846ca68b; x ^= x >> 16, u32 multiplications wrapping.
fn mlab_lowbias32(v: u32) -> u32 {
    var x = v;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

// The hash of a fragment in a pixel, which seeds both of Unbiased's dithers (mlab::fragment_hash):
// lowbias32(key ^ lowbias32(pixel)). `key`: the fragment's stable key (mlab::Fragment::with_key)
// or mlab_content_key; `pixel`: the framebuffer's pixel id, y * width + x.
fn mlab_fragment_hash(key: u32, pixel: u32) -> u32 {
    return mlab_lowbias32(key ^ mlab_lowbias32(pixel));
}

// The content key of a fragment without a stable key (mlab::Fragment::hash): the XOR of the bits
// of its premultiplied r, g, b, alpha and depth.
fn mlab_content_key(c: vec3<u32>, a: u32, z: u32) -> u32 {
    return c.x ^ c.y ^ c.z ^ a ^ z;
}

// The hash of an already quantized row inserted without its fragment (mlab::mlab::row_hash): the
// row's content key word0 ^ word1 in pixel `pixel`.
fn mlab_row_hash(row: vec2<u32>, pixel: u32) -> u32 {
    return mlab_fragment_hash(row.x ^ row.y, pixel);
}

// Significand (implicit bit included) and effective biased exponent of a non-negative finite f32.
fn mlab_f32_parts(v: u32) -> vec2<u32> {
    let e = (v >> 23u) & 0xffu;
    let f = v & 0x7fffffu;
    return vec2<u32>(select(f | 0x800000u, f, e == 0u), max(e, 1u));
}

// Bits of the correctly rounded (to nearest, ties to even) f32 product v * 255, for v the bits
// of a finite f32 in [-1, 1] whose sign is ignored (-0 * 255 + u = +0 + u for u > 0).
fn mlab_f32_mul255(v: u32) -> u32 {
    let parts = mlab_f32_parts(v & 0x7fffffffu);
    let p = parts.x * 255u; // exact: below 2^32
    if (p == 0u) {
        return 0u;
    }
    let n = 32u - countLeadingZeros(p);
    if (n <= 24u) {
        // Exact (only for subnormal v): subnormal or smallest-exponent result.
        return ((parts.y - 1u) << 23u) + p;
    }
    let s = n - 24u;
    var q = p >> s;
    let rem = p & ((1u << s) - 1u);
    let half = 1u << (s - 1u);
    if (rem > half || (rem == half && (q & 1u) == 1u)) {
        q += 1u;
    }
    // q in [2^23, 2^24]: its implicit bit (or a carry to 2^24) adds to the exponent field.
    return ((parts.y + s - 1u) << 23u) + q;
}

// Bits of the correctly rounded (to nearest, ties to even) f32 sum a + b, for the bits of two
// non-negative finite f32 whose sum is finite. Three guard bits (guard, round, sticky).
fn mlab_f32_add(a: u32, b: u32) -> u32 {
    let x = max(a, b); // non-negative f32 order as their bits
    let y = min(a, b);
    let px = mlab_f32_parts(x);
    let py = mlab_f32_parts(y);
    let mx = px.x << 3u;
    let my = py.x << 3u;
    let d = px.y - py.y;
    var ys = select(0u, 1u, my != 0u);
    if (d < 27u) {
        ys = (my >> d) | select(0u, 1u, (my & ((1u << d) - 1u)) != 0u);
    }
    var m = mx + ys;
    var e = px.y;
    if (m >= (1u << 27u)) {
        m = (m >> 1u) | (m & 1u);
        e += 1u;
    }
    let g = m & 7u;
    m = m >> 3u;
    if (g > 4u || (g == 4u && (m & 1u) == 1u)) {
        m += 1u;
    }
    return ((e - 1u) << 23u) + m;
}

// The f32 with bits v (non-negative, below 2^32) truncated to an integer: Rust's `as u8` for
// the kernel's values in [0, 256).
fn mlab_f32_trunc(v: u32) -> u32 {
    let e = v >> 23u;
    if (e < 127u) {
        return 0u;
    }
    return ((v & 0x7fffffu) | 0x800000u) >> (150u - min(e, 150u));
}

// The kernel's f32 step floor(v * 255 + u): f32 multiply, rounded, then f32 add, rounded, then
// truncation (docs/layout.md), exactly, from the bits of v and u.
fn mlab_quantize_byte(v: u32, u: u32) -> u32 {
    return mlab_f32_trunc(mlab_f32_add(mlab_f32_mul255(v), u));
}

// A row from a fragment's bits (premultiplied r, g, b, alpha, depth) and the dither u (bits).
fn mlab_quantize_with(c: vec3<u32>, a: u32, z: u32, u: u32) -> vec2<u32> {
    let r = mlab_quantize_byte(c.x, u);
    let g = mlab_quantize_byte(c.y, u);
    let b = mlab_quantize_byte(c.z, u);
    let t = 255u - mlab_quantize_byte(a, u);
    return vec2<u32>(r | (g << 8u) | (b << 16u) | (t << 24u), z);
}

// Paper::quantize: every channel floor(v * 255 + 0.5). `h` (the fragment's hash) is not read:
// the signature of every quantization, as mlab::Arithmetic::quantize.
fn mlab_quantize_paper(c: vec3<u32>, a: u32, z: u32, h: u32) -> vec2<u32> {
    return mlab_quantize_with(c, a, z, 0x3f000000u);
}

// Unbiased::quantize: faint fragments (alpha * 255 < 16 in f32) with u = ((h >> 24) + 0.5) / 256,
// h the fragment's hash (mlab_fragment_hash); others as Paper.
fn mlab_quantize_unbiased(c: vec3<u32>, a: u32, z: u32, h: u32) -> vec2<u32> {
    // 16.0 is 0x41800000; non-negative f32 compare as their bits.
    if (mlab_f32_mul255(a) >= 0x41800000u) {
        return mlab_quantize_with(c, a, z, 0x3f000000u);
    }
    // u = (2 t + 1) * 2^-9 as f32 bits (exact), t = h >> 24: n = 2 t + 1 has L bits,
    // u = n / 2^(L-1) * 2^(L-10).
    let n = 2u * (h >> 24u) + 1u;
    let l = 32u - countLeadingZeros(n);
    let u = ((117u + l) << 23u) | ((n << (24u - l)) & 0x7fffffu);
    return mlab_quantize_with(c, a, z, u);
}

fn mlab_channel(w: u32, i: u32) -> u32 {
    return (w >> (8u * i)) & 0xffu;
}

// round(x / 255) for x <= 65025 (unorm::div255).
fn mlab_div255_round(x: u32) -> u32 {
    let y = x + 128u;
    return (y + (y >> 8u)) >> 8u;
}

// Paper::merge (Eq. 7-8, round to nearest), front nearer; z = z_front. `h` (the inserted
// fragment's hash) is not read: the signature of every merge, as mlab::Arithmetic::merge.
fn mlab_merge_paper(front: vec2<u32>, back: vec2<u32>, h: u32) -> vec2<u32> {
    let at = front.x >> 24u;
    let bt = back.x >> 24u;
    // The three channels written out: no loop (lavapipe's loop limit counts every iteration).
    let r = min(mlab_channel(front.x, 0u) + mlab_div255_round(mlab_channel(back.x, 0u) * at), 255u);
    let g = min(mlab_channel(front.x, 1u) + mlab_div255_round(mlab_channel(back.x, 1u) * at), 255u);
    let b = min(mlab_channel(front.x, 2u) + mlab_div255_round(mlab_channel(back.x, 2u) * at), 255u);
    return vec2<u32>(r | (g << 8u) | (b << 16u) | (mlab_div255_round(at * bt) << 24u), front.y);
}

// The order-preserving key of an f32's bits (arith::depth_key), as the bits of an i32: the low 31
// bits flipped for a negative sign. Its own inverse.
fn mlab_depth_order_key(bits: u32) -> u32 {
    return bits ^ select(0u, 0x7fffffffu, (bits >> 31u) != 0u);
}

// The back row's weight in the depth of Unbiased's merge (arith::centroid_weight), in
// 1/65536ths: p = Tf Tb, cb = 255 Tf - p, w = min(floor(256 cb / (65025 - p)), 255) * 256 for
// Tf >= 160, else 0. An exact u32 division (65025 - p = 0 only where cb = 0).
fn mlab_centroid_weight(tf: u32, tb: u32) -> u32 {
    let p = tf * tb;
    let cb = 255u * tf - p;
    let q = min((256u * cb) / max(65025u - p, 1u), 255u);
    return select(0u, q << 8u, tf >= 160u);
}

// The depth of Unbiased's merge (arith::centroid_depth): the key of z_front moved toward z_back's
// by floor(diff * w / 65536) if the back row is behind (signed keys), else z_front, bit for bit.
// (diff >> 16) w + (((diff & 0xffff) w) >> 16) <= diff: no u32 product or sum overflows.
fn mlab_centroid_depth(front: vec2<u32>, back: vec2<u32>) -> u32 {
    let w = mlab_centroid_weight(front.x >> 24u, back.x >> 24u);
    let kf = mlab_depth_order_key(front.y);
    let kb = mlab_depth_order_key(back.y);
    let diff = select(0u, kb - kf, bitcast<i32>(kb) > bitcast<i32>(kf));
    let step = (diff >> 16u) * w + (((diff & 0xffffu) * w) >> 16u);
    return mlab_depth_order_key(kf + step);
}

// Unbiased::merge, `h` the inserted fragment's hash: d = ((h & 0xffff) * 255) >> 16,
// T = (Tf Tb + d) / 255, C = min(255, Cf + (Cb Tf + 254 - d) / 255), z = mlab_centroid_depth.
fn mlab_merge_unbiased(front: vec2<u32>, back: vec2<u32>, h: u32) -> vec2<u32> {
    let d = ((h & 0xffffu) * 255u) >> 16u;
    let at = front.x >> 24u;
    let bt = back.x >> 24u;
    // The three channels written out: no loop (lavapipe's loop limit counts every iteration).
    let r = min(mlab_channel(front.x, 0u) + (mlab_channel(back.x, 0u) * at + 254u - d) / 255u, 255u);
    let g = min(mlab_channel(front.x, 1u) + (mlab_channel(back.x, 1u) * at + 254u - d) / 255u, 255u);
    let b = min(mlab_channel(front.x, 2u) + (mlab_channel(back.x, 2u) * at + 254u - d) / 255u, 255u);
    let t = (at * bt + d) / 255u;
    return vec2<u32>(r | (g << 8u) | (b << 16u) | (t << 24u), mlab_centroid_depth(front, back));
}

// A row that changes nothing (R = G = B = 0, T = 255), whatever its depth.
fn mlab_row_is_invisible(row: vec2<u32>) -> bool {
    return row.x == 0xff000000u;
}

// PaperTail += row: word0 R 0..10 | G 10..20 | B 20..30 | spare 30..32 (kept),
// word1 alpha 0..16 | count 16..32; every field saturates.
fn mlab_tail_add_paper(tail: vec2<u32>, row: vec2<u32>) -> vec2<u32> {
    if (mlab_row_is_invisible(row)) {
        return tail;
    }
    let r = min((tail.x & 0x3ffu) + mlab_channel(row.x, 0u), 1023u);
    let g = min(((tail.x >> 10u) & 0x3ffu) + mlab_channel(row.x, 1u), 1023u);
    let b = min(((tail.x >> 20u) & 0x3ffu) + mlab_channel(row.x, 2u), 1023u);
    let a = min((tail.y & 0xffffu) + 255u - (row.x >> 24u), 65535u);
    let n = min((tail.y >> 16u) + 1u, 65535u);
    return vec2<u32>(r | (g << 10u) | (b << 20u) | (tail.x & 0xc0000000u), a | (n << 16u));
}

// Tail += row, the 64-bit tail as two words (word0 | word1 << 32): R 0..13 | G 13..26 |
// B 26..39 (bits 26..32 of word0 and 0..7 of word1) | alpha 39..53 | count 53..64; saturating.
fn mlab_tail_add_wide(tail: vec2<u32>, row: vec2<u32>) -> vec2<u32> {
    if (mlab_row_is_invisible(row)) {
        return tail;
    }
    let r = min((tail.x & 0x1fffu) + mlab_channel(row.x, 0u), 8191u);
    let g = min(((tail.x >> 13u) & 0x1fffu) + mlab_channel(row.x, 1u), 8191u);
    let b = min(((tail.x >> 26u) | ((tail.y & 0x7fu) << 6u)) + mlab_channel(row.x, 2u), 8191u);
    let a = min(((tail.y >> 7u) & 0x3fffu) + 255u - (row.x >> 24u), 16383u);
    let n = min((tail.y >> 21u) + 1u, 2047u);
    return vec2<u32>(r | (g << 13u) | (b << 26u), (b >> 6u) | (a << 7u) | (n << 21u));
}

// The rounded Q15 product (x * y + 16384) >> 15 of the integer resolve, x, y <= 32767.
fn mlab_q15(x: u32, y: u32) -> u32 {
    return (x * y + 16384u) >> 15u;
}

// The integer RGBA8 resolve's last step (docs/layout.md, "Integer resolve"): from the three
// accumulators and the Q15 visibility to R | G << 8 | B << 16 | A << 24. `bg`: the background's
// three channels as the kernel quantizes them (mlab_gpu::background_q15, computed on the CPU)
// and w = 1 for an opaque background, w = 0 for Background::Transparent (premultiplied output).
fn mlab_resolve_pixel(acc: vec3<u32>, v: u32, bg: vec4<u32>) -> u32 {
    if (bg.w != 0u) {
        let c = min(acc + vec3<u32>(mlab_q15(bg.x, v), mlab_q15(bg.y, v), mlab_q15(bg.z, v)), vec3<u32>(32767u)) >> vec3<u32>(7u);
        return c.x | (c.y << 8u) | (c.z << 16u) | (255u << 24u);
    }
    let c = acc >> vec3<u32>(7u);
    let a = (mlab_q15(32767u - v, 32640u) + 64u) >> 7u;
    return c.x | (c.y << 8u) | (c.z << 16u) | (a << 24u);
}
