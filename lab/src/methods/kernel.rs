//! MLAB and HT through the kernel's pixel-major framebuffers, fragment by fragment in
//! submission order, each keyed by its primitive's id ([`crate::stream::Frag::to_kernel`]:
//! the dithers hold still under camera motion), and the lab's [`Arith`] (which the `*_with` functions, here and in
//! [`super::lanes`], turn into the kernel's arithmetic type).

use super::catalog::{HT_SIZES, MLAB_SIZES};
use super::{BinnedStream, Image};
use mlab::glam::Vec3;
use mlab::{
    Arithmetic, Fragment, Framebuffer, HybridFramebuffer, MlabFramebuffer, Paper, Resolved, Row, TailFormat, Unbiased,
};

/// The kernel's arithmetic as a run-time value ([`mlab::ArithKind`]: `Paper` or `Unbiased`,
/// the default): how MLAB's merge rounds its unorm8 products, how a fragment is quantized to a
/// row, and the HT tail's layout. The lab turns it into the kernel's type only in the `*_with`
/// functions ([`mlab_with`], [`hybrid_with`], [`mlab_lanes_with`](super::mlab_lanes_with), ...).
pub use mlab::ArithKind as Arith;

/// A validated fragment quantized to a row as `arith` quantizes it in the pixel of id `pixel`
/// (`y * width + x`, as a framebuffer's `pixel_id`).
pub fn quantize(arith: Arith, fragment: &Fragment, pixel: u32) -> Row {
    let h = fragment.hash(pixel);
    match arith {
        Arith::Paper => Paper::quantize(fragment, h),
        Arith::Unbiased => Unbiased::quantize(fragment, h),
    }
}

fn kernel_image(
    binned: &BinnedStream,
    resolve: impl Fn(u32, u32) -> Result<Resolved, String>,
) -> Result<Image, String> {
    let s = binned.stream;
    let pixels = (0..s.height).flat_map(|y| (0..s.width).map(move |x| (x, y)));
    image_of(binned, pixels.map(|(x, y)| resolve(x, y)))
}

/// The image of the stream from its resolved pixels, row major: each over the background, and
/// its transmittance (the background's visibility).
pub(super) fn image_of(
    binned: &BinnedStream,
    resolved: impl Iterator<Item = Result<Resolved, String>>,
) -> Result<Image, String> {
    let s = binned.stream;
    let bg = Vec3::from(s.background);
    let mut rgb = Vec::with_capacity(s.pixels());
    let mut vis = Vec::with_capacity(s.pixels());
    for r in resolved {
        let r = r?;
        rgb.push(r.over(bg).to_array());
        vis.push(r.transmittance);
    }
    Ok(Image {
        width: s.width,
        height: s.height,
        rgb,
        vis,
    })
}

pub(super) fn err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

/// MLAB with the kernel's framebuffer view in arithmetic `A`, in submission order (or, when
/// `sorted`, each pixel's fragments front to back).
pub fn run_mlab<const M: usize, A: Arithmetic>(binned: &BinnedStream, sorted: bool) -> Result<Image, String> {
    let s = binned.stream;
    let mut storage = vec![Row::EMPTY; MlabFramebuffer::<M, A>::rows_needed(s.width, s.height).map_err(err)?];
    let mut fb = MlabFramebuffer::<M, A>::new(&mut storage, s.width, s.height).map_err(err)?;
    fb.clear();
    let insert = |fb: &mut MlabFramebuffer<M, A>, i: usize| -> Result<(), String> {
        let f = &s.frags[i];
        let frag = f.to_kernel().map_err(|e| format!("fragment {i}: {e}"))?;
        fb.insert(f.pixel % s.width, f.pixel / s.width, &frag).map_err(err)
    };
    if sorted {
        for &i in &binned.sorted.index {
            insert(&mut fb, i as usize)?;
        }
    } else {
        for i in 0..s.frags.len() {
            insert(&mut fb, i)?;
        }
    }
    kernel_image(binned, |x, y| fb.resolve(x, y).map_err(err))
}

/// Hybrid Transparency with the kernel's framebuffer view in arithmetic `A` (which picks the
/// tail), in submission order; also the number of pixels whose tail has a field at its
/// maximum (`saturated`).
pub fn run_hybrid<const K: usize, A: Arithmetic>(binned: &BinnedStream) -> Result<(Image, usize), String> {
    let s = binned.stream;
    let mut storage = vec![Row::EMPTY; HybridFramebuffer::<K, A>::rows_needed(s.width, s.height).map_err(err)?];
    let mut fb = HybridFramebuffer::<K, A>::new(&mut storage, s.width, s.height).map_err(err)?;
    // The tail slot of `Row::EMPTY` bytes is not an empty tail: clear for a new frame.
    fb.clear();
    for (i, f) in s.frags.iter().enumerate() {
        let frag = f.to_kernel().map_err(|e| format!("fragment {i}: {e}"))?;
        fb.insert(f.pixel % s.width, f.pixel / s.width, &frag).map_err(err)?;
    }
    let mut saturated = 0;
    for y in 0..s.height {
        for x in 0..s.width {
            saturated += usize::from(fb.pixel(x, y).map_err(err)?.1.saturated());
        }
    }
    Ok((kernel_image(binned, |x, y| fb.resolve(x, y).map_err(err))?, saturated))
}

fn mlab_dyn<A: Arithmetic>(m: usize, binned: &BinnedStream, sorted: bool) -> Result<Image, String> {
    by_size!(
        m,
        [1, 2, 3, 4, 5, 6, 7, 8, 12, 16],
        run_mlab::<_, A>(binned, sorted),
        Err(format!("MLAB {m}: supported row counts are {MLAB_SIZES:?}"))
    )
}

fn hybrid_dyn<A: Arithmetic>(k: usize, binned: &BinnedStream) -> Result<(Image, usize), String> {
    by_size!(
        k,
        [0, 1, 2, 3, 4, 5, 6, 7, 11, 15],
        run_hybrid::<_, A>(binned),
        Err(format!("HT {k}: supported head sizes are {HT_SIZES:?}"))
    )
}

// Where the lab's `Arith` picks the kernel's arithmetic type (and in `lanes.rs`).

/// MLAB `m` with arithmetic `arith` (scalar kernel), in submission order.
pub fn mlab_with(m: usize, arith: Arith, binned: &BinnedStream) -> Result<Image, String> {
    match arith {
        Arith::Paper => mlab_dyn::<Paper>(m, binned, false),
        Arith::Unbiased => mlab_dyn::<Unbiased>(m, binned, false),
    }
}

/// MLAB `m` with arithmetic `arith`, fed each pixel's fragments front to back.
pub fn mlab_sorted_with(m: usize, arith: Arith, binned: &BinnedStream) -> Result<Image, String> {
    match arith {
        Arith::Paper => mlab_dyn::<Paper>(m, binned, true),
        Arith::Unbiased => mlab_dyn::<Unbiased>(m, binned, true),
    }
}

/// HT `k` with arithmetic `arith` (scalar kernel): the image and the number of pixels with a
/// saturated tail.
pub fn hybrid_with(k: usize, arith: Arith, binned: &BinnedStream) -> Result<(Image, usize), String> {
    match arith {
        Arith::Paper => hybrid_dyn::<Paper>(k, binned),
        Arith::Unbiased => hybrid_dyn::<Unbiased>(k, binned),
    }
}
