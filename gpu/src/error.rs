//! The compositor's errors.

use mlab::{FragmentError, Layers};

/// Why the GPU path refused or failed. Nothing panics on bad input: every check returns one
/// of these.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum GpuError {
    /// No Vulkan adapter was found (wgpu's message). On Linux without a GPU,
    /// `apt-get install mesa-vulkan-drivers libvulkan1` gives Mesa's software driver (lavapipe).
    NoAdapter(String),
    /// The adapter refused the device (wgpu's message), for example for lack of the WebGPU
    /// default limits.
    RequestDevice(String),
    /// A size that is not one of [`Layers::SIZES`].
    UnsupportedLayers(Layers),
    /// `width * height` (with the spans' padding) does not fit in 32 bits.
    FrameTooLarge {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// One line of the frame needs more storage than one binding may hold (see
    /// [`crate::Compositor::max_binding_bytes`]).
    LineTooLarge {
        /// The line.
        y: u32,
        /// Bytes it needs in one binding (the largest of its rows, its offsets, its fragments at
        /// 32 bytes each and its sort keys at 8 bytes per key, padded to a power of two).
        bytes: u64,
        /// The binding limit in bytes.
        limit: u64,
    },
    /// More fragments than 32-bit offsets can count.
    TooManyFragments {
        /// How many were given.
        count: usize,
    },
    /// Fragment `index` names a pixel outside the frame.
    PixelOutOfRange {
        /// Position of the fragment in the input.
        index: usize,
        /// Its pixel (`y * width + x`).
        pixel: u32,
        /// `width * height`.
        pixels: u32,
    },
    /// Fragment `index` is not a valid [`mlab::Fragment`] (premultiplied).
    Fragment {
        /// Position of the fragment in the input.
        index: usize,
        /// Why.
        error: FragmentError,
    },
    /// An RGBA8 resolve on the GPU was asked of a method without an integer resolve. Every
    /// method and size has one since HT's RGBA8 became the integer resolve of HT: no function
    /// of this version returns it (kept so that code matching on it keeps compiling).
    NoIntegerResolve(Layers),
    /// The shader or pipeline was refused (wgpu's validation message).
    Shader(String),
    /// The device failed while compositing (out of memory, device lost, mapping failed:
    /// wgpu's message).
    Device(String),
}

impl core::fmt::Display for GpuError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            GpuError::NoAdapter(m) => write!(f, "no Vulkan adapter: {m}"),
            GpuError::RequestDevice(m) => write!(f, "device request refused: {m}"),
            GpuError::UnsupportedLayers(l) => write!(f, "unsupported size {l:?} (sizes: 1..=8)"),
            GpuError::FrameTooLarge { width, height } => write!(f, "frame {width}x{height} too large"),
            GpuError::LineTooLarge { y, bytes, limit } => {
                write!(f, "line {y} needs {bytes} bytes in one binding, limit {limit}")
            }
            GpuError::TooManyFragments { count } => write!(f, "{count} fragments: at most 2^32 - 1"),
            GpuError::PixelOutOfRange { index, pixel, pixels } => {
                write!(f, "fragment {index}: pixel {pixel} outside the frame ({pixels} pixels)")
            }
            GpuError::Fragment { index, error } => write!(f, "fragment {index}: {error}"),
            GpuError::NoIntegerResolve(l) => write!(f, "{l:?} has no integer RGBA8 resolve"),
            GpuError::Shader(m) => write!(f, "shader refused: {m}"),
            GpuError::Device(m) => write!(f, "device error: {m}"),
        }
    }
}

impl std::error::Error for GpuError {}
