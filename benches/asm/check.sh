#!/usr/bin/env bash
# The assembly guard (issue 31): build benches/asm (every hot entry point of the kernel) for
# x86-64-v3 and x86-64-v4, disassemble it, and fail on instructions that AMD CPUs microcode in
# the kernel's functions and the probe's wrappers: masked stores (vmaskmovps/pd, vpmaskmovd/q:
# LLVM folds a blend stored where its operand was loaded from into one; the MLAB lanes ran
# 1.4-2.2x slower on Zen 4 with them), gathers, scatters, and compress stores. Instruction
# counts cannot see these (callgrind counts one instruction); see docs/performance.md.
#   bash benches/asm/check.sh            # the check (CI)
#   bash benches/asm/check.sh --plant    # self-test: a planted vmaskmovpd must make it fail
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
features=()
if [ "${1:-}" = "--plant" ]; then features=(--features plant); fi
status=0
for level in x86-64-v3 x86-64-v4; do
  dir="${MLAB_ASM_TARGET_DIR:-$here/target}/$level"
  (cd "$here" && CARGO_TARGET_DIR="$dir" RUSTFLAGS="-C target-cpu=$level -C symbol-mangling-version=v0" \
    cargo build --release --quiet "${features[@]}")
  objdump -d --no-show-raw-insn -C "$dir/release/mlab-asm" | python3 -c '
import re, sys
level = sys.argv[1]
# Mnemonics AMD microcodes (Zen 2-4): masked moves, gathers, scatters; compress to memory.
bad = re.compile(r"^(v?p?maskmov[a-z]*|v?p?gather[a-z]*|v?p?scatter[a-z]*)$")
compress = re.compile(r"^v?p?compress[a-z]*$")
ours = re.compile(r"(^|[<\s(&])(mlab|mlab_asm)::")
fn, scanned, hits, wrappers = None, 0, {}, set()
for line in sys.stdin:
    m = re.match(r"^[0-9a-f]+ <(.*)>:$", line)
    if m:
        fn = m.group(1) if ours.search(m.group(1)) else None
        if fn:
            scanned += 1
            w = re.match(r"mlab_asm::(\w+)", fn)
            if w: wrappers.add(w.group(1))
        continue
    if fn is None or "\t" not in line:
        continue
    ins = line.split("\t")[1].split()
    if not ins:
        continue
    op = ins[0]
    if bad.match(op) or (compress.match(op) and "(" in line.split("\t")[1].split(",")[-1]):
        hits.setdefault(fn, {}).setdefault(op, 0)
        hits[fn][op] += 1
need = {"lanes_mlab", "lanes_hybrid", "framebuffer", "main"}
if not need <= wrappers:
    print(f"asm check {level}: the probe wrappers {sorted(need - wrappers)} are missing from the binary: nothing was checked")
    sys.exit(2)
for f, ops in sorted(hits.items()):
    print(f"asm check {level}: {f}: " + ", ".join(f"{n} x {op}" for op, n in sorted(ops.items())))
print(f"asm check {level}: {scanned} functions of mlab and its probe scanned, {len(hits)} with microcoded instructions")
sys.exit(1 if hits else 0)
' "$level" || status=1
done
exit $status
