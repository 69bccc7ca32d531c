#!/usr/bin/env python3
"""Summarise criterion results as a Markdown table: ns per element (fragment or pixel) and
throughput, from target*/criterion/**/new/{estimates,benchmark}.json.

Usage: python3 benches/report.py [CRITERION_DIR ...]   (default: target/criterion)
"""
import json
import pathlib
import sys


def rows(root):
    for bench in sorted(pathlib.Path(root).glob("**/new/benchmark.json")):
        meta = json.loads(bench.read_text())
        est = json.loads((bench.parent / "estimates.json").read_text())
        thr = meta.get("throughput") or {}
        elements = thr.get("Elements") or thr.get("elements")
        if not elements:
            continue
        ns = est["median"]["point_estimate"] / elements
        lo = est["median"]["confidence_interval"]["lower_bound"] / elements
        hi = est["median"]["confidence_interval"]["upper_bound"] / elements
        yield meta["full_id"], ns, lo, hi


def main():
    roots = sys.argv[1:] or ["target/criterion"]
    for root in roots:
        print(f"\n{root}\n")
        print("| bench | ns / element (median) | 95% CI | M elements/s |")
        print("|---|---:|---|---:|")
        for name, ns, lo, hi in rows(root):
            print(f"| {name} | {ns:.3f} | {lo:.3f}-{hi:.3f} | {1e3 / ns:.0f} |")


if __name__ == "__main__":
    main()
