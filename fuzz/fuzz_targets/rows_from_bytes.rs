//! Fuzz target `rows_from_bytes`: see `mlab_fuzz::targets::rows_from_bytes` for what it checks.
#![no_main]

libfuzzer_sys::fuzz_target!(init: mlab_fuzz::announce("rows_from_bytes"), |data: &[u8]| mlab_fuzz::targets::rows_from_bytes::rows_from_bytes(data));
