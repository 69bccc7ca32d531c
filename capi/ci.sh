#!/usr/bin/env bash
# The C API from C and C++ (.ci/run's "C API" step; runs from any directory):
# 1. the release library; its shared library's SONAME and exports; the headers alone (mlab.h
#    as C99 and C++11, mlab.hpp as C++17, warning-free);
# 2. examples/triangles.c against the static library, run for MLAB 1-8 and HT 1-8 in both
#    arithmetics with AddressSanitizer and UndefinedBehaviorSanitizer (the C side; the Rust
#    library is not instrumented) and under valgrind's memcheck (every access of the process,
#    the library's writes into the caller's buffers included); any report fails; its 32 PPM
#    files equal the Rust API's (tests/triangles.rs) byte for byte;
# 3. install.sh into a prefix: the static archive's global symbols are the header's functions
#    and nothing else, and so are the shared library's; the example linked by the two
#    pkg-config lines of docs/c.md (shared: it loads libmlab.so.N from the prefix; static: it
#    needs no libmlab) gives the same files;
# 4. examples/triangles.cpp (the C++ wrapper, mlab.hpp) against the installed archive, under
#    ASan + UBSan and under valgrind: the same files;
# 5. with cmake installed: both examples through mlab.cmake (examples/CMakeLists.txt) with
#    CARGO_TARGET_DIR set, then a source touched: cargo rebuilds the archive and both are
#    relinked.
set -euo pipefail
cd "$(dirname "$0")/.."
out="$PWD/target/capi-ci" # absolute: cargo test runs in capi/
rm -rf "$out"
mkdir -p "$out"
same() { # same DIR: DIR's 32 images are the C example's
  local n=0 f
  for f in "$out"/c/*.ppm; do
    cmp "$f" "$1/$(basename "$f")"
    n=$((n + 1))
  done
  [ "$n" -eq 32 ] && [ "$(ls "$1" | wc -l)" -eq 32 ]
}
run() { # run DIR PROGRAM...: PROGRAM writes its images into $out/DIR, which must be the C example's
  mkdir -p "$out/$1"
  "${@:2}" "$out/$1"
  same "$out/$1"
}
VALGRIND=(valgrind -q --error-exitcode=1 --leak-check=full --errors-for-leak-kinds=definite,indirect)

# 1.
cargo build --release -p mlab-capi
lib=target/release
grep -oE '\bmlab_[a-z0-9_]+\(' capi/include/mlab.h | tr -d '(' | sort -u >"$out/api.txt"
readelf -d "$lib/libmlab_capi.so" | grep "SONAME.*\[libmlab\.so\.$(sed -n 's/^#define MLAB_ABI_VERSION //p' capi/include/mlab.h)\]" >/dev/null
nm -D --defined-only "$lib/libmlab_capi.so" | awk '{ print $3 }' | sort | diff "$out/api.txt" -
"${CC:-cc}" -std=c99 -Wall -Wextra -Werror -pedantic -fsyntax-only -x c capi/include/mlab.h
"${CXX:-c++}" -std=c++11 -Wall -Wextra -Werror -pedantic -fsyntax-only -x c++ capi/include/mlab.h
"${CXX:-c++}" -std=c++17 -Wall -Wextra -Werror -pedantic -fsyntax-only -x c++ -Icapi/include capi/include/mlab.hpp

# 2. The libraries that `rustc --print native-static-libs` lists for the static library on Linux.
LIBS=(-lgcc_s -lutil -lrt -lpthread -lm -ldl)
CFLAGS=(-std=c11 -Wall -Wextra -Werror -pedantic -O1 -g -Icapi/include)
SAN=(-fno-omit-frame-pointer -fsanitize=address,undefined -fno-sanitize-recover=all)
export ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1
"${CC:-cc}" "${CFLAGS[@]}" "${SAN[@]}" capi/examples/triangles.c "$lib/libmlab_capi.a" "${LIBS[@]}" -o "$out/triangles-asan"
mkdir -p "$out/c"
"$out/triangles-asan" "$out/c"
"${CC:-cc}" "${CFLAGS[@]}" capi/examples/triangles.c "$lib/libmlab_capi.a" "${LIBS[@]}" -o "$out/triangles"
run c-valgrind "${VALGRIND[@]}" "$out/triangles"
MLAB_CAPI_PPM_DIR="$out/rust" cargo test -q -p mlab-capi --test triangles
same "$out/rust"

# 3.
bash capi/install.sh "$out/prefix" >/dev/null
export PKG_CONFIG_PATH="$out/prefix/lib/pkgconfig"
globals() { { nm -g --defined-only "$1" 2>/dev/null || true; } | awk 'NF == 3 { print $3 }' | sort; }
before=$(globals "$lib/libmlab_capi.a" | wc -l)
globals "$out/prefix/lib/libmlab.a" | diff "$out/api.txt" -
nm -D --defined-only "$out/prefix/lib/libmlab.so" | awk '{ print $3 }' | sort | diff "$out/api.txt" -
# The lines of docs/c.md ("Install").
"${CC:-cc}" -std=c11 -O2 capi/examples/triangles.c $(pkg-config --cflags --libs mlab) \
  -Wl,-rpath,"$(pkg-config --variable=libdir mlab)" -o "$out/triangles-shared"
ldd "$out/triangles-shared" | grep "libmlab\.so\.[0-9]* => $out/prefix/lib/" >/dev/null
run c-shared "$out/triangles-shared"
"${CC:-cc}" -std=c11 -O2 capi/examples/triangles.c $(pkg-config --cflags --libs mlab-static) -o "$out/triangles-static"
if ldd "$out/triangles-static" | grep libmlab; then echo "linked the shared library"; exit 1; fi
run c-static "$out/triangles-static"

# 4.
CXXFLAGS=(-std=c++17 -Wall -Wextra -Werror -pedantic -O1 -g $(pkg-config --cflags mlab-static))
"${CXX:-c++}" "${CXXFLAGS[@]}" "${SAN[@]}" capi/examples/triangles.cpp $(pkg-config --libs mlab-static) -o "$out/triangles-cpp-asan"
run cpp-asan "$out/triangles-cpp-asan"
"${CXX:-c++}" "${CXXFLAGS[@]}" capi/examples/triangles.cpp $(pkg-config --libs mlab-static) -o "$out/triangles-cpp"
run cpp-valgrind "${VALGRIND[@]}" "$out/triangles-cpp"
echo "C API: 32 images from C (ASan + UBSan, valgrind, shared and static installed) and C++ (ASan + UBSan, valgrind) byte-identical to the Rust API's; static archive: $before global symbols in cargo's, $(wc -l <"$out/api.txt") (the API) installed; shared: the API's"

# 5.
if ! command -v cmake >/dev/null; then
  echo "cmake not installed: the CMake build is skipped (apt-get install cmake)"
  exit 0
fi
# A target directory of its own, seeded with a copy of the release build so that only the
# touched rebuild compiles.
export CARGO_TARGET_DIR=target/capi-cmake
rm -rf "$CARGO_TARGET_DIR" && mkdir -p "$CARGO_TARGET_DIR" && cp -a target/release "$CARGO_TARGET_DIR/"
cmake -S capi/examples -B "$out/cmake" >/dev/null
cmake --build "$out/cmake" >/dev/null
run cmake-c "$out/cmake/triangles"
run cmake-cpp "$out/cmake/triangles_cpp"
sleep 1 # a coarse file-system clock
touch capi/src/status.rs
cmake --build "$out/cmake" >/dev/null
archive="$CARGO_TARGET_DIR/release/libmlab_capi.a"
[ "$archive" -nt capi/src/status.rs ] && [ "$out/cmake/triangles" -nt "$archive" ] && [ "$out/cmake/triangles_cpp" -nt "$archive" ] ||
  { echo "the CMake build did not rebuild the library after a touched source, or did not relink"; exit 1; }
run cmake-c-rebuilt "$out/cmake/triangles"
echo "CMake (mlab.cmake, CARGO_TARGET_DIR=$CARGO_TARGET_DIR): both examples byte-identical, rebuilt and relinked after a touched source"
