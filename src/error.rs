//! One error for everything the crate refuses, so that `?` works in a function returning
//! `Result<_, mlab::Error>` on fragment constructors and framebuffer operations alike.

use crate::fragment::FragmentError;

/// A refused fragment or a refused framebuffer operation.
///
/// ```
/// use mlab::glam::Vec3;
/// use mlab::{Error, Fragment, Framebuffer, MlabFramebuffer, Row};
/// fn draw(storage: &mut [Row]) -> Result<(), Error> {
///     let mut fb = MlabFramebuffer::<2>::new_cleared(storage, 4, 4)?; // FramebufferError
///     fb.insert(1, 1, &Fragment::straight(Vec3::X, f32::NAN, 1.0)?)?; // FragmentError
///     Ok(())
/// }
/// let mut storage = vec![Row::EMPTY; 32];
/// assert!(matches!(draw(&mut storage), Err(Error::Fragment(_))));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Error {
    /// A fragment was refused ([`crate::Fragment`]'s constructors).
    Fragment(FragmentError),
    /// A framebuffer operation was refused.
    Framebuffer(FramebufferError),
}

impl core::fmt::Display for Error {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Error::Fragment(e) => e.fmt(f),
            Error::Framebuffer(e) => e.fmt(f),
        }
    }
}

impl core::error::Error for Error {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Error::Fragment(e) => Some(e),
            Error::Framebuffer(e) => Some(e),
        }
    }
}

impl From<FragmentError> for Error {
    fn from(e: FragmentError) -> Error {
        Error::Fragment(e)
    }
}

impl From<FramebufferError> for Error {
    fn from(e: FramebufferError) -> Error {
        Error::Framebuffer(e)
    }
}

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
    /// A run-time layer count that [`DynFramebuffer`](crate::DynFramebuffer) does not offer (see
    /// [`Layers::SIZES`](crate::Layers::SIZES)).
    UnsupportedLayers {
        /// Rows (MLAB) or head rows (HT) asked for.
        rows: usize,
    },
    /// Two framebuffers of different sizes ([`Grid::copy_from`](crate::Grid::copy_from)).
    SizeMismatch,
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
            FramebufferError::UnsupportedLayers { rows } => {
                write!(f, "{rows} rows per pixel is not one of the run-time sizes 1 to 8")
            }
            FramebufferError::SizeMismatch => f.write_str("framebuffers of different sizes"),
        }
    }
}

impl core::error::Error for FramebufferError {}
