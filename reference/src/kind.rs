//! The reference side of a pixel kind: what the fuzz targets (`lanes_masks`) and the kernel's
//! tests (`tests/spans.rs`, `tests/batch.rs`) need to know of [`mlab::Mlab`] and [`mlab::Ht`]
//! to check a framebuffer pixel by pixel, written once: [`RefKind`], with [`MlabKind`] and
//! [`HtKind`].
//!
//! A pixel is seen as its `SLOTS` row-sized slots, as pixel-major storage holds them (MLAB:
//! the `M` rows; HT: the `K` head rows, then the tail's 8 bytes as a row). The inserts are
//! the reference models' (Listing 1 with [`Model::ref_merge`], Listing 2 with the reference
//! tail layout), for any slot contents; the resolves are the kernel's scalar per-pixel
//! resolve (f32, which the framebuffers' span resolves must equal bit for bit) and the
//! reference integer resolve ([`crate::resolve_int`]); [`RefKind::lanes_insert`] calls the
//! kernel's lanes insert, the other side of the lanes-vs-scalar checks (as [`crate::lanes`]).

use core::marker::PhantomData;

use mlab::framebuffer::Pixel;
use mlab::lanes::{self, HybridSpan, LANES};
use mlab::{Background, Fragment, Ht, Hybrid, Mlab, Resolved, Row, TailFormat, resolve_rows};

use crate::model::{Model, ref_bubble, ref_fragment_hash, ref_key, ref_row_hash, ref_tail_fields};

/// The limit of a resolved HT tail's color: the documented `COLOR_MAX * (1/255)` in f32 of
/// the arithmetic's tail (`1023` for the paper's, `8191` for the wide one), with the color
/// maximum taken from the reference layout (equal to the kernel's `TailFormat::COLOR_MAX`,
/// checked by the fuzz target `rows_from_bytes`).
pub fn tail_color_limit<A: Model>() -> f32 {
    A::TAIL.max(0) as f32 * (1.0 / 255.0)
}

/// The reference side of a pixel kind of the kernel ([`RefKind::P`]): one pixel's slots
/// (see the module docs) inserted into, resolved and cleared by the reference, and compared
/// with what the kernel's framebuffers hold.
pub trait RefKind {
    /// The kernel's pixel kind.
    type P: Pixel<Arith = Self::A>;
    /// Its arithmetic, with its reference model.
    type A: Model;
    /// Row-sized slots per pixel.
    const SLOTS: usize = <Self::P as Pixel>::ROWS;

    /// Largest resolved color of one pixel (`M`, or `K` plus the tail's limit).
    fn max_color() -> f32;
    /// The reference insert (Listing 1 or 2) into one pixel's slots, of any contents, of a
    /// row inserted with hash `h` (only MLAB's merge reads it).
    fn ref_insert(slots: &mut [Row], row: Row, h: u32);
    /// The kernel's scalar resolve of one pixel's slots (Eq. 5, or head and tail).
    fn ref_resolve(slots: &[Row]) -> Resolved;
    /// What `Framebuffer::resolve_rgba8` writes for one pixel's slots: the reference integer
    /// resolve ([`crate::resolve_int`]), MLAB's or HT's.
    fn ref_rgba8(slots: &[Row], bg: Background) -> [u8; 4];
    /// Make one pixel's slots an empty pixel.
    fn cleared(slots: &mut [Row]);
    /// One pixel's contents (`Grid::pixel`) as its `SLOTS` rows (HT: head rows, then the tail).
    fn slots(value: <Self::P as Pixel>::Value) -> Vec<Row>;
    /// The kernel's lanes insert (`mlab::lanes`) of `rows` with `hashes` in the lanes of
    /// `mask`, on a layer-major span of `SLOTS` layers (`span[j][lane]`; HT: the tails as
    /// rows in the last layer).
    fn lanes_insert(span: &mut [[Row; LANES]], rows: &[Row; LANES], hashes: &[u32; LANES], mask: u8);

    /// [`RefKind::ref_insert`] of a row as `Framebuffer::insert_row` inserts it into the
    /// pixel of id `pixel` (with the row's hash).
    fn ref_insert_row(slots: &mut [Row], row: Row, pixel: u32) {
        Self::ref_insert(slots, row, ref_row_hash(row, pixel));
    }
    /// [`RefKind::ref_insert`] of a valid fragment as `Framebuffer::insert` inserts it into
    /// the pixel of id `pixel` (the reference quantization and the fragment's hash).
    fn ref_insert_fragment(slots: &mut [Row], f: &Fragment, pixel: u32) {
        let h = ref_fragment_hash(ref_key(f), pixel);
        Self::ref_insert(slots, Self::A::ref_row(f, pixel), h);
    }
}

/// MLAB with `M` rows per pixel in the arithmetic `A`.
pub struct MlabKind<const M: usize, A>(PhantomData<A>);
/// HT with `K` head rows and a tail per pixel in the arithmetic `A`.
pub struct HtKind<const K: usize, A>(PhantomData<A>);

impl<const M: usize, A: Model> RefKind for MlabKind<M, A> {
    type P = Mlab<M, A>;
    type A = A;
    fn max_color() -> f32 {
        M as f32
    }
    fn ref_insert(slots: &mut [Row], row: Row, h: u32) {
        let (mut rows, pushed) = ref_bubble(slots, row);
        let last = rows[M - 1];
        rows[M - 1] = A::ref_merge(last, pushed, h);
        slots.copy_from_slice(&rows);
    }
    fn ref_resolve(slots: &[Row]) -> Resolved {
        resolve_rows(slots)
    }
    fn ref_rgba8(slots: &[Row], bg: Background) -> [u8; 4] {
        crate::resolve_int::rgba8(slots, bg)
    }
    fn cleared(slots: &mut [Row]) {
        slots.fill(Row::EMPTY);
    }
    fn slots(value: [Row; M]) -> Vec<Row> {
        value.to_vec()
    }
    fn lanes_insert(span: &mut [[Row; LANES]], rows: &[Row; LANES], hashes: &[u32; LANES], mask: u8) {
        let mut s: [[Row; LANES]; M] = core::array::from_fn(|j| span[j]);
        lanes::mlab_insert_hashed::<A, M>(&mut s, rows, hashes, mask);
        span.copy_from_slice(&s);
    }
}

/// An HT tail stored as a row (its 8 bytes), and back.
fn tail_of<A: Model>(slot: Row) -> A::Tail {
    <A::Tail as TailFormat>::from_bytes(slot.to_bytes())
}

impl<const K: usize, A: Model> RefKind for HtKind<K, A> {
    type P = Ht<K, A>;
    type A = A;
    fn max_color() -> f32 {
        K as f32 + tail_color_limit::<A>()
    }
    fn ref_insert(slots: &mut [Row], row: Row, _: u32) {
        let tail = slots[K].to_bytes();
        let (head, pushed) = ref_bubble(&slots[..K], row);
        slots[..K].copy_from_slice(&head);
        let t = A::TAIL.pack(ref_tail_fields(A::TAIL, A::TAIL.fields(tail), &[pushed]), tail);
        slots[K] = Row::from_bytes(t);
    }
    fn ref_resolve(slots: &[Row]) -> Resolved {
        Hybrid::<K, A>::from_parts(core::array::from_fn(|i| slots[i]), tail_of::<A>(slots[K])).resolve()
    }
    fn ref_rgba8(slots: &[Row], bg: Background) -> [u8; 4] {
        crate::resolve_int::ht_rgba8(&slots[..K], tail_of::<A>(slots[K]), bg)
    }
    fn cleared(slots: &mut [Row]) {
        slots[..K].fill(Row::EMPTY);
        slots[K] = Row::from_bytes([0; 8]);
    }
    fn slots((head, tail): ([Row; K], A::Tail)) -> Vec<Row> {
        let mut v = head.to_vec();
        v.push(Row::from_bytes(tail.to_bytes()));
        v
    }
    fn lanes_insert(span: &mut [[Row; LANES]], rows: &[Row; LANES], _: &[u32; LANES], mask: u8) {
        let mut s = HybridSpan::<K, A> {
            head: core::array::from_fn(|j| span[j]),
            tails: span[K].map(tail_of::<A>),
        };
        lanes::hybrid_insert(&mut s, rows, mask);
        span[..K].copy_from_slice(&s.head);
        span[K] = s.tails.map(|t| Row::from_bytes(t.to_bytes()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mlab::{Framebuffer, Grid, Paper, PixelMajor, Unbiased};

    /// A few rows: fragments' rows at tied and distinct depths, and arbitrary bytes.
    fn rows() -> Vec<Row> {
        let mut v: Vec<Row> = (0..40u8)
            .map(|i| Row::new([i * 3, i, 255 - i * 5], 255 - i * 6, f32::from(i % 7) * 0.5))
            .collect();
        v.push(Row::from_bytes([0xab, 0xcd, 0xef, 0x01, 0xff, 0xff, 0xff, 0xff]));
        v.push(Row::from_bytes([9, 8, 7, 6, 5, 4, 3, 2]));
        v
    }

    /// The reference insert, resolve, RGBA8 and clear against a pixel-major grid of 3 x 2
    /// pixels, and the lanes insert against the reference insert lane by lane.
    fn check<K: RefKind>() {
        let (w, h) = (3u32, 2u32);
        let mut storage = vec![Row::EMPTY; Grid::<K::P, PixelMajor>::rows_needed(w, h).unwrap()];
        let mut fb = Grid::<K::P, PixelMajor>::new_cleared(&mut storage, w, h).unwrap();
        let mut model = vec![Row::EMPTY; storage_len::<K>(w, h)];
        model.chunks_exact_mut(K::SLOTS).for_each(K::cleared);
        let bg = Background::Opaque(mlab::glam::Vec3::new(0.2, 0.5, 0.7));
        for (i, &row) in rows().iter().enumerate() {
            let p = i as u32 % (w * h);
            fb.insert_row(p % w, p / w, row).unwrap();
            let slots = &mut model[p as usize * K::SLOTS..][..K::SLOTS];
            K::ref_insert_row(slots, row, p);
            assert_eq!(K::slots(fb.pixel(p % w, p / w).unwrap()), slots.to_vec(), "row {i}");
            assert_eq!(fb.resolve(p % w, p / w), Ok(K::ref_resolve(slots)));
            let mut out = vec![[0u8; 4]; (w * h) as usize];
            fb.resolve_rgba8(&mut out, bg).unwrap();
            assert_eq!(out[p as usize], K::ref_rgba8(slots, bg));
        }
        let f = Fragment::straight(mlab::glam::Vec3::new(0.9, 0.5, 0.2), 0.03, 0.25).unwrap();
        fb.insert(1, 1, &f).unwrap();
        K::ref_insert_fragment(&mut model[4 * K::SLOTS..][..K::SLOTS], &f, 4);
        assert_eq!(
            K::slots(fb.pixel(1, 1).unwrap()),
            model[4 * K::SLOTS..][..K::SLOTS].to_vec()
        );
        // Lanes: pixel `lane` of the model in each lane, every other lane on.
        let mut span: Vec<[Row; LANES]> = (0..K::SLOTS)
            .map(|j| core::array::from_fn(|l| model[l % 6 * K::SLOTS + j]))
            .collect();
        let new = rows()[5];
        let hashes = core::array::from_fn(|l| ref_row_hash(new, l as u32));
        K::lanes_insert(&mut span, &[new; LANES], &hashes, 0b0101_0101);
        for lane in 0..LANES {
            let mut want = model[lane % 6 * K::SLOTS..][..K::SLOTS].to_vec();
            if lane % 2 == 0 {
                K::ref_insert(&mut want, new, hashes[lane]);
            }
            let got: Vec<Row> = span.iter().map(|layer| layer[lane]).collect();
            assert_eq!(got, want, "lane {lane}");
        }
        fb.clear();
        K::cleared(&mut model[..K::SLOTS]);
        assert_eq!(K::slots(fb.pixel(0, 0).unwrap()), model[..K::SLOTS].to_vec());
        assert!(K::max_color() >= 1.0);
    }

    fn storage_len<K: RefKind>(w: u32, h: u32) -> usize {
        (w * h) as usize * K::SLOTS
    }

    #[test]
    fn kinds_match_the_kernel() {
        check::<MlabKind<1, Paper>>();
        check::<MlabKind<3, Unbiased>>();
        check::<HtKind<0, Unbiased>>();
        check::<HtKind<2, Paper>>();
        check::<HtKind<2, Unbiased>>();
    }
}
