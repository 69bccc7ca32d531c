#!/usr/bin/env bash
# ns per element of the headline kernel benches on every backend that runs here, one criterion
# run per backend, back to back (docs/performance.md, "Every backend"). Build the binaries first:
#   cargo bench --bench kernel --no-run                                                  # sse2
#   CARGO_TARGET_DIR=target-v3 RUSTFLAGS="-C target-cpu=x86-64-v3" cargo bench --bench kernel --no-run
#   CARGO_TARGET_DIR=target-wasm RUSTFLAGS="-C target-feature=+simd128" \
#     cargo bench --bench kernel --target wasm32-wasip1 --no-run                         # simd128
#   CARGO_TARGET_DIR=target-wasm-portable cargo bench --bench kernel --target wasm32-wasip1 --no-run
# then: benches/backends.sh sse2=BIN avx2=BIN simd128=BIN.wasm portable=BIN.wasm
# (.wasm binaries run under node's node:wasi with .ci/wasi-run.mjs). NEON under qemu is not
# timed: emulation says nothing about an aarch64 core.
set -euo pipefail
cd "$(dirname "$0")/.."
FILTER='^(insert_random/(mlab_lanes/4|mlab_lanes_paper/4|ht_lanes/3|mlab_scalar/4|over_rgba8_lanes)|resolve_rgba8/mlab_lanes/4)$'
ARGS=(--bench --warm-up-time 1 --measurement-time 3 --noplot "$FILTER")
for spec in "$@"; do
  name=${spec%%=*} bin=${spec#*=}
  if [[ $bin == *.wasm ]]; then
    out=$(node --no-warnings .ci/wasi-run.mjs "$bin" "${ARGS[@]}" 2>&1)
  else
    out=$("$bin" "${ARGS[@]}" 2>&1)
  fi
  # criterion: "ID\n time: [lo mid hi]\n thrpt: [lo mid hi]" (then the same two lines as changes
  # against the previous run, skipped): ns per element = 1000 / mid Melem/s.
  echo "$out" | awk -v b="$name" '
    /^[a-z_0-9]+\/[a-z_0-9\/]+/ { id = $1; seen = 0 }
    /^ *thrpt:/ && !seen { seen = 1; v = $4; u = $5; s = (u ~ /^G/) ? 1000 * v : (u ~ /^K/) ? v / 1000 : v;
               printf "%-10s %-34s %8.3f ns/element\n", b, id, 1000 / s }'
done
