//! Reference models, written independently of the kernel's code: a defect model for
//! fragment validation, a `Vec`-based Listing 1 with an f64-rounded merge, a sort-and-sum
//! Hybrid Transparency, and an exact f64 per-pixel oracle.

use mlab::{FragmentError, Row};

use crate::input::{Ctor, RawFragment};

/// A set of [`FragmentError`]s (one bit per variant).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Defects(u16);

/// The bit of an error variant. `FragmentError` is `#[non_exhaustive]`: a new variant
/// fails here until the model learns it.
pub fn defect_bit(e: FragmentError) -> u16 {
    1 << match e {
        FragmentError::NanColor => 0,
        FragmentError::InfiniteColor => 1,
        FragmentError::NegativeColor => 2,
        FragmentError::ColorAboveOne => 3,
        FragmentError::NanAlpha => 4,
        FragmentError::AlphaOutOfRange => 5,
        FragmentError::NanDepth => 6,
        FragmentError::InfiniteDepth => 7,
        other => panic!("the defect model does not know {other:?}"),
    }
}

impl Defects {
    fn add(&mut self, e: FragmentError, present: bool) {
        if present {
            self.0 |= defect_bit(e);
        }
    }

    /// No defect.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// `e` is one of the defects.
    pub fn contains(self, e: FragmentError) -> bool {
        self.0 & defect_bit(e) != 0
    }
}

/// What a valid fragment must hold: premultiplied color and alpha, as f32, bit for bit.
#[derive(Clone, Copy, Debug)]
pub struct Expected {
    /// Premultiplied color.
    pub color: [f32; 3],
    /// Alpha.
    pub alpha: f32,
}

/// Every defect of the raw arguments (the kernel must return one of them, or `Ok` when
/// there is none), and the fields a valid fragment must hold.
pub fn defects(f: &RawFragment) -> (Defects, Expected) {
    let mut d = Defects::default();
    let a_in = f.a;
    d.add(FragmentError::NanAlpha, a_in.is_nan());
    d.add(
        FragmentError::AlphaOutOfRange,
        !a_in.is_nan() && !(0.0..=1.0).contains(&a_in),
    );
    let alpha = if f.ctor == Ctor::WithTransmittance {
        1.0 - a_in
    } else {
        a_in
    };
    d.add(FragmentError::NanColor, f.color.iter().any(|c| c.is_nan()));
    d.add(FragmentError::InfiniteColor, f.color.iter().any(|c| c.is_infinite()));
    d.add(FragmentError::NegativeColor, f.color.iter().any(|&c| c < 0.0));
    d.add(FragmentError::NanDepth, f.z.is_nan());
    d.add(FragmentError::InfiniteDepth, f.z.is_infinite());
    let color = if f.ctor == Ctor::Straight {
        f.color.map(|c| c * alpha)
    } else {
        f.color
    };
    d.add(FragmentError::ColorAboveOne, color.iter().any(|&c| c > 1.0));
    (d, Expected { color, alpha })
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

/// Listing 1 over a list of rows that holds only what was inserted (no empty rows), for
/// rows with finite depths: insert at the first position whose depth is not smaller, and
/// when the list is longer than `M` merge the last two.
#[derive(Clone, Debug)]
pub struct RefMlab {
    m: usize,
    rows: Vec<Row>,
}

impl RefMlab {
    /// An empty blending array of `m` rows.
    pub fn new(m: usize) -> Self {
        RefMlab { m, rows: Vec::new() }
    }

    /// Insert a row with a finite depth.
    pub fn insert(&mut self, row: Row) {
        let pos = self
            .rows
            .iter()
            .position(|b| row.depth() <= b.depth())
            .unwrap_or(self.rows.len());
        self.rows.insert(pos, row);
        if self.rows.len() > self.m {
            let back = self.rows.pop().unwrap();
            let front = self.rows.pop().unwrap();
            self.rows.push(ref_merge(front, back));
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

/// The expected tail fields after adding `rows` to a tail with fields `start` (exact sums,
/// each field saturating): `[r, g, b, alpha, count]`. Rows with no color and `T = 255`
/// are skipped.
pub fn ref_tail_fields(start: [u64; 5], rows: &[Row]) -> [u64; 5] {
    let mut s = start;
    for r in rows {
        let [cr, cg, cb, t] = r.rgbt();
        if [cr, cg, cb, t] == [0, 0, 0, 255] {
            continue;
        }
        s[0] += u64::from(cr);
        s[1] += u64::from(cg);
        s[2] += u64::from(cb);
        s[3] += u64::from(255 - t);
        s[4] += 1;
    }
    [
        s[0].min(1023),
        s[1].min(1023),
        s[2].min(1023),
        s[3].min(65535),
        s[4].min(65535),
    ]
}

/// The 8 tail bytes for given fields and spare bits, packed here (not by the kernel).
pub fn ref_tail_bytes(f: [u64; 5], spare: u32) -> [u8; 8] {
    let w0 = f[0] as u32 | (f[1] as u32) << 10 | (f[2] as u32) << 20 | spare << 30;
    let w1 = f[3] as u32 | (f[4] as u32) << 16;
    let mut b = [0; 8];
    b[..4].copy_from_slice(&w0.to_le_bytes());
    b[4..].copy_from_slice(&w1.to_le_bytes());
    b
}

/// Stable order of a pixel's fragments: by depth, later submission in front on ties.
/// `items` are `(depth, submission index, payload)`.
pub fn sort_front_to_back<T: Copy>(items: &mut [(f32, usize, T)]) {
    items.sort_by(|a, b| a.0.partial_cmp(&b.0).expect("finite depths").then(b.1.cmp(&a.1)));
}

/// Hybrid Transparency by sorting: the head is the `k` nearest rows (padded with empty
/// rows), the tail the saturated sums of the others.
pub fn ref_hybrid(k: usize, rows: &[Row]) -> (Vec<Row>, [u8; 8]) {
    let mut items: Vec<(f32, usize, Row)> = rows.iter().enumerate().map(|(i, r)| (r.depth(), i, *r)).collect();
    sort_front_to_back(&mut items);
    let mut head: Vec<Row> = items.iter().take(k).map(|x| x.2).collect();
    head.resize(k, Row::EMPTY);
    let rest: Vec<Row> = items.iter().skip(k).map(|x| x.2).collect();
    (head, ref_tail_bytes(ref_tail_fields([0; 5], &rest), 0))
}

/// The exact per-pixel oracle: fragments `(premultiplied color, alpha, depth)` in
/// submission order, sorted front to back (later in front on ties), composited in f64.
/// Returns `(color, transmittance)`.
pub fn oracle(frags: &[([f32; 3], f32, f32)]) -> ([f64; 3], f64) {
    let mut items: Vec<(f32, usize, ([f32; 3], f32))> =
        frags.iter().enumerate().map(|(i, &(c, a, z))| (z, i, (c, a))).collect();
    sort_front_to_back(&mut items);
    let mut color = [0.0f64; 3];
    let mut v = 1.0f64;
    for (_, _, (c, a)) in items {
        for i in 0..3 {
            color[i] += f64::from(c[i]) * v;
        }
        v *= 1.0 - f64::from(a);
    }
    (color, v)
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
