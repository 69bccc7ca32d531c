//! oit-lab: how close to the exact image is MLAB with `M` rows on a kind of scene, and what
//! do the other order-independent transparency methods give for the same memory?
//!
//! The floors, each importing only the ones above it in this list (no import loop; one
//! exception: [`out::figure`] draws a [`study::evaluate::Evaluation`]):
//! - [`stream`]: fragment streams in submission order; [`dump`]: the fragment dump format.
//! - [`methods`]: the exact A-buffer reference and every method as a compositor over the
//!   same stream (MLAB and HT from the `mlab` kernel); [`methods::catalog`]: the sizes the lab
//!   runs, the memory budgets and every command's list of methods.
//! - [`scenes`]: seven deterministic procedural scenes as primitive lists with their span
//!   rasterizers; the fragment streams come from them.
//! - [`metrics`]: RMSE, PSNR, max error, FLIP (error maps with nv-flip's color map), SSIM,
//!   background visibility bias, the change between two submission orders; each over the
//!   whole image and over the covered pixels.
//! - [`tiled`]: whole frames on every core: primitives binned into bands and tiles and
//!   rasterized straight into each worker's tile-sized target (`rayon`), MLAB and the
//!   baselines.
//! - [`par`]: the studies' work queue on all cores.
//! - [`out`]: what the commands write: [`out::picture`], PNGs and the Figure 3 grid (with the
//!   5x7 font of its labels); [`out::figure`], what the main job's figures show;
//!   [`out::table`], the tables' number formats, notes and the progress bar.
//! - [`study`]: two engines, [`study::evaluate`] (one stream against the reference, its
//!   tables) and [`study::sweep`] (every scene in several primitive orders and seeds), and one
//!   file per command, importing the engines, `methods`, `out` and never another command:
//!   [`study::run`] (the main job, `oit-lab run`, and `oit-lab evaluate`), [`study::faint`]
//!   (issue 9: faint and dense layers, both kernel arithmetics, HT tail sums), [`study::stability`]
//!   (issue 10: spreads of the quality and the change between orders), [`study::peers`]
//!   (issue 25: MLAB against the bounded-memory methods by memory budget, with the flicker of
//!   each under a moving camera), [`study::bench`](mod@study::bench) (frame timings and the
//!   scaling plot), [`study::dump`] (`oit-lab dump`).
//!
//! The binary (`main.rs`, `cli.rs`) reads the command line and calls the commands.

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
