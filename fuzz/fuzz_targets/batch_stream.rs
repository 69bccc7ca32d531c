//! Fuzz target `batch_stream`: see `mlab_fuzz::batch::batch_stream` for what it checks.
#![no_main]

libfuzzer_sys::fuzz_target!(init: mlab_fuzz::announce("batch_stream"), |data: &[u8]| mlab_fuzz::batch::batch_stream(data));
