#!/usr/bin/env bash
# The kernel's tests (`cargo test -p mlab --lib` and every file in tests/ but the scalar-only
# properties.rs: lanes == scalar byte for byte among them) on the SIMD backends that `wide` picks at
# compile time beyond the two native x86-64 runs of .ci/run (SSE2, AVX2). Called by .ci/run;
# runs alone too: `bash .ci/backends.sh [v4|neon|simd128|portable]...` (default: all).
#
#   v4        x86-64-v4 (AVX-512), natively, only when /proc/cpuinfo lists avx512f; skipped
#             with a printed line otherwise (qemu's TCG has no AVX-512, Intel SDE is no package)
#   neon      aarch64-unknown-linux-gnu under qemu-aarch64
#   simd128   wasm32-wasip1 +simd128 under node's node:wasi (.ci/wasi-run.mjs)
#   portable  wasm32-wasip1 without simd128: `wide` without any SIMD
#
# Every run sets MLAB_EXPECT_BACKEND (tests/lanes.rs fails when lanes::BACKEND differs) and
# prints the backend. What is missing (rustup targets, qemu-user, the aarch64 linker, node) is
# installed here. Doc tests do not run cross; the benches are not built: `--cfg
# mlab_no_bench_deps` drops criterion (Cargo.toml), a third of each build.
#
# Proptest cases (PROPTEST_CASES overrides them all):
#   v4: 1024, as the native runs of .ci/run.
#   neon, simd128, portable: 256, to keep CI under 15 minutes (1024 cost about 40 s more each).
#   neon builds every crate at opt-level 1 (CARGO_PROFILE_DEV_OPT_LEVEL=1; debug assertions and
#   overflow checks stay on): unoptimized under qemu, 1024 cases took 12 minutes, 64 a minute.
# A wasm test that panics aborts its binary (panic=abort), before libtest prints what it
# captured: the wasm runs pass --nocapture so that the panic message shows.
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR=never
# Line tables only: panics still name file and line; the builds are smaller and faster.
export CARGO_PROFILE_DEV_DEBUG=line-tables-only
NO_BENCH="--cfg mlab_no_bench_deps"
# Every test file that runs the lanes (the unit tests of src/ included). tests/properties.rs (the
# scalar kernel against the f64 oracle; no lanes, no `wide`) runs natively in .ci/run only: on
# these targets it would test the same scalar Rust again, for a build of its own (CI time).
LANE_TESTS="--test lanes --test spans --test batch --test reliability --test unbiased --test layout --test bad_input"

step() { echo; echo "==== $* ($(date +%T))"; }
# CPU seconds (user + system) of the finished children of this shell, into CPU_S (no
# subshell: a subshell would count its own children).
TICKS=$(getconf CLK_TCK)
cpu_s() {
  local st
  read -r -a st </proc/$$/stat
  CPU_S=$(((st[15] + st[16]) / TICKS))
}
# took NAME START_SECONDS START_CPU: wall time and CPU time (on 2 cores, CPU / 2 is the wall
# time of a busy step on an idle machine; wall well above that means other load).
took() {
  cpu_s
  echo "---- $1: $((SECONDS - $2)) s wall, $((CPU_S - $3)) s CPU"
}

need_target() {
  if ! rustup target list --installed | grep -qx "$1"; then
    rustup target add "$1"
  fi
}

apt_updated=
need_apt() { # need_apt COMMAND PACKAGE...
  if ! command -v "$1" >/dev/null 2>&1; then
    if [ -z "$apt_updated" ]; then
      apt-get update -qq
      apt_updated=1
    fi
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${@:2}"
  fi
}

# kernel_tests NAME EXPECTED_BACKEND CASES [cargo args...]; the environment carries the rest,
# HARNESS_ARGS extra arguments for the test binaries.
kernel_tests() {
  local name="$1" want="$2" cases="$3"
  shift 3
  # shellcheck disable=SC2086
  MLAB_EXPECT_BACKEND="$want" PROPTEST_CASES="$cases" cargo test -p mlab --lib $LANE_TESTS "$@" \
    -- ${HARNESS_ARGS:-}
  # The same check once more, printed (the run above already failed on a wrong backend).
  MLAB_EXPECT_BACKEND="$want" cargo test -q -p mlab --test lanes backend_is_the_expected_one "$@" \
    -- --nocapture | grep "backend"
  echo "$name: lanes backend \"$want\" asserted, $cases proptest cases"
}

run_v4() {
  step "kernel tests, x86-64-v4: lanes on an AVX-512 build"
  local t=$SECONDS c
  cpu_s
  c=$CPU_S
  if grep -qw avx512f /proc/cpuinfo; then
    echo "CPU has avx512f: running the x86-64-v4 build natively"
    # --target: the build scripts stay generic x86-64 (RUSTFLAGS then reach only the target).
    CARGO_TARGET_DIR=target-v4 RUSTFLAGS="-C target-cpu=x86-64-v4 $NO_BENCH" \
      kernel_tests x86-64-v4 avx512 "${PROPTEST_CASES:-1024}" \
      --target x86_64-unknown-linux-gnu
  else
    echo "SKIPPED x86-64-v4: this CPU has no avx512f in /proc/cpuinfo ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)); no emulator for it installs here"
  fi
  took x86-64-v4 $t "$c"
}

run_neon() {
  step "kernel tests, aarch64 under qemu-aarch64: lanes on NEON"
  local t=$SECONDS c
  cpu_s
  c=$CPU_S
  need_target aarch64-unknown-linux-gnu
  need_apt qemu-aarch64 qemu-user
  need_apt aarch64-linux-gnu-gcc gcc-aarch64-linux-gnu libc6-dev-arm64-cross
  took "aarch64 install" $t "$c"
  t=$SECONDS
  cpu_s
  c=$CPU_S
  CARGO_TARGET_DIR=target-aarch64 RUSTFLAGS="$NO_BENCH" CARGO_PROFILE_DEV_OPT_LEVEL=1 \
    CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc \
    CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_RUNNER="qemu-aarch64 -L /usr/aarch64-linux-gnu" \
    kernel_tests aarch64 neon "${PROPTEST_CASES:-256}" --target aarch64-unknown-linux-gnu
  took aarch64 $t "$c"
}

# wasm_tests NAME EXPECTED_BACKEND TARGET_DIR EXTRA_RUSTFLAGS
wasm_tests() {
  need_target wasm32-wasip1
  need_apt node nodejs
  local node_flags="--no-warnings"
  # node:wasi needs a flag before node 20.
  if [ "$(node -p 'process.versions.node.split(".")[0]')" -lt 20 ]; then
    node_flags="$node_flags --experimental-wasi-unstable-preview1"
  fi
  # 8 MiB of stack: wasm runs each test on the main thread, whose stack is 1 MiB by default
  # (native test threads get 2 MiB); proptest's nested strategies overflow it unoptimized.
  CARGO_TARGET_DIR="$3" RUSTFLAGS="$NO_BENCH -C link-arg=-zstack-size=8388608 $4" \
    CARGO_TARGET_WASM32_WASIP1_RUNNER="node $node_flags $PWD/.ci/wasi-run.mjs" \
    HARNESS_ARGS=--nocapture kernel_tests "$1" "$2" "${PROPTEST_CASES:-256}" --target wasm32-wasip1
}

run_simd128() {
  step "kernel tests, wasm32-wasip1 +simd128 under node:wasi: lanes on simd128"
  local t=$SECONDS c
  cpu_s
  c=$CPU_S
  wasm_tests wasm32+simd128 simd128 target-wasm-simd128 "-C target-feature=+simd128"
  took "wasm32 simd128" $t "$c"
}

run_portable() {
  step "kernel tests, wasm32-wasip1 without simd128 under node:wasi: lanes without SIMD"
  local t=$SECONDS c
  cpu_s
  c=$CPU_S
  wasm_tests wasm32 portable target-wasm-portable ""
  took "wasm32 portable" $t "$c"
}

for b in "${@:-v4 neon simd128 portable}"; do
  for one in $b; do
    case "$one" in
      v4 | neon | simd128 | portable) "run_$one" ;;
      *) echo "unknown backend $one (v4, neon, simd128, portable)" >&2; exit 2 ;;
    esac
  done
done
