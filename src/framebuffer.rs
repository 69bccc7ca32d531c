//! Framebuffer views over borrowed storage: no allocation, every size and coordinate
//! checked, errors instead of panics.
//!
//! Storage is a caller-owned `&mut [Row]`, pixel-major and row-major: pixel `(x, y)` owns
//! the rows `[(y * width + x) * R, (y * width + x + 1) * R)` where `R` is the number of
//! rows per pixel (`M` for MLAB, `K + 1` for Hybrid Transparency, whose last row-sized
//! slot holds the 8-byte [`Tail`](crate::Tail)). The storage can be handed to a GPU as bytes or
//! little-endian words with [`MlabFramebuffer::as_bytes`] / [`MlabFramebuffer::as_words`]
//! (`RG32Uint` texels).
//!
//! ```
//! use glam::Vec3;
//! use mlab::{Background, Fragment, MlabFramebuffer, Row};
//! let mut storage = vec![Row::EMPTY; 4 * 2 * 2]; // 4x2 pixels, 2 rows each
//! let mut fb = MlabFramebuffer::<2>::new(&mut storage, 4, 2)?;
//! fb.insert(1, 1, &Fragment::straight(Vec3::X, 1.0, 5.0)?)?;
//! assert!(fb.insert(4, 0, &Fragment::straight(Vec3::X, 1.0, 5.0)?).is_err());
//! let mut out = [[0u8; 4]; 8];
//! fb.resolve_rgba8(&mut out, Background::Opaque(Vec3::ZERO))?;
//! assert_eq!(out[5], [255, 0, 0, 255]);
//! assert_eq!(out[0], [0, 0, 0, 255]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use glam::Vec4;
use half::f16;

use core::marker::PhantomData;

use crate::arith::{Arithmetic, Unbiased};
use crate::fragment::Fragment;
use crate::hybrid::{self, TailFormat};
use crate::mlab;
use crate::resolve::{Background, Resolved, resolve_rows, to_rgba8, to_rgba16f};
use crate::row::Row;

/// Why a framebuffer operation was refused. Nothing was changed when one is returned.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum FramebufferError {
    /// The storage slice does not hold exactly `width * height * rows_per_pixel` rows.
    StorageLength {
        /// Rows required.
        expected: usize,
        /// Rows given.
        actual: usize,
    },
    /// `width * height * rows_per_pixel` does not fit in `usize`.
    SizeOverflow,
    /// A coordinate lies outside the framebuffer.
    OutOfBounds {
        /// Column asked for.
        x: u32,
        /// Line asked for.
        y: u32,
        /// Framebuffer width.
        width: u32,
        /// Framebuffer height.
        height: u32,
    },
    /// An output slice does not hold exactly `width * height` pixels.
    OutputLength {
        /// Pixels required.
        expected: usize,
        /// Pixels given.
        actual: usize,
    },
}

impl core::fmt::Display for FramebufferError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            FramebufferError::StorageLength { expected, actual } => {
                write!(f, "framebuffer storage holds {actual} rows, expected {expected}")
            }
            FramebufferError::SizeOverflow => f.write_str("framebuffer size overflows usize"),
            FramebufferError::OutOfBounds { x, y, width, height } => {
                write!(f, "pixel ({x}, {y}) is outside the {width}x{height} framebuffer")
            }
            FramebufferError::OutputLength { expected, actual } => {
                write!(f, "output holds {actual} pixels, expected {expected}")
            }
        }
    }
}

impl core::error::Error for FramebufferError {}

/// Width and height with the checks shared by every framebuffer view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Dims {
    pub(crate) width: u32,
    pub(crate) height: u32,
}

impl Dims {
    fn pixels(self) -> Option<usize> {
        (self.width as usize).checked_mul(self.height as usize)
    }

    /// `width * height * rows_per_pixel`, or [`FramebufferError::SizeOverflow`].
    fn rows_needed(self, rows_per_pixel: usize) -> Result<usize, FramebufferError> {
        self.pixels()
            .and_then(|p| p.checked_mul(rows_per_pixel))
            .ok_or(FramebufferError::SizeOverflow)
    }

    /// Check that `storage_len` is exactly the rows needed.
    fn check_storage(self, rows_per_pixel: usize, storage_len: usize) -> Result<(), FramebufferError> {
        let expected = self.rows_needed(rows_per_pixel)?;
        if expected != storage_len {
            return Err(FramebufferError::StorageLength {
                expected,
                actual: storage_len,
            });
        }
        Ok(())
    }

    /// The error for pixel `(x, y)` outside these dimensions.
    pub(crate) fn out_of_bounds(self, x: u32, y: u32) -> FramebufferError {
        FramebufferError::OutOfBounds {
            x,
            y,
            width: self.width,
            height: self.height,
        }
    }

    /// Pixel index of `(x, y)`.
    fn index(self, x: u32, y: u32) -> Result<usize, FramebufferError> {
        if x >= self.width || y >= self.height {
            return Err(self.out_of_bounds(x, y));
        }
        Ok(y as usize * self.width as usize + x as usize)
    }

    /// Check an output slice length: exactly `width * height` pixels.
    pub(crate) fn check_output(self, len: usize) -> Result<(), FramebufferError> {
        let expected = self.pixels().ok_or(FramebufferError::SizeOverflow)?;
        if len != expected {
            return Err(FramebufferError::OutputLength { expected, actual: len });
        }
        Ok(())
    }
}

/// Resolve every pixel into `out`, converting each with `write`.
fn resolve_each<T>(
    dims: Dims,
    out: &mut [T],
    resolved: impl Iterator<Item = Resolved>,
    background: Background,
    write: impl Fn(Vec4) -> T,
) -> Result<(), FramebufferError> {
    dims.check_output(out.len())?;
    for (o, r) in out.iter_mut().zip(resolved) {
        *o = write(r.pixel(background));
    }
    Ok(())
}

/// The GPU-upload views shared by both framebuffers.
macro_rules! storage_views {
    () => {
        /// The storage as rows (pixel-major, row-major).
        pub fn as_rows(&self) -> &[Row] {
            bytemuck::cast_slice(self.rows_flat())
        }

        /// The storage as bytes (8 per row; layout in [`Row`]).
        pub fn as_bytes(&self) -> &[u8] {
            bytemuck::cast_slice(self.rows_flat())
        }

        /// The storage as native-endian `u32` words, two per row (`RG32Uint`). On
        /// little-endian hosts these are the words of [`Row::words`].
        pub fn as_words(&self) -> &[u32] {
            bytemuck::cast_slice(self.rows_flat())
        }

        /// Width in pixels.
        pub fn width(&self) -> u32 {
            self.dims.width
        }

        /// Height in pixels.
        pub fn height(&self) -> u32 {
            self.dims.height
        }

        /// Resolve every pixel into premultiplied or opaque RGBA f32 (see [`Background`]).
        pub fn resolve_into(&self, out: &mut [Vec4], background: Background) -> Result<(), FramebufferError> {
            resolve_each(self.dims, out, self.resolved(), background, |p| p)
        }

        /// Resolve every pixel into RGBA8 ([`to_rgba8`]).
        pub fn resolve_rgba8(&self, out: &mut [[u8; 4]], background: Background) -> Result<(), FramebufferError> {
            resolve_each(self.dims, out, self.resolved(), background, to_rgba8)
        }

        /// Resolve every pixel into RGBA16F ([`to_rgba16f`]).
        pub fn resolve_rgba16f(&self, out: &mut [[f16; 4]], background: Background) -> Result<(), FramebufferError> {
            resolve_each(self.dims, out, self.resolved(), background, to_rgba16f)
        }
    };
}

/// An MLAB framebuffer: `width * height` blending arrays of `M` rows over borrowed storage,
/// in the arithmetic `A` ([`Unbiased`] by default, [`Paper`](crate::Paper) for the paper's).
#[derive(Debug)]
pub struct MlabFramebuffer<'a, const M: usize, A: Arithmetic = Unbiased> {
    pixels: &'a mut [[Row; M]],
    dims: Dims,
    arithmetic: PhantomData<A>,
}

impl<'a, const M: usize, A: Arithmetic> MlabFramebuffer<'a, M, A> {
    /// Rows of storage needed for `width x height` pixels (`width * height * M`), or
    /// [`FramebufferError::SizeOverflow`].
    pub fn rows_needed(width: u32, height: u32) -> Result<usize, FramebufferError> {
        Dims { width, height }.rows_needed(M)
    }

    /// A view over `storage`, which must hold exactly `width * height * M` rows. The
    /// contents are kept (call [`clear`](Self::clear) for a new frame): rows from a previous
    /// frame or from arbitrary bytes are valid input.
    pub fn new(storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        let dims = Dims { width, height };
        dims.check_storage(M, storage.len())?;
        let () = mlab::AtLeastOne::<M>::OK;
        let actual = storage.len();
        // Cannot fail: the length is a multiple of M >= 1 and the alignment is Row's.
        let pixels: &mut [[Row; M]] =
            bytemuck::try_cast_slice_mut(storage).map_err(|_| FramebufferError::StorageLength {
                expected: actual,
                actual,
            })?;
        Ok(MlabFramebuffer {
            pixels,
            dims,
            arithmetic: PhantomData,
        })
    }

    /// [`new`](Self::new), then [`clear`](Self::clear).
    pub fn new_cleared(storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        let mut fb = Self::new(storage, width, height)?;
        fb.clear();
        Ok(fb)
    }

    fn rows_flat(&self) -> &[[Row; M]] {
        self.pixels
    }

    fn resolved(&self) -> impl Iterator<Item = Resolved> + '_ {
        self.pixels.iter().map(|p| resolve_rows(p))
    }

    /// Reset every pixel to empty rows.
    pub fn clear(&mut self) {
        self.pixels.fill([Row::EMPTY; M]);
    }

    /// Insert a fragment at `(x, y)` with Listing 1 (quantized by `A`).
    #[inline]
    pub fn insert(&mut self, x: u32, y: u32, fragment: &Fragment) -> Result<(), FramebufferError> {
        self.insert_row(x, y, A::quantize(fragment))
    }

    /// Insert a quantized row at `(x, y)` with Listing 1.
    #[inline]
    pub fn insert_row(&mut self, x: u32, y: u32, row: Row) -> Result<(), FramebufferError> {
        let i = self.dims.index(x, y)?;
        if let Some(p) = self.pixels.get_mut(i) {
            mlab::insert_with::<A, M>(p, row);
        }
        Ok(())
    }

    /// The blending array of pixel `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> Result<&[Row; M], FramebufferError> {
        let i = self.dims.index(x, y)?;
        self.pixels.get(i).ok_or(self.dims.out_of_bounds(x, y))
    }

    /// The blending array of pixel `(x, y)`, mutable.
    pub fn pixel_mut(&mut self, x: u32, y: u32) -> Result<&mut [Row; M], FramebufferError> {
        let i = self.dims.index(x, y)?;
        let d = self.dims;
        self.pixels.get_mut(i).ok_or(d.out_of_bounds(x, y))
    }

    /// Resolve one pixel (Eq. 5).
    pub fn resolve(&self, x: u32, y: u32) -> Result<Resolved, FramebufferError> {
        self.pixel(x, y).map(|p| resolve_rows(p))
    }

    storage_views!();
}

/// A Hybrid Transparency framebuffer: per pixel `K` head rows then one tail slot
/// (`K + 1` row-sized slots, `8 * (K + 1)` bytes) over borrowed storage, in the arithmetic
/// `A` (which picks the tail layout: [`Tail`](crate::Tail) by default).
#[derive(Debug)]
pub struct HybridFramebuffer<'a, const K: usize, A: Arithmetic = Unbiased> {
    rows: &'a mut [Row],
    dims: Dims,
    arithmetic: PhantomData<A>,
}

impl<'a, const K: usize, A: Arithmetic> HybridFramebuffer<'a, K, A> {
    /// Rows of storage needed for `width x height` pixels (`width * height * (K + 1)`).
    pub fn rows_needed(width: u32, height: u32) -> Result<usize, FramebufferError> {
        Dims { width, height }.rows_needed(K + 1)
    }

    /// A view over `storage`, which must hold exactly `width * height * (K + 1)` rows.
    /// Contents are kept. **Storage filled with [`Row::EMPTY`] is not a cleared HT
    /// framebuffer**: the tail slots would hold an empty row's bytes, which are not an empty
    /// [`Tail`](crate::Tail). Use [`new_cleared`](Self::new_cleared) (or [`clear`](Self::clear)) to start a
    /// frame.
    pub fn new(storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        let dims = Dims { width, height };
        dims.check_storage(K + 1, storage.len())?;
        Ok(HybridFramebuffer {
            rows: storage,
            dims,
            arithmetic: PhantomData,
        })
    }

    /// [`new`](Self::new), then [`clear`](Self::clear): the way to start a frame.
    pub fn new_cleared(storage: &'a mut [Row], width: u32, height: u32) -> Result<Self, FramebufferError> {
        let mut fb = Self::new(storage, width, height)?;
        fb.clear();
        Ok(fb)
    }

    fn rows_flat(&self) -> &[Row] {
        self.rows
    }

    fn split(pixel: &[Row]) -> ([Row; K], A::Tail) {
        let mut head = [Row::EMPTY; K];
        let mut tail = A::Tail::EMPTY;
        if let Some((t, h)) = pixel.split_last() {
            head.copy_from_slice(&h[..K.min(h.len())]);
            tail = A::Tail::from_bytes(t.to_bytes());
        }
        (head, tail)
    }

    fn resolved(&self) -> impl Iterator<Item = Resolved> + '_ {
        self.rows.chunks_exact(K + 1).map(|p| {
            let (head, tail) = Self::split(p);
            hybrid::resolve(&head, tail)
        })
    }

    /// Reset every pixel: empty head rows, empty tail.
    pub fn clear(&mut self) {
        for p in self.rows.chunks_exact_mut(K + 1) {
            if let Some((t, h)) = p.split_last_mut() {
                h.fill(Row::EMPTY);
                *t = Row::from_bytes(A::Tail::EMPTY.to_bytes());
            }
        }
    }

    fn pixel_slots(&self, x: u32, y: u32) -> Result<&[Row], FramebufferError> {
        let i = self.dims.index(x, y)?;
        self.rows
            .get(i * (K + 1)..(i + 1) * (K + 1))
            .ok_or(self.dims.out_of_bounds(x, y))
    }

    /// Insert a fragment at `(x, y)` with Listing 2 (quantized by `A`).
    #[inline]
    pub fn insert(&mut self, x: u32, y: u32, fragment: &Fragment) -> Result<(), FramebufferError> {
        self.insert_row(x, y, A::quantize(fragment))
    }

    /// Insert a quantized row at `(x, y)` with Listing 2.
    #[inline]
    pub fn insert_row(&mut self, x: u32, y: u32, row: Row) -> Result<(), FramebufferError> {
        let i = self.dims.index(x, y)?;
        if let Some(p) = self.rows.get_mut(i * (K + 1)..(i + 1) * (K + 1))
            && let Some((t, h)) = p.split_last_mut()
            && let Ok(head) = <&mut [Row; K]>::try_from(h)
        {
            let mut tail = A::Tail::from_bytes(t.to_bytes());
            hybrid::insert(head, &mut tail, row);
            *t = Row::from_bytes(tail.to_bytes());
        }
        Ok(())
    }

    /// Head rows and tail of pixel `(x, y)`.
    pub fn pixel(&self, x: u32, y: u32) -> Result<([Row; K], A::Tail), FramebufferError> {
        self.pixel_slots(x, y).map(Self::split)
    }

    /// Resolve one pixel.
    pub fn resolve(&self, x: u32, y: u32) -> Result<Resolved, FramebufferError> {
        self.pixel(x, y).map(|(h, t)| hybrid::resolve(&h, t))
    }

    storage_views!();
}
