#!/usr/bin/env bash
# Time a change against its base: the kernel and batch benches of BASE (any commit) and of this
# working tree, built for one target, interleaved in one run (benches/interleave.py: each
# binary's filter in turn, ROUNDS rounds, minimum per bench), then each bench's ratio
# new / base. Instruction counts cannot see microcoded instructions, store-forwarding stalls
# or latency chains (issue 31): a change to the lanes, the merges or the framebuffers is timed
# with this, against its base, as well as counted (docs/performance.md, "The rule").
#   benches/compare.sh BASE [ROUNDS] [FILTER] [BENCHES]
#   RUSTFLAGS="-C target-cpu=x86-64-v3" benches/compare.sh main~1 4 '^insert_random/mlab_lanes'
# BENCHES: "kernel batch" by default. Each RUSTFLAGS gets its own target directories (wide
# picks its backend at compile time). Read /proc/loadavg before trusting a figure: another
# busy process on a 2-core machine moves these by 10-50 %. Loop placement alone moves one by up
# to 25 %: add `-C llvm-args=-align-loops=64` to RUSTFLAGS for a second, placement-free run.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
base=${1:?usage: benches/compare.sh BASE [ROUNDS] [FILTER] [BENCHES]}
rounds=${2:-4}; filter=${3:-.}; benches=${4:-kernel batch}
flags=${RUSTFLAGS:-}
tag=$(printf '%s' "$flags" | tr -c 'a-zA-Z0-9' '_' | cut -c1-40)
work=${MLAB_COMPARE_DIR:-/tmp/mlab-compare}
mkdir -p "$work"
sha=$(git -C "$repo" rev-parse --short "$base")
if [ ! -d "$work/base" ]; then git -C "$repo" worktree add --detach "$work/base" "$sha" >/dev/null; fi
git -C "$work/base" checkout -q --detach "$sha"
build() { # dir, target dir, bench -> executable path
  (cd "$1" && CARGO_TARGET_DIR="$2" cargo bench --bench "$3" --no-run --message-format=json 2>/dev/null) |
    python3 -c 'import json,sys
for l in sys.stdin:
    m=json.loads(l)
    if m.get("executable") and m.get("target",{}).get("kind")==["bench"]: print(m["executable"])'
}
for b in $benches; do
  old=$(build "$work/base" "$work/target-base$tag" "$b"); cp "$old" "$work/$b-base"
  new=$(build "$repo" "$repo/target-compare$tag" "$b"); cp "$new" "$work/$b-new"
  echo "== $b: base $sha, new $(git -C "$repo" rev-parse --short HEAD)$(git -C "$repo" diff --quiet || echo '+changes'), RUSTFLAGS='$flags', load $(cut -d' ' -f1-3 /proc/loadavg)"
  python3 "$repo/benches/interleave.py" "$filter" "$rounds" "$work/$b-base" "$work/$b-new"
done
