//! The same bytes on a GPU: the WGSL twin of the [`mlab`] kernel ([`wgsl`]) and a wgpu
//! compositor ([`Compositor`]) whose rows are bit-identical to the CPU kernel's ([`cpu`]).
//!
//! ```no_run
//! use mlab::{ArithKind, Layers};
//! use mlab_gpu::{Compositor, Gpu, GpuFragment, Layout};
//! let gpu = Gpu::new()?; // the first Vulkan adapter (lavapipe on a machine without a GPU)
//! let compositor = Compositor::new(&gpu, Layers::Mlab(4), ArithKind::Unbiased, Layout::Spans)?;
//! let fragments = [
//!     GpuFragment::new(5, [0.5, 0.0, 0.0, 0.5], 2.0),
//!     GpuFragment::new(5, [0.01, 0.0, 0.0, 0.03], 3.0).with_key(17), // the primitive's id
//! ];
//! let words = compositor.composite(64, 32, &fragments)?; // the storage, as Row::words
//! assert_eq!(words, mlab_gpu::cpu::composite(Layers::Mlab(4), ArithKind::Unbiased, Layout::Spans, 64, 32, &fragments)?);
//! # Ok::<(), mlab_gpu::GpuError>(())
//! ```
//!
//! The arithmetic is the kernel's run-time [`mlab::ArithKind`] (this crate's own `Arith`
//! enum, its copy, is gone). How it works, what it needs and what it guarantees: `docs/gpu.md`.

mod compositor;
pub mod cpu;
mod device;
mod error;
mod fragment;
mod pass;
mod plan;
mod sort;
pub mod wgsl;

pub use compositor::Compositor;
pub use device::Gpu;
pub use error::GpuError;
pub use fragment::GpuFragment;
pub use pass::background_q15;
pub use plan::Layout;
pub use sort::Sort;
