#!/usr/bin/env bash
# Installs the mlab C library under a prefix, as a C library installs (Linux, GNU binutils):
#
#   bash capi/install.sh [PREFIX]        # default /usr/local; DESTDIR=... stages it
#
#   PREFIX/include/mlab.h, mlab.hpp      the C header and the C++17 wrapper
#   PREFIX/lib/libmlab.a                 static: one object, only the C API's symbols global
#   PREFIX/lib/libmlab.so.N              shared, SONAME libmlab.so.N (N = MLAB_ABI_VERSION)
#   PREFIX/lib/libmlab.so -> libmlab.so.N
#   PREFIX/lib/pkgconfig/mlab.pc         the shared library (`pkg-config --libs mlab`)
#   PREFIX/lib/pkgconfig/mlab-static.pc  the static one, by path (`pkg-config --libs mlab-static`)
#
# What cargo-c's `cargo cinstall` does, without cargo-c (whose build takes longer than CI has).
# Builds the release library first (`cargo build --release -p mlab-capi`; CARGO_TARGET_DIR is
# honoured). LIBDIR overrides PREFIX/lib.
set -euo pipefail
cd "$(dirname "$0")/.."
prefix="${1:-${PREFIX:-/usr/local}}"
libdir="${LIBDIR:-$prefix/lib}"
dest="${DESTDIR:-}"
cargo build --release -p mlab-capi
built="${CARGO_TARGET_DIR:-target}/release"
header=capi/include/mlab.h
macro() { sed -n "s/^#define $1 \([0-9]*\)$/\1/p" "$header"; }
abi=$(macro MLAB_ABI_VERSION)
version="$(macro MLAB_VERSION_MAJOR).$(macro MLAB_VERSION_MINOR).$(macro MLAB_VERSION_PATCH)"
# The system libraries the Rust standard library links on Linux (`--print native-static-libs`).
native="-lgcc_s -lutil -lrt -lpthread -lm -ldl -lc"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The static archive as one relocatable object: the members the API reaches (a partial link
# from the API's functions, unused sections dropped), every global symbol but the API's made
# local, so that the standard library and kernel inside cannot clash with the program's. The
# LLVM bitcode sections of the standard library's objects are dropped: the linker plugins of
# an older LLVM fail on them, and nothing links them.
{ nm -g --defined-only "$built/libmlab_capi.a" 2>/dev/null || true; } | awk 'NF == 3 && $2 == "T" && $3 ~ /^mlab_/ { print $3 }' |
  sort -u >"$work/api.txt"
ld -r --gc-sections $(sed 's/^/-u /' "$work/api.txt") --whole-archive "$built/libmlab_capi.a" -o "$work/all.o"
objcopy --keep-global-symbols="$work/api.txt" --remove-section=.llvmbc --remove-section=.llvmcmd \
  "$work/all.o" "$work/mlab.o"
ar rcs "$work/libmlab.a" "$work/mlab.o"

install -d "$dest$prefix/include" "$dest$libdir/pkgconfig"
install -m 644 capi/include/mlab.h capi/include/mlab.hpp "$dest$prefix/include/"
install -m 644 "$work/libmlab.a" "$dest$libdir/libmlab.a"
install -m 755 "$built/libmlab_capi.so" "$dest$libdir/libmlab.so.$abi"
ln -sf "libmlab.so.$abi" "$dest$libdir/libmlab.so"
pc() {
  cat <<EOF
prefix=$prefix
includedir=\${prefix}/include
libdir=$libdir

Name: $1
Description: order-independent transparency (MLAB, Hybrid Transparency), C API
Version: $version
Cflags: -I\${includedir}
EOF
}
{ pc mlab; echo "Libs: -L\${libdir} -lmlab"; echo "Libs.private: $native"; } >"$dest$libdir/pkgconfig/mlab.pc"
{ pc mlab-static; echo "Libs: \${libdir}/libmlab.a $native"; } >"$dest$libdir/pkgconfig/mlab-static.pc"
echo "installed mlab $version (C API $abi) under $dest$prefix"
