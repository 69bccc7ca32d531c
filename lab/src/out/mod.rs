//! What the commands write: PNGs and the labelled figure grid ([`picture`], with its 5x7
//! font), what the main job's figures show ([`figure`]), the tables' shared pieces
//! ([`table`]).

pub mod figure;
pub mod picture;
pub mod table;
