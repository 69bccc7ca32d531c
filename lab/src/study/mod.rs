//! The studies: two engines, the evaluation of one stream against the reference
//! ([`evaluate`]) and seeds x primitive orders ([`sweep`]), and the commands built on them
//! ([`run`], [`faint`], [`stability`], [`peers`], [`bench`](mod@bench), [`dump`]). A command imports the engines, `methods/` and `out/`, never
//! another command.

pub mod bench;
pub mod dump;
pub mod evaluate;
pub mod faint;
pub mod peers;
pub mod run;
pub mod stability;
pub mod sweep;
