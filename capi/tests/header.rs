//! `include/mlab.h` is what cbindgen generates from `src/lib.rs` (and the modules it declares,
//! in their order) with `cbindgen.toml`, byte for byte: a change of the API that is not in the
//! checked-in header fails here. Its version macros are the crate's version.
//! `MLAB_BLESS=1 cargo test -p mlab-capi --test header` rewrites the header.

use std::path::Path;

#[test]
fn header_is_generated_from_the_source() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .expect("cbindgen parses src/lib.rs and its modules")
        .write(&mut generated);
    let path = dir.join("include/mlab.h");
    if std::env::var_os("MLAB_BLESS").is_some() {
        std::fs::write(&path, &generated).expect("write include/mlab.h");
    }
    let checked_in = std::fs::read(&path).expect("include/mlab.h");
    assert!(
        checked_in == generated,
        "include/mlab.h differs from what cbindgen generates from src/ (MLAB_BLESS=1 \
         cargo test -p mlab-capi --test header rewrites it); generated:\n{}",
        String::from_utf8_lossy(&generated)
    );
}

/// The header's version macros are the crate's version.
#[test]
fn version_macros_are_the_crate_version() {
    let v = |s: &str| s.parse::<u32>().unwrap();
    assert_eq!(
        [
            mlab_capi::MLAB_VERSION_MAJOR,
            mlab_capi::MLAB_VERSION_MINOR,
            mlab_capi::MLAB_VERSION_PATCH
        ],
        [
            v(env!("CARGO_PKG_VERSION_MAJOR")),
            v(env!("CARGO_PKG_VERSION_MINOR")),
            v(env!("CARGO_PKG_VERSION_PATCH"))
        ]
    );
}
