//! Fuzz target `mlab_stream`: see `mlab_fuzz::targets::mlab_stream` for what it checks.
#![no_main]

libfuzzer_sys::fuzz_target!(init: mlab_fuzz::announce("mlab_stream"), |data: &[u8]| mlab_fuzz::targets::mlab_stream::mlab_stream(data));
