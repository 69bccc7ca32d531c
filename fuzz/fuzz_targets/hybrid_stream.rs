//! Fuzz target `hybrid_stream`: see `mlab_fuzz::targets::hybrid_stream` for what it checks.
#![no_main]

libfuzzer_sys::fuzz_target!(init: mlab_fuzz::announce("hybrid_stream"), |data: &[u8]| mlab_fuzz::targets::hybrid_stream::hybrid_stream(data));
