#!/usr/bin/env python3
"""Criterion estimates as a Markdown table.

For every benchmark under a criterion output folder (default: $CARGO_TARGET_DIR/criterion or
target/criterion) print: the id, criterion's mean per iteration with its 95 % interval, the
fastest sample (time/iterations of the quickest sample: the least disturbed by other processes
on a shared machine), and both divided by the declared `Throughput::Elements` (time per element,
e.g. per lane-stride or per cell).

Usage: python3 experiments/criterion_table.py [CRITERION_DIR] [ID_PREFIX ...]
"""
import json
import os
import sys


def fmt(sec):
    for unit, f in (("s", 1.0), ("ms", 1e-3), ("µs", 1e-6), ("ns", 1e-9)):
        if sec >= f:
            return f"{sec / f:.3g} {unit}"
    return f"{sec / 1e-9:.3g} ns"


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.environ.get("CARGO_TARGET_DIR", "target"), "criterion")
    prefixes = sys.argv[2:]
    rows = []
    for dirpath, _, files in os.walk(root):
        if os.path.basename(dirpath) != "new" or "benchmark.json" not in files:
            continue
        bench = json.load(open(os.path.join(dirpath, "benchmark.json")))
        if prefixes and not any(bench["full_id"].startswith(p) for p in prefixes):
            continue
        est = json.load(open(os.path.join(dirpath, "estimates.json")))["mean"]
        sample = json.load(open(os.path.join(dirpath, "sample.json")))
        best = min(t / i for t, i in zip(sample["times"], sample["iters"])) * 1e-9
        mean = est["point_estimate"] * 1e-9
        lo = est["confidence_interval"]["lower_bound"] * 1e-9
        hi = est["confidence_interval"]["upper_bound"] * 1e-9
        n = (bench.get("throughput") or {}).get("Elements", 1)
        rows.append((bench["full_id"], mean, lo, hi, best, n))
    rows.sort()
    print("| benchmark | mean [95 % CI] per iteration | fastest sample | elements | mean per element | fastest per element |")
    print("|---|---|---|---|---|---|")
    for fid, mean, lo, hi, best, n in rows:
        print(f"| `{fid}` | {fmt(mean)} [{fmt(lo)}, {fmt(hi)}] | {fmt(best)} | {n} | "
              f"{fmt(mean / n)} | {fmt(best / n)} |")


if __name__ == "__main__":
    main()
