#!/usr/bin/env bash
# The per-pixel client passes (benches/previous_release/bench.rs) against an older commit and this
# checkout, interleaved (benches/interleave.py), and their instructions per call (callgrind).
# Usage: benches/previous_release.sh [COMMIT] [ROUNDS]   (default 90750a7, 5 rounds)
# Builds for the default target (SSE2), as the client measurement of issue 21 did; set
# RUSTFLAGS="-C target-cpu=x86-64-v3" for AVX2 (never native under valgrind).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
commit=${1:-90750a7}; rounds=${2:-5}
work=${PREVIOUS_RELEASE_DIR:-/tmp/mlab-previous-release}
mkdir -p "$work"
if [ ! -d "$work/kernel" ]; then git -C "$repo" worktree add --detach "$work/kernel" "$commit" >/dev/null; fi
git -C "$work/kernel" checkout -q --detach "$commit"
crate() { # dir, kernel path, cfg
  mkdir -p "$1"
  cat >"$1/Cargo.toml" <<TOML
[package]
name = "previous-release-$(basename "$1")"
version = "0.0.0"
edition = "2024"
[dependencies]
mlab = { path = "$2" }
criterion = { version = "0.8", default-features = false, features = ["cargo_bench_support"] }
[features]
current = []
[[bench]]
name = "release"
path = "$repo/benches/previous_release/bench.rs"
harness = false
[workspace]
TOML
}
crate "$work/old" "$work/kernel"
crate "$work/new" "$repo"
bins=()
for side in old new; do
  features=; if [ $side = new ]; then features="--features current"; fi
  bin=$(cd "$work/$side" && cargo bench --no-run $features --message-format=json 2>/dev/null |
    python3 -c 'import json,sys
for l in sys.stdin:
    m=json.loads(l)
    if m.get("executable") and m.get("target",{}).get("kind")==["bench"]: print(m["executable"])')
  bins+=("$bin")
done
echo "old ($commit): ${bins[0]}"; echo "new ($(git -C "$repo" rev-parse --short HEAD)): ${bins[1]}"
python3 "$repo/benches/interleave.py" release "$rounds" "${bins[@]}"
for id in mlab4 mlab8 ht3; do
  for i in 0 1; do
    "$repo/benches/callgrind.sh" "${bins[$i]}" "release/${id}_per_pixel" "release::$id" 1 inclusive | sed "s/^/$([ $i = 0 ] && echo old || echo new) /"
  done
done
