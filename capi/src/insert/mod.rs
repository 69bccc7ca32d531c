//! The inserts, by how the fragments come: one per call as scalars (`pixel`), 8 of one line
//! (`span`), or an array of fragments with their pixels (`batch`); each straight or
//! premultiplied color, without or with a stable key.
//!
//! The `mod` lines are in the order of the functions in the header (cbindgen follows them),
//! so each stands alone: rustfmt would sort a group of them.

pub(crate) mod pixel;

pub(crate) mod span;

pub(crate) mod batch;
