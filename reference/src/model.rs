//! Reference models of the kernel's two arithmetics, written from the documented
//! definitions (`src/arith.rs`, `src/unorm.rs`, the tail tables of `src/tail.rs`,
//! `docs/layout.md`), never calling the kernel's `merge`, `merge_dither`, `quantize` or tail
//! packing: the quantizations, the dithers, the merge products, a `Vec`-based Listing 1, the
//! HT tail layouts, a sort-and-sum Hybrid Transparency, and Eq. 5 and the Bavoil-Myers tail
//! in f64. The kernel's marker types ([`Paper`], [`Unbiased`]) only name the model
//! ([`Model`]).

use mlab::{Arithmetic, Fragment, Paper, Row, Unbiased};

use crate::oracle::front_to_back;

// ---------------------------------------------------------------------------------------
// The two arithmetics

/// The reference model of one of the kernel's arithmetics. The kernel's marker types
/// ([`Paper`], [`Unbiased`]) only name it: every function here is written from the
/// documented definitions (`src/arith.rs`, `src/unorm.rs`, the tail tables of
/// `src/tail.rs`), and none calls the kernel's arithmetic.
pub trait Model: Arithmetic {
    /// A strict upper bound on the error of one merge product, in steps of `1/255`:
    /// `0.5` for the paper's round to nearest (at most `127/255`, ties cannot occur), `1`
    /// for the dithered rounding (`floor((p + d) / 255)` with `d` in `0..=254` lies in
    /// `(p/255 - 1, p/255 + 254/255]`).
    const MERGE_ERROR: f64;
    /// The rounding bound of the tests' oracle bound ([`crate::oracle::oracle_with_bound`])
    /// for this arithmetic: [`crate::DELTA`] for the paper's, [`crate::DELTA_UNBIASED`] for
    /// the dithered one (one unorm8 step, every quantization and product counted alike).
    const DELTA: f64;
    /// The HT tail layout of this arithmetic.
    const TAIL: TailLayout;

    /// Paper Eq. 7 and 8 on bytes, products rounded as this arithmetic documents, during
    /// the insert of a fragment of hash `h` ([`ref_fragment_hash`]).
    fn ref_merge(front: Row, back: Row, h: u32) -> Row;

    /// Quantize a validated fragment's premultiplied color, alpha and depth, of hash `h`,
    /// into a row: to nearest (`floor(v * 255 + 0.5)` per channel, `T = 255 - floor(alpha *
    /// 255 + 0.5)`, in f32), unless the arithmetic says otherwise.
    fn ref_quantize(color: [f32; 3], alpha: f32, depth: f32, _h: u32) -> Row {
        Row::new(color.map(|c| ref_byte(c, 0.5)), 255 - ref_byte(alpha, 0.5), depth)
    }

    /// Largest error of the quantization of a fragment of this alpha, in steps, before
    /// f32 rounding: `0.5` to nearest, [`DITHERED_QUANT_ERROR`] dithered.
    fn quant_error(_alpha: f32) -> f64 {
        0.5
    }

    /// [`Model::ref_quantize`] of a fragment in the pixel of id `pixel`.
    fn ref_row(f: &Fragment, pixel: u32) -> Row {
        let c = f.color().to_array();
        let h = ref_fragment_hash(ref_key(f), pixel);
        Self::ref_quantize(c, f.alpha(), f.depth(), h)
    }
}

/// Alpha, in bytes, below which the unbiased arithmetic dithers a fragment's quantization
/// (`mlab::Unbiased::quantize` docs: `alpha * 255 < 16`, computed in f32).
pub const FAINT_BYTES: f32 = 16.0;

/// True when the unbiased arithmetic dithers this fragment (`alpha * 255 < 16` in f32).
pub fn is_faint(alpha: f32) -> bool {
    let bytes: f32 = alpha * 255.0;
    bytes < FAINT_BYTES
}

/// Largest error of the dithered quantization (`mlab::arith::quantize_dithered`), in
/// steps, before f32 rounding: `floor(v * 255 + u)` with `u` in `[1/512, 511/512]`.
pub const DITHERED_QUANT_ERROR: f64 = 511.0 / 512.0;

/// The dithered quantization of a validated fragment (`mlab::arith::quantize_dithered`
/// docs, used by the unbiased arithmetic for faint fragments): `floor(v * 255 + u)` per
/// channel and for alpha, one dither `u` ([`ref_fragment_dither`] of the hash `h`) for all
/// four.
pub fn ref_quantize_dithered(color: [f32; 3], alpha: f32, depth: f32, h: u32) -> Row {
    let u = ref_fragment_dither(h);
    Row::new(color.map(|c| ref_byte(c, u)), 255 - ref_byte(alpha, u), depth)
}

/// `floor(v * 255 + u)` in f32, the multiply and the add each rounded once (the
/// documented quantization: `u = 0.5` to nearest, a dither for `quantize_dithered`).
pub fn ref_byte(v: f32, u: f32) -> u8 {
    let scaled: f32 = v * 255.0;
    let y: f32 = scaled + u;
    let b = y.floor();
    assert!(
        (0.0..256.0).contains(&b),
        "quantization of {v} + {u} out of a byte: {b}"
    );
    b as u8
}

/// `lowbias32` (`mlab::lowbias32` docs), step by step in 64-bit arithmetic reduced
/// modulo `2^32`.
pub fn ref_lowbias32(x: u32) -> u32 {
    let m = |a: u64, k: u64| (a * k) % (1 << 32);
    let mut v = u64::from(x);
    v ^= v >> 16;
    v = m(v, 0x7feb_352d);
    v ^= v >> 15;
    v = m(v, 0x846c_a68b);
    v ^= v >> 16;
    v as u32
}

/// The hash of a fragment of key `key` in pixel `pixel` (`mlab::fragment_hash` docs):
/// `lowbias32(key ^ lowbias32(pixel))`.
pub fn ref_fragment_hash(key: u32, pixel: u32) -> u32 {
    ref_lowbias32(key ^ ref_lowbias32(pixel))
}

/// The key of a fragment (`mlab::Fragment::hash` docs): its stable key, or the XOR of the
/// f32 bits of its premultiplied R, G, B, alpha and depth.
pub fn ref_key(f: &Fragment) -> u32 {
    let c = f.color().to_array();
    f.key()
        .unwrap_or(c[0].to_bits() ^ c[1].to_bits() ^ c[2].to_bits() ^ f.alpha().to_bits() ^ f.depth().to_bits())
}

/// The hash of an inserted row (`mlab::mlab::row_hash` docs): the key is the XOR of its
/// two little-endian words.
pub fn ref_row_hash(row: Row, pixel: u32) -> u32 {
    let b = row.to_bytes();
    let w0 = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    let w1 = u32::from_le_bytes([b[4], b[5], b[6], b[7]]);
    ref_fragment_hash(w0 ^ w1, pixel)
}

/// The dither of the unbiased merge, in `0..=254` (`mlab::arith::merge_dither` docs):
/// `floor((h mod 2^16) * 255 / 65536)`.
pub fn ref_merge_dither(h: u32) -> u32 {
    (u64::from(h % 65536) * 255 / 65536) as u32
}

/// The dither of the dithered fragment quantization (`mlab::arith::fragment_dither` docs):
/// `u = (floor(h / 2^24) + 0.5) / 256`.
pub fn ref_fragment_dither(h: u32) -> f32 {
    ((h / (1 << 24)) as f32 + 0.5) / 256.0
}

/// The position of an f32 in IEEE order as an unsigned key (`docs/layout.md`):
/// `bits | 2^31` for a positive sign, `!bits` for a negative one.
pub fn ref_depth_order(bits: u32) -> u64 {
    u64::from(if bits >> 31 == 1 { !bits } else { bits | 0x8000_0000 })
}

/// The depth of the unbiased merge (`mlab::arith::centroid_depth` docs): with the back row's
/// share of the merged opacity in 1/256ths, `w = min(floor(256 (255 - T_b) T_f / (65025 -
/// T_f T_b)), 255)` (0 when `T_f < 160` or the share is 0), the key moved from the front's
/// toward the back's by `floor((K_b - K_f) w / 256)` when the back's key is larger; in u64.
pub fn ref_centroid_depth(front: Row, back: Row) -> f32 {
    let (f, b) = (front.to_bytes(), back.to_bytes());
    let (t_f, t_b) = (u64::from(f[3]), u64::from(b[3]));
    let cb = (255 - t_b) * t_f;
    let w = if t_f < 160 || cb == 0 {
        0
    } else {
        (256 * cb / (255 * (255 - t_f) + cb)).min(255)
    };
    let (kf, kb) = (ref_depth_order(front.words()[1]), ref_depth_order(back.words()[1]));
    if kb <= kf {
        return front.depth();
    }
    let k = (kf + (kb - kf) * w / 256) as u32;
    f32::from_bits(if k >> 31 == 1 { k & 0x7fff_ffff } else { !k })
}

/// `round(a * b / 255)` in f64 (ties cannot occur: 255 is odd).
pub fn ref_mul(a: u8, b: u8) -> u8 {
    (f64::from(a) * f64::from(b) / 255.0).round() as u8
}

/// Paper Eq. 7 and 8 on bytes: `A = min(255, A_f + A_b T_f)`, `T = T_f T_b`, `z = z_f`.
pub fn ref_merge(front: Row, back: Row) -> Row {
    let f = front.to_bytes();
    let b = back.to_bytes();
    let add = |i: usize| (u16::from(f[i]) + u16::from(ref_mul(b[i], f[3]))).min(255) as u8;
    Row::from_bytes([add(0), add(1), add(2), ref_mul(f[3], b[3]), f[4], f[5], f[6], f[7]])
}

/// The unbiased Eq. 7 and 8 on bytes (`mlab::Unbiased::merge` docs), with
/// `d = ref_merge_dither(h)`: `T = floor((T_f T_b + d) / 255)`,
/// `A = min(255, A_f + floor((A_b T_f + 254 - d) / 255))`, `z` = [`ref_centroid_depth`];
/// plain integer division.
pub fn ref_merge_unbiased(front: Row, back: Row, h: u32) -> Row {
    let f = front.to_bytes();
    let b = back.to_bytes();
    let d = ref_merge_dither(h);
    let t_f = u32::from(f[3]);
    let add = |i: usize| (u32::from(f[i]) + (u32::from(b[i]) * t_f + 254 - d) / 255).min(255) as u8;
    let t = ((t_f * u32::from(b[3]) + d) / 255) as u8;
    Row::new([add(0), add(1), add(2)], t, ref_centroid_depth(front, back))
}

impl Model for Paper {
    const MERGE_ERROR: f64 = 0.5;
    const DELTA: f64 = crate::DELTA;
    const TAIL: TailLayout = PAPER_TAIL;

    fn ref_merge(front: Row, back: Row, _h: u32) -> Row {
        ref_merge(front, back)
    }
}

impl Model for Unbiased {
    const MERGE_ERROR: f64 = 1.0;
    const DELTA: f64 = crate::DELTA_UNBIASED;
    const TAIL: TailLayout = WIDE_TAIL;

    fn ref_merge(front: Row, back: Row, h: u32) -> Row {
        ref_merge_unbiased(front, back, h)
    }

    /// To nearest, except faint fragments ([`is_faint`]): [`ref_quantize_dithered`].
    fn ref_quantize(color: [f32; 3], alpha: f32, depth: f32, h: u32) -> Row {
        if is_faint(alpha) {
            ref_quantize_dithered(color, alpha, depth, h)
        } else {
            Paper::ref_quantize(color, alpha, depth, h)
        }
    }

    fn quant_error(alpha: f32) -> f64 {
        if is_faint(alpha) { DITHERED_QUANT_ERROR } else { 0.5 }
    }
}

// ---------------------------------------------------------------------------------------
// Listing 1

/// Listing 1 over a list of rows that holds only what was inserted (no empty rows), for
/// rows with finite depths: insert at the first position whose depth is not smaller, and
/// when the list is longer than `M` merge the last two with the model's merge.
#[derive(Clone, Debug)]
pub struct RefMlab {
    m: usize,
    rows: Vec<Row>,
    merge: fn(Row, Row, u32) -> Row,
}

impl RefMlab {
    /// An empty blending array of `m` rows in the arithmetic `A`.
    pub fn new<A: Model>(m: usize) -> Self {
        RefMlab {
            m,
            rows: Vec::new(),
            merge: A::ref_merge,
        }
    }

    /// Insert a row with a finite depth, of hash `h` (the inserted fragment's).
    pub fn insert(&mut self, row: Row, h: u32) {
        let pos = self
            .rows
            .iter()
            .position(|b| row.depth() <= b.depth())
            .unwrap_or(self.rows.len());
        self.rows.insert(pos, row);
        if self.rows.len() > self.m {
            let back = self.rows.pop().unwrap();
            let front = self.rows.pop().unwrap();
            self.rows.push((self.merge)(front, back, h));
        }
    }

    /// The `m` rows, padded with empty rows.
    pub fn rows(&self) -> Vec<Row> {
        let mut v = self.rows.clone();
        v.resize(self.m, Row::EMPTY);
        v
    }
}

/// Listing 1 transcribed for arbitrary rows (NaN depths, unsorted): carry the new row
/// through the array, swapping where `carried.z <= slot.z`; returns the array before the
/// merge and the row pushed out.
pub fn ref_bubble(rows: &[Row], row: Row) -> (Vec<Row>, Row) {
    let mut out = Vec::with_capacity(rows.len());
    let mut carried = row;
    for &slot in rows {
        let (z_c, z_s) = (f32::from_bits(carried.words()[1]), f32::from_bits(slot.words()[1]));
        if z_c <= z_s {
            out.push(carried);
            carried = slot;
        } else {
            out.push(slot);
        }
    }
    (out, carried)
}

// ---------------------------------------------------------------------------------------
// HT tails

/// An HT tail layout: where each field lies in the tail's 8 bytes read as one
/// little-endian `u64`. Bits that belong to no field are spare: ignored on read, kept on
/// write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TailLayout {
    /// `(lowest bit, width)` of the R, G, B sums, the alpha sum and the count.
    pub fields: [(u32, u32); 5],
}

/// The paper's tail (`mlab::hybrid::PaperTail` docs): `word0` = R 0..10, G 10..20,
/// B 20..30, spare 30..32; `word1` = alpha 0..16, count 16..32; as one LE `u64` the alpha
/// sum is at bit 32 and the count at 48.
pub const PAPER_TAIL: TailLayout = TailLayout {
    fields: [(0, 10), (10, 10), (20, 10), (32, 16), (48, 16)],
};

/// The default tail (`mlab::Tail` docs), one LE `u64`: R 0..13, G 13..26, B 26..39,
/// alpha 39..53, count 53..64; no spare bit.
pub const WIDE_TAIL: TailLayout = TailLayout {
    fields: [(0, 13), (13, 13), (26, 13), (39, 14), (53, 11)],
};

impl TailLayout {
    /// Largest value of field `i` (all its bits set).
    pub fn max(self, i: usize) -> u64 {
        (1u64 << self.fields[i].1) - 1
    }

    /// The bits of the `u64` that belong to no field.
    pub fn spare_mask(self) -> u64 {
        !self
            .fields
            .iter()
            .fold(0u64, |m, &(shift, bits)| m | ((1u64 << bits) - 1) << shift)
    }

    /// The fields `[r, g, b, alpha, count]` of 8 tail bytes.
    pub fn fields(self, bytes: [u8; 8]) -> [u64; 5] {
        let v = u64::from_le_bytes(bytes);
        core::array::from_fn(|i| (v >> self.fields[i].0) & self.max(i))
    }

    /// The 8 bytes holding `fields` (each at most its maximum), with the spare bits of
    /// `spare_from`; packed here, not by the kernel.
    pub fn pack(self, fields: [u64; 5], spare_from: [u8; 8]) -> [u8; 8] {
        let mut v = u64::from_le_bytes(spare_from) & self.spare_mask();
        for (i, &f) in fields.iter().enumerate() {
            assert!(f <= self.max(i), "field {i} = {f} does not fit {self:?}");
            v |= f << self.fields[i].0;
        }
        v.to_le_bytes()
    }

    /// Some field at its maximum (`TailFormat::saturated`).
    pub fn saturated(self, bytes: [u8; 8]) -> bool {
        let f = self.fields(bytes);
        (0..5).any(|i| f[i] == self.max(i))
    }
}

/// The expected tail fields after adding `rows` to a tail with fields `start` (exact sums,
/// each field saturating at its maximum in `layout`): `[r, g, b, alpha, count]`. Rows with
/// no color and `T = 255` are skipped.
pub fn ref_tail_fields(layout: TailLayout, start: [u64; 5], rows: &[Row]) -> [u64; 5] {
    let mut s = start;
    for r in rows {
        let ([cr, cg, cb], t) = (r.color(), r.transmittance());
        if [cr, cg, cb, t] == [0, 0, 0, 255] {
            continue;
        }
        s[0] += u64::from(cr);
        s[1] += u64::from(cg);
        s[2] += u64::from(cb);
        s[3] += u64::from(255 - t);
        s[4] += 1;
    }
    core::array::from_fn(|i| s[i].min(layout.max(i)))
}

/// Hybrid Transparency by sorting: the head is the `k` nearest rows (padded with empty
/// rows), the tail the saturated sums of the others, packed in `layout`.
pub fn ref_hybrid(k: usize, rows: &[Row], layout: TailLayout) -> (Vec<Row>, [u8; 8]) {
    let depths: Vec<f32> = rows.iter().map(|r| r.depth()).collect();
    let order = front_to_back(&depths);
    let mut head: Vec<Row> = order.iter().take(k).map(|&i| rows[i]).collect();
    head.resize(k, Row::EMPTY);
    let rest: Vec<Row> = order.iter().skip(k).map(|&i| rows[i]).collect();
    (head, layout.pack(ref_tail_fields(layout, [0; 5], &rest), [0; 8]))
}

/// Eq. 5 in f64 over rows in the given order (no sorting).
pub fn composite_rows_f64(rows: &[Row]) -> ([f64; 3], f64) {
    let mut color = [0.0f64; 3];
    let mut v = 1.0f64;
    for r in rows {
        let b = r.to_bytes();
        for i in 0..3 {
            color[i] += f64::from(b[i]) / 255.0 * v;
        }
        v *= f64::from(b[3]) / 255.0;
    }
    (color, v)
}

/// Bavoil-Myers tail resolve in f64 from the tail fields (as the kernel documents it):
/// `(color, transmittance)`.
pub fn tail_f64(fields: [u64; 5]) -> ([f64; 3], f64) {
    let [r, g, b, a, n] = fields;
    if [r, g, b, a, n] == [0; 5] {
        return ([0.0; 3], 1.0);
    }
    let n = n.max(1) as f64;
    let s_a = a as f64 / 255.0;
    let mean = (s_a / n).min(1.0);
    let t = (1.0 - mean).powf(n);
    let scale = if a == 0 { 1.0 } else { (1.0 - t) / s_a };
    ([r, g, b].map(|c| c as f64 / 255.0 * scale), t)
}

/// The models against the literal examples and properties of the kernel's documentation
/// (`cargo test --manifest-path fuzz/Cargo.toml`), so that a reference cannot drift
/// along with the kernel.
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tails_match_the_documented_bytes() {
        let row = Row::new([255, 2, 3], 128, 5.0);
        // `PaperTail` docs: words [255 | 2 << 10 | 3 << 20, 127 | 1 << 16].
        let f = ref_tail_fields(PAPER_TAIL, [0; 5], &[row]);
        assert_eq!(f, [255, 2, 3, 127, 1]);
        assert_eq!(
            PAPER_TAIL.pack(f, [0; 8]),
            [0xff, 0x08, 0x30, 0x00, 0x7f, 0x00, 0x01, 0x00]
        );
        assert_eq!(PAPER_TAIL.spare_mask(), 0b11 << 30);
        // `Tail` docs: 255 | 2 << 13 | 3 << 26 | 127 << 39 | 1 << 53.
        let f = ref_tail_fields(WIDE_TAIL, [0; 5], &[row]);
        assert_eq!(
            WIDE_TAIL.pack(f, [0xff; 8]),
            [0xff, 0x40, 0x00, 0x0c, 0x80, 0x3f, 0x20, 0x00]
        );
        assert_eq!(WIDE_TAIL.spare_mask(), 0, "the wide tail has no spare bit");
        // tests/layout.rs: R 0x1abc, G 0x155, B 0x1001, alpha 0x2fed, count 0x587.
        let b = WIDE_TAIL.pack([0x1abc, 0x155, 0x1001, 0x2fed, 0x587], [0; 8]);
        assert_eq!(u64::from_le_bytes(b), 0xb0f7_f6c0_042a_babc);
        assert_eq!(WIDE_TAIL.fields(b), [0x1abc, 0x155, 0x1001, 0x2fed, 0x587]);
        // Saturation: every field stops at its maximum.
        let many = vec![Row::new([255; 3], 0, 1.0); 70];
        assert_eq!(ref_tail_fields(WIDE_TAIL, [0; 5], &many), [8191, 8191, 8191, 16383, 70]);
        assert_eq!(
            ref_tail_fields(PAPER_TAIL, [0; 5], &many),
            [1023, 1023, 1023, 70 * 255, 70]
        );
        assert_eq!(
            ref_tail_fields(WIDE_TAIL, [0, 0, 0, 0, 2047], &[Row::new([1, 0, 0], 255, 1.0)]),
            [1, 0, 0, 0, 2047]
        );
        // Invisible rows are skipped.
        assert_eq!(
            ref_tail_fields(WIDE_TAIL, [0; 5], &[Row::new([0; 3], 255, 1.0)]),
            [0; 5]
        );
    }

    #[test]
    fn merges_match_the_documented_examples() {
        // `merge_with` docs.
        let front = Row::new([100, 0, 0], 128, 1.0);
        let back = Row::new([0, 200, 0], 0, 2.0);
        assert_eq!(ref_merge(front, back), Row::new([100, 100, 0], 0, 1.0));
        // `merge` docs (unbiased): 200 * 128 / 255 = 100.39 rounds to 100 or 101.
        // T_front 128 is below the centroid threshold (160): the depth stays the front's.
        let m = ref_merge_unbiased(front, back, 0x1234_5678);
        assert_eq!((m.transmittance(), m.depth()), (0, 1.0));
        assert!(m.color()[1] == 100 || m.color()[1] == 101);
        assert_eq!(ref_merge_unbiased(front, Row::EMPTY, 7), front);
        // T_front 204 (alpha 0.2) over an opaque back: the back's share of the opacity is
        // 0.8 / (0.2 + 0.8), w = floor(256 * 204 * 255 / (255 * 51 + 204 * 255)) = 204,
        // and 1.0 -> 2.0 is 2^23 keys: z = 1.0 + floor(2^23 * 204 / 256) / 2^23.
        let m = ref_merge_unbiased(Row::new([10, 0, 0], 204, 1.0), back, 0);
        assert_eq!(m.depth(), 1.0 + ((8_388_608u64 * 204 / 256) as f32) / 8_388_608.0);
    }

    #[test]
    fn lowbias32_and_the_hash() {
        // Bijective on a sample, 0 fixed, the hash the composition of the docs.
        assert_eq!(ref_lowbias32(0), 0);
        assert_eq!(ref_lowbias32(1), mlab::lowbias32(1));
        let mut seen = std::collections::HashSet::new();
        for x in 0..100_000u32 {
            assert!(seen.insert(ref_lowbias32(x.wrapping_mul(2_654_435_761))));
        }
        assert_eq!(ref_fragment_hash(5, 9), ref_lowbias32(5 ^ ref_lowbias32(9)));
    }

    #[test]
    fn merge_dither_is_nearly_uniform() {
        // `merge_dither` docs: each d in 0..=254 has 257 or 258 of the 65536 values of s.
        let mut hist = [0u32; 255];
        for s in 0..65536u64 {
            hist[(s * 255 / 65536) as usize] += 1;
        }
        assert!(hist.iter().all(|&n| n == 257 || n == 258));
        assert_eq!(ref_merge_dither(0xffff_0000), 0);
        assert_eq!(ref_merge_dither(0x0000_ffff), 254);
    }

    #[test]
    fn unbiased_products_are_unbiased_and_within_one_step() {
        // Over the 255 dithers, the mean of floor((p + d) / 255) is p / 255 exactly, and
        // each result is within (p/255 - 1, p/255 + 254/255].
        for p in (0..=255 * 255).step_by(97) {
            let sum: u32 = (0..=254).map(|d| (p + d) / 255).sum();
            assert_eq!(sum, p, "p = {p}");
            for d in 0..=254 {
                let err = f64::from((p + d) / 255) - f64::from(p) / 255.0;
                assert!(err > -1.0 && err <= 254.0 / 255.0 + 1e-12, "p = {p}, d = {d}");
            }
        }
    }

    #[test]
    fn fragment_dither_range_and_exact_bytes() {
        let mut x = 0x1234_5678u32;
        for _ in 0..10_000 {
            x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let k = x % 256;
            let v = k as f32 / 255.0;
            let c = [v, (x >> 8) as f32 / u32::MAX as f32, 0.0];
            let _ = c;
            let u = ref_fragment_dither(x.rotate_left(5));
            assert!((1.0 / 512.0..=511.0 / 512.0).contains(&u), "{u}");
            // A value that is a byte quantizes to that byte.
            assert_eq!(u32::from(ref_byte(v, u)), k);
        }
    }
}
