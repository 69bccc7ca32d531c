#!/usr/bin/env bash
# Instructions per element of one bench function, counted by callgrind (repeatable, unlike
# wall time on a shared machine). Usage:
#   benches/callgrind.sh BENCH_BINARY 'criterion/id' 'crate::function' ELEMENTS_PER_CALL [inclusive]
# BENCH_BINARY: the path `cargo bench --bench kernel --no-run` prints (build it with
# RUSTFLAGS="-C target-cpu=x86-64-v3" for AVX2, never target-cpu=native: valgrind faults on
# AVX-512). The bench drivers are #[inline(never)], so each is one symbol. By default the
# count is exclusive (the function's own instructions, callees that were inlined included);
# with `inclusive`, the functions it calls are counted too (for drivers whose callees are
# not inlined, such as the framebuffer span inserts in benches/batch.rs).
set -euo pipefail
bin=$1; id=$2; fn=$3; per_call=$4; mode=${5:-exclusive}
out=$(mktemp)
valgrind --tool=callgrind --callgrind-out-file="$out" "$bin" --bench --profile-time 1 "^$id\$" >/dev/null 2>&1
python3 - "$out" "$fn" "$id" "$per_call" "$mode" <<'PY'
import re, sys
path, fn, bench, per_call, mode = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5]
names, current, calls, ir, pending, call_cost = {}, None, 0, 0, False, False
for line in open(path):
    m = re.match(r"(c?)fn=\((\d+)\)(?: (.*))?", line)
    if m:
        if m.group(3):
            names[m.group(2)] = m.group(3)
        name = names.get(m.group(2), "")
        if m.group(1):  # a call from the current function to `name`
            pending = name == fn
        else:
            current = name
        continue
    if line.startswith("calls="):
        if pending:
            calls += int(line.split()[0].split("=")[1])
        call_cost = True
        continue
    if call_cost:  # inclusive cost line of a call made by `current`
        call_cost = False
        if mode == "inclusive" and current == fn and not pending:
            parts = line.split()
            if len(parts) >= 2:
                ir += int(parts[1])
        pending = False
        continue
    if current == fn and (line[:1].isdigit() or line[:1] in "+-*"):
        parts = line.split()
        if len(parts) >= 2:
            ir += int(parts[1])
print(f"{bench}: {ir} instructions ({mode}) in {calls} calls = {ir / max(calls, 1) / per_call:.2f} per element")
PY
rm -f "$out"
