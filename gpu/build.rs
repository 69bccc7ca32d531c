//! Decides whether the GPU tests can run: with no Vulkan driver on this machine they are
//! built `#[ignore]`d (`cfg(mlab_gpu_no_driver)`), so `cargo test` reports them as ignored
//! instead of passing without a GPU. Under `CI=true` they are never ignored: a missing adapter
//! fails them (`gpu/tests/common/mod.rs`). `MLAB_GPU_TESTS=skip` ignores them anyway (a
//! machine whose driver is installed but broken).
use std::path::{Path, PathBuf};

fn main() {
    println!("cargo::rustc-check-cfg=cfg(mlab_gpu_no_driver)");
    for var in [
        "CI",
        "MLAB_GPU_TESTS",
        "VK_ICD_FILENAMES",
        "VK_DRIVER_FILES",
        "XDG_DATA_DIRS",
        "XDG_CONFIG_DIRS",
    ] {
        println!("cargo::rerun-if-env-changed={var}");
    }
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        return;
    }
    let skip = std::env::var("MLAB_GPU_TESTS").is_ok_and(|v| v == "skip");
    if skip || !vulkan_driver_present() {
        println!("cargo::rustc-cfg=mlab_gpu_no_driver");
    }
}

/// A Vulkan ICD manifest where the Vulkan loader looks on Linux and the BSDs, or the files
/// `VK_ICD_FILENAMES` / `VK_DRIVER_FILES` name. Elsewhere (Windows: the registry; macOS) the
/// tests run and a missing adapter fails them.
fn vulkan_driver_present() -> bool {
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if !["linux", "freebsd", "openbsd", "netbsd", "dragonfly", "android"].contains(&os.as_str()) {
        return true;
    }
    for var in ["VK_DRIVER_FILES", "VK_ICD_FILENAMES"] {
        if let Ok(list) = std::env::var(var) {
            return list.split(':').any(|f| Path::new(f).is_file());
        }
    }
    let mut dirs: Vec<PathBuf> = Vec::new();
    let xdg = |var: &str, default: &str| std::env::var(var).unwrap_or_else(|_| default.to_string());
    for base in xdg("XDG_CONFIG_DIRS", "/etc/xdg").split(':').chain(["/etc"]) {
        dirs.push(Path::new(base).join("vulkan/icd.d"));
    }
    for base in xdg("XDG_DATA_DIRS", "/usr/local/share:/usr/share").split(':') {
        dirs.push(Path::new(base).join("vulkan/icd.d"));
    }
    if let Ok(home) = std::env::var("HOME") {
        dirs.push(Path::new(&home).join(".local/share/vulkan/icd.d"));
    }
    let mut found = false;
    for dir in &dirs {
        // Watch the manifest folder (or the `vulkan` folder above it) so that installing a
        // driver rebuilds the tests without the ignore.
        if dir.is_dir() {
            println!("cargo::rerun-if-changed={}", dir.display());
        } else if let Some(parent) = dir.parent().filter(|p| p.is_dir()) {
            println!("cargo::rerun-if-changed={}", parent.display());
        }
        let manifests = std::fs::read_dir(dir).into_iter().flatten().flatten();
        found |= manifests
            .into_iter()
            .any(|e| e.path().extension().is_some_and(|x| x == "json"));
    }
    found
}
