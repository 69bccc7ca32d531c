#!/usr/bin/env bash
# Fuzz smoke run for CI (issue 5), called by .ci/run. Every target runs for a bounded time
# (FUZZ_SECONDS, default 15 s) from the committed seeds, two targets at a time (one per core),
# on the backends in FUZZ_BACKENDS: "default" (SSE2 lanes, what a plain build gets; CI's
# choice) and/or "v3" (x86-64-v3, AVX2 lanes), each in its own target dir. CI fuzzes the
# default build only, to stay within its 15 minutes: the AVX2 lanes are proven byte-identical
# to the scalar kernel by the x86-64-v3 kernel tests (properties and the exhaustive lane-helper
# tests); `FUZZ_BACKENDS="default v3" bash fuzz/ci.sh` fuzzes both (about 4 minutes more).
# A crash or a failed check fails the run.
# Stable toolchain: `--sanitizer none`, no nightly flag. New corpus entries go to a scratch
# dir, so the committed seeds are never modified.
set -euo pipefail
cd "$(dirname "$0")"
SECS="${FUZZ_SECONDS:-15}"
BACKENDS="${FUZZ_BACKENDS:-default}"
TARGETS=(mlab_stream hybrid_stream rows_from_bytes lanes_masks batch_stream)

if ! cargo fuzz --version >/dev/null 2>&1; then
  echo "installing cargo-fuzz"
  cargo install cargo-fuzz --locked
fi
cargo fuzz --version

scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
start=$SECONDS

# build_backend TARGET_DIR RUSTFLAGS
# 16 codegen units (cargo-fuzz's default is 1): the build takes about a fifth less; the
# fuzzers run slightly slower.
build_backend() {
  RUSTFLAGS="$2" cargo fuzz build --sanitizer none --codegen-units 16 --target-dir "$1"
}

# run_target NAME TARGET_DIR RUSTFLAGS TARGET: one bounded fuzz run; prints one line.
run_target() {
  local name="$1" dir="$2" flags="$3" t="$4"
  mkdir -p "$scratch/$name/$t"
  local log="$scratch/$name/$t.log"
  if ! RUSTFLAGS="$flags" cargo fuzz run --sanitizer none --codegen-units 16 --target-dir "$dir" "$t" \
      "$scratch/$name/$t" "corpus/$t" -- \
      -max_total_time="$SECS" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 >"$log" 2>&1; then
    echo "FAILED: $t on $name"
    tail -n 60 "$log"
    return 1
  fi
  local runs backend
  runs="$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo '?')"
  backend="$(grep -o 'mlab_fuzz backend: .*' "$log" | head -n 1 || true)"
  echo "ok: $t on $name: $runs executions in ${SECS} s ($backend)"
}

# run_backend NAME TARGET_DIR RUSTFLAGS: every target, two at a time.
run_backend() {
  local name="$1" dir="$2" flags="$3"
  local simd=sse2
  # shellcheck disable=SC2086
  if rustc --print cfg $flags | grep -q 'target_feature="avx2"'; then simd=avx2; fi
  echo "== backend: $name (RUSTFLAGS='$flags', SIMD: $simd)"
  local i
  for ((i = 0; i < ${#TARGETS[@]}; i += 2)); do
    local pids=() t
    for t in "${TARGETS[@]:i:2}"; do
      run_target "$name" "$dir" "$flags" "$t" >"$scratch/$name-$t.out" 2>&1 &
      pids+=($!)
    done
    local failed=0 p
    for p in "${pids[@]}"; do wait "$p" || failed=1; done
    for t in "${TARGETS[@]:i:2}"; do cat "$scratch/$name-$t.out"; done
    if [ "$failed" != 0 ]; then exit 1; fi
  done
}

for b in $BACKENDS; do
  case "$b" in
    default) dir=target flags="" ;;
    v3) dir=target/x86-64-v3 flags="-C target-cpu=x86-64-v3" ;;
    *) echo "unknown fuzz backend $b (default, v3)" >&2; exit 2 ;;
  esac
  t0=$SECONDS
  build_backend "$dir" "$flags"
  echo "built $b in $((SECONDS - t0)) s"
  run_backend "$b" "$dir" "$flags"
done
echo "fuzz: all targets passed on $BACKENDS in $((SECONDS - start)) s"
