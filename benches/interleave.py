#!/usr/bin/env python3
"""Interleaved criterion runs of several bench binaries, minimum of the lower bounds.

On a shared VM one criterion run can be 2x off; running each binary's filter in turn, several
rounds, and keeping the lowest `time:` lower bound per (bench, binary) gives figures that agree
between sessions to a few per cent. Usage:

    python3 benches/interleave.py FILTER ROUNDS BINARY [BINARY ...]

(BINARY: the paths `cargo bench --bench batch --no-run` prints, one per target.) With two or
more binaries, a last table gives each bench's minimum of every binary as a ratio to the first
binary's (benches/compare.sh: base first).
"""
import subprocess, re, sys, collections
filt, rounds, bins = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
d = collections.defaultdict(list)
for r in range(rounds):
    for b in bins:
        out = subprocess.run([b, '--bench', '--warm-up-time', '0.3', '--measurement-time', '1', filt], capture_output=True, text=True).stdout
        name = None
        for line in out.splitlines():
            m = re.match(r'^(\S+/\S+)\s*(time:.*)?$', line.strip())
            if line.strip() and not line.startswith(' ') and '/' in line.split()[0]:
                name = line.split()[0]
            t = re.search(r'time:\s+\[([\d.]+) (\w+) ([\d.]+) (\w+)', line)
            if t and name:
                v = float(t.group(3)); u = t.group(4)
                v *= {'ns':1e-3,'µs':1,'us':1,'ms':1e3,'s':1e6}[u]
                d[(name, b)].append(v)
for k in sorted(d):
    print(f"{k[0]:45s} {k[1][-22:]:22s} min {min(d[k]):9.1f} us  median {sorted(d[k])[len(d[k])//2]:9.1f}  n={len(d[k])}")
if len(bins) > 1:
    print(f"\n{'bench':45s} " + " ".join(f"{'bin%d/bin0' % i:>10s}" for i in range(1, len(bins))))
    for name in sorted({k[0] for k in d}):
        if (name, bins[0]) not in d:
            continue
        base = min(d[(name, bins[0])])
        cells = [f"{min(d[(name, b)]) / base:10.3f}" if (name, b) in d else f"{'-':>10s}" for b in bins[1:]]
        print(f"{name:45s} " + " ".join(cells))
