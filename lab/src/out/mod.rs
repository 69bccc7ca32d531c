//! What the commands write: the tables' shared pieces ([`table`]).

pub mod table;
