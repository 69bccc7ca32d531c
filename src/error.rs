//! One error for everything the crate refuses, so that `?` works in a function returning
//! `Result<_, mlab::Error>` on fragment constructors and framebuffer operations alike.

use crate::fragment::FragmentError;
use crate::framebuffer::FramebufferError;

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
