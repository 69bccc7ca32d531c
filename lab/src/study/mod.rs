//! The studies: the evaluation of one stream against the reference ([`evaluate`]) and the
//! commands built on it ([`run`]).

pub mod evaluate;
pub mod run;
