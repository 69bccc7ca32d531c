#!/usr/bin/env bash
# The C API from C (.ci/run's "C API" step; runs from any directory): the static library
# (release), examples/triangles.c compiled by the system C compiler against it and run for
# MLAB 1-8 and HT 1-8 in both arithmetics, twice: with AddressSanitizer and
# UndefinedBehaviorSanitizer (they check the C side; the Rust library is not instrumented),
# and under valgrind's memcheck (every access of the process, the library's writes into the
# caller's buffers included: a too-short buffer passed with a too-large length is caught
# there, not by ASan). Any report fails. Then its 32 PPM files are compared byte for byte
# (`cmp`) with the same scene through the Rust API (tests/triangles.rs).
set -euo pipefail
cd "$(dirname "$0")/.."
out="$PWD/target/capi-ci" # absolute: cargo test runs in capi/
rm -rf "$out"
mkdir -p "$out/c" "$out/rust"
cargo build --release -p mlab-capi
# The header alone, as C99 and as C++11 (docs/c.md says both compile warning-free).
"${CC:-cc}" -std=c99 -Wall -Wextra -Werror -pedantic -fsyntax-only -x c capi/include/mlab.h
"${CXX:-c++}" -std=c++11 -Wall -Wextra -Werror -pedantic -fsyntax-only -x c++ capi/include/mlab.h
# The libraries that `rustc --print native-static-libs` lists for the static library on
# Linux (docs/c.md).
LIBS=(target/release/libmlab_capi.a -lgcc_s -lutil -lrt -lpthread -lm -ldl)
CFLAGS=(-std=c11 -Wall -Wextra -Werror -pedantic -O1 -g -Icapi/include)
"${CC:-cc}" "${CFLAGS[@]}" -fno-omit-frame-pointer -fsanitize=address,undefined -fno-sanitize-recover=all \
  capi/examples/triangles.c "${LIBS[@]}" -o "$out/triangles-asan"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 "$out/triangles-asan" "$out/c"
if command -v valgrind >/dev/null; then
  "${CC:-cc}" "${CFLAGS[@]}" capi/examples/triangles.c "${LIBS[@]}" -o "$out/triangles"
  mkdir -p "$out/c-valgrind"
  valgrind -q --error-exitcode=1 --leak-check=full --errors-for-leak-kinds=definite,indirect \
    "$out/triangles" "$out/c-valgrind"
  for f in "$out"/c/*.ppm; do cmp "$f" "$out/c-valgrind/$(basename "$f")"; done
else
  echo "valgrind not installed: the memcheck run is skipped (apt-get install valgrind)"
fi
MLAB_CAPI_PPM_DIR="$out/rust" cargo test -q -p mlab-capi --test triangles
n=0
for f in "$out"/rust/*.ppm; do
  cmp "$f" "$out/c/$(basename "$f")"
  n=$((n + 1))
done
[ "$n" -eq 32 ] && [ "$(ls "$out/c" | wc -l)" -eq 32 ]
echo "C example: $n images byte-identical to the Rust API's (MLAB 1-8, HT 1-8, both arithmetics), no sanitizer report"
