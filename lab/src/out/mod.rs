//! What the commands write: PNGs and the labelled figure grid ([`picture`], with its 5x7
//! font), the tables' shared pieces ([`table`]).

pub mod picture;
pub mod table;
