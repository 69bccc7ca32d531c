//! oit-lab: how close to the exact image is MLAB with `M` rows on a kind of scene, and what
//! do the other order-independent transparency methods give for the same memory?
//!
//! - [`scenes`]: seven deterministic procedural scenes as primitive lists with their span
//!   rasterizers; the fragment streams in submission order ([`stream`]) come from them.
//! - [`methods`]: the exact A-buffer reference and every method as a compositor over the
//!   same stream (MLAB and HT from the `mlab` kernel).
//! - [`metrics`]: RMSE, PSNR, max error, FLIP (error maps with nv-flip's color map), SSIM,
//!   background visibility bias, the change between two submission orders; each over the
//!   whole image and over the covered pixels.
//! - [`study::faint`]: `oit-lab faint` (issue 9): many faint or dense layers, both kernel
//!   arithmetics, HT tail sums and saturation.
//! - [`out::picture`]: PNGs and the Figure 3 grid (with the 5x7 font of its labels);
//!   [`out::figure`]: what the main job's figures show;
//!   [`dump`]: the fragment dump format (`oit-lab dump` is [`study::dump`]).
//! - [`study`]: the studies. [`study::evaluate`]: the whole evaluation of one stream and its
//!   tables; [`study::run`]: the main job (`oit-lab run`) and `oit-lab evaluate`.
//! - [`study::peers`]: `oit-lab peers` (issue 25), MLAB against the bounded-memory methods by memory
//!   budget, with the flicker of each under a moving camera.
//! - [`study::sweep`]: every scene in several primitive orders and seeds (the engine of
//!   stability and peers); [`study::stability`]: `oit-lab stability`, spreads of the quality
//!   and the change between orders.
//! - [`out`]: what the commands write: the tables' shared pieces ([`out::table`]: number
//!   formats, the median, the notes under the tables, the progress bar).
//! - [`study::bench`](mod@study::bench): `oit-lab bench`, frame timings and the scaling plot.
//! - [`tiled`]: whole frames on every core: primitives binned into bands and tiles and
//!   rasterized straight into each worker's tile-sized target (`rayon`), MLAB and the
//!   baselines.

#![forbid(unsafe_code)]

pub mod dump;
pub mod methods;
pub mod metrics;
pub mod out;
pub mod par;
pub mod scenes;
pub mod stream;
pub mod study;
pub mod tiled;
