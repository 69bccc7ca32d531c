//! The shared library's SONAME on ELF targets: `libmlab.so.N`, `N` the C API's
//! `MLAB_ABI_VERSION` (read from `src/lib.rs`, where it is written once), the name it is
//! installed under (`install.sh`) and that a program linked against it loads. Only the
//! shared library's link gets it (`rustc-cdylib-link-arg`); nothing is generated.
fn main() {
    println!("cargo:rerun-if-changed=src/lib.rs");
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    let unix = std::env::var("CARGO_CFG_TARGET_FAMILY").is_ok_and(|f| f.split(',').any(|f| f == "unix"));
    if !unix || matches!(os.as_str(), "macos" | "ios" | "tvos" | "watchos" | "visionos") {
        return;
    }
    let lib = std::fs::read_to_string("src/lib.rs").expect("src/lib.rs");
    let abi = lib
        .split("pub const MLAB_ABI_VERSION: u32 = ")
        .nth(1)
        .and_then(|rest| rest.split(';').next())
        .and_then(|n| n.parse::<u32>().ok())
        .expect("src/lib.rs defines `pub const MLAB_ABI_VERSION: u32 = N;`");
    println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libmlab.so.{abi}");
}
