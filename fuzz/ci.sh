#!/usr/bin/env bash
# Fuzz smoke run for CI (issue 5), called by .ci/run. Every target runs for a bounded time
# (FUZZ_SECONDS, default 20 s) from the committed seeds, on the default target and on
# x86-64-v3 (AVX2), each in its own target dir, the two backends side by side (built at
# once, then one fuzzer per core). A crash or a failed check fails CI.
# Stable toolchain: `--sanitizer none`, no nightly flag. New corpus entries go to a scratch
# dir, so the committed seeds are never modified.
set -euo pipefail
cd "$(dirname "$0")"
SECS="${FUZZ_SECONDS:-20}"
TARGETS=(mlab_stream hybrid_stream rows_from_bytes lanes_masks)

if ! cargo fuzz --version >/dev/null 2>&1; then
  echo "installing cargo-fuzz"
  cargo install cargo-fuzz --locked
fi
cargo fuzz --version

scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
start=$SECONDS

# build_backend TARGET_DIR RUSTFLAGS
build_backend() {
  RUSTFLAGS="$2" cargo fuzz build --sanitizer none --target-dir "$1"
}

# run_backend NAME TARGET_DIR RUSTFLAGS
run_backend() {
  local name="$1" dir="$2" flags="$3"
  local simd=sse2
  # shellcheck disable=SC2086
  if rustc --print cfg $flags | grep -q 'target_feature="avx2"'; then simd=avx2; fi
  echo "== backend: $name (RUSTFLAGS='$flags', SIMD: $simd)"
  for t in "${TARGETS[@]}"; do
    mkdir -p "$scratch/$name/$t"
    local log="$scratch/$name/$t.log"
    if ! RUSTFLAGS="$flags" cargo fuzz run --sanitizer none --target-dir "$dir" "$t" \
        "$scratch/$name/$t" "corpus/$t" -- \
        -max_total_time="$SECS" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 >"$log" 2>&1; then
      echo "FAILED: $t on $name"
      tail -n 60 "$log"
      exit 1
    fi
    local runs backend
    runs="$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')"
    backend="$(grep -o 'mlab_fuzz backend: .*' "$log" | head -n 1 || true)"
    echo "ok: $t on $name: $runs executions in ${SECS} s ($backend)"
  done
}

V3_FLAGS="-C target-cpu=x86-64-v3"
# Both builds at once, then both backends' targets at once (one fuzzer per core): CI has two.
build_backend target "" >"$scratch/build-default.log" 2>&1 &
default_build=$!
build_backend target/x86-64-v3 "$V3_FLAGS" >"$scratch/build-v3.log" 2>&1 &
v3_build=$!
for b in default:$default_build v3:$v3_build; do
  if ! wait "${b#*:}"; then
    echo "FAILED: build for ${b%%:*}"
    tail -n 60 "$scratch/build-${b%%:*}.log"
    exit 1
  fi
done
echo "built both backends in $((SECONDS - start)) s"
run_backend default target "" >"$scratch/run-default.log" 2>&1 &
default_run=$!
run_backend x86-64-v3 target/x86-64-v3 "$V3_FLAGS" >"$scratch/run-v3.log" 2>&1 &
v3_run=$!
failed=0
wait "$default_run" || failed=1
wait "$v3_run" || failed=1
cat "$scratch/run-default.log" "$scratch/run-v3.log"
if [ "$failed" != 0 ]; then
  exit 1
fi
echo "fuzz: all targets passed on both backends in $((SECONDS - start)) s"
