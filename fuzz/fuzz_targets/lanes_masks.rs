//! Fuzz target `lanes_masks`: see `mlab_fuzz::targets::lanes_masks` for what it checks.
#![no_main]

libfuzzer_sys::fuzz_target!(init: mlab_fuzz::announce("lanes_masks"), |data: &[u8]| mlab_fuzz::targets::lanes_masks::lanes_masks(data));
