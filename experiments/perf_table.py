#!/usr/bin/env python3
"""The performance tables of the kernel and the walkers, from criterion's output and Pinocchio's.

Reads criterion's estimates of the `soa` bench (`soa_aba/N`, `soa_batch_aba_nN/LANES`) and of
the `models` bench (`models_stride/MODEL`, `models_basin/MODEL`), and the CSV printed by
`../shared/peers/bench_pin` (Pinocchio's scalar ABA on the same planar chains), and prints two
Markdown tables: the batched ABA per lane-DoF against Pinocchio per DoF, and every walker's
strides/s and basin cells/s against the simplest walker's. With `--write FILE` it replaces the
text between `<!-- perf-table:begin -->` and `<!-- perf-table:end -->` in FILE instead (the
README and experiments/results/soa_scaling/soa_scaling.md carry these markers).

Times are criterion's mean per iteration (its point estimate). Pinocchio was run only at
n = 1, 2, 3, 4, 7, 12, …: at other n its ns/DoF is interpolated linearly in n between the two
nearest runs (its ns/DoF is nearly flat in n), and the table says so.

Usage:
    python3 experiments/perf_table.py --pin PIN.csv --load "1.1-1.3" [--criterion DIR]
        [--write FILE ...]

Reproduce (nothing else running on the machine):
    cargo bench -p pdw-benches --bench soa -- --noplot 'soa_batch_aba_n(2|3|5|8|12)/(1|64|1024)$'
    /path/to/bench_pin > pin.csv        # build line in ../shared/peers/README.md
    cargo bench -p pdw-benches --bench models -- --noplot
    python3 experiments/perf_table.py --pin pin.csv --load "$(cut -d' ' -f1-3 /proc/loadavg)"
"""
import argparse
import csv
import json
import os
import re
import sys

MODELS = ["simplest", "compass", "kneed", "seed5"]
# the kernel's speed targets: basin cells/s as a fraction of the simplest walker's
BASIN_TARGET = {"compass": 1 / 4, "kneed": 1 / 12, "seed5": 1 / 12}
ABA_TARGET_NS = 4.0
PIN_RATIO_TARGET = 100.0
COMPASS_STRIDE_TARGET_US = 6.0
THREADS = 2


def estimates(root):
    """{full_id: (mean seconds per iteration, elements per iteration, fastest sample's seconds
    per iteration)} of every benchmark (the fastest sample is the one least disturbed by other
    processes on a shared machine; the mean where criterion kept no samples)."""
    out = {}
    for dirpath, _, files in os.walk(root):
        if os.path.basename(dirpath) != "new" or "benchmark.json" not in files:
            continue
        with open(os.path.join(dirpath, "benchmark.json")) as f:
            bench = json.load(f)
        with open(os.path.join(dirpath, "estimates.json")) as f:
            mean = json.load(f)["mean"]["point_estimate"] * 1e-9
        elements = (bench.get("throughput") or {}).get("Elements", 1)
        fastest = mean
        sample_path = os.path.join(dirpath, "sample.json")
        if os.path.exists(sample_path):
            with open(sample_path) as f:
                sample = json.load(f)
            fastest = min(t / i for t, i in zip(sample["times"], sample["iters"])) * 1e-9
        out[bench["full_id"]] = (mean, elements, fastest)
    return out


def pinocchio(path):
    """[(n, ns per DoF)] of Pinocchio's ABA, sorted by n."""
    with open(path) as f:
        rows = [r for r in csv.DictReader(f)]
    return sorted((int(r["n"]), float(r["aba_ns_per_dof"])) for r in rows)


def pin_at(pin, n):
    """Pinocchio's ns/DoF at n and how it was obtained (run, or interpolated between two)."""
    for m, v in pin:
        if m == n:
            return v, f"{n}"
    below = [(m, v) for m, v in pin if m < n]
    above = [(m, v) for m, v in pin if m > n]
    if not below or not above:
        raise SystemExit(f"Pinocchio has no run around n = {n}")
    (m0, v0), (m1, v1) = below[-1], above[0]
    return v0 + (v1 - v0) * (n - m0) / (m1 - m0), f"{m0}–{m1}"


def kernel_table(est, pin):
    lines = [
        "| n | batched ABA, 1024 lanes (µs per call) | ns per lane-DoF | fastest sample: ns per "
        "lane-DoF | 64 lanes: ns per lane-DoF | 1 lane (ns) | Pinocchio ABA ns/DoF (n run) "
        "| × Pinocchio per DoF |",
        "|---|---|---|---|---|---|---|---|",
    ]
    ns = sorted({int(m.group(1)) for k in est if (m := re.match(r"soa_batch_aba_n(\d+)/", k))})
    if not ns:
        raise SystemExit("no soa_batch_aba_nN benchmarks in the criterion folder")
    for n in ns:
        def per(lanes):
            t, _, _ = est[f"soa_batch_aba_n{n}/{lanes}"]
            return t, t / (lanes * n) * 1e9
        t1024, d1024 = per(1024)
        f1024 = est[f"soa_batch_aba_n{n}/1024"][2] / (1024 * n) * 1e9
        _, d64 = per(64)
        t1, _ = per(1)
        p, runs = pin_at(pin, n)
        lines.append(
            f"| {n} | {t1024 * 1e6:.2f} | {d1024:.2f} | {f1024:.2f} | {d64:.2f} | {t1 * 1e9:.1f} | "
            f"{p:.1f} ({runs}) | {p / d1024:.0f}× |"
        )
    return lines, ns


def walker_table(est):
    lines = [
        "| model | strides/s | µs per lane-stride (2 threads) | strides/s × simplest "
        "| basin cells/s | cells/s × simplest | target (cells/s) |",
        "|---|---|---|---|---|---|---|",
    ]
    rate = {}
    for m in MODELS:
        ts, es, _ = est[f"models_stride/{m}"]
        tb, eb, _ = est[f"models_basin/{m}"]
        rate[m] = (es / ts, eb / tb)
    s0, b0 = rate["simplest"]
    for m in MODELS:
        s, b = rate[m]
        target = BASIN_TARGET.get(m)
        verdict = "—" if target is None else (
            f"≥ 1/{1 / target:.0f}: " + ("met" if b / b0 >= target else "missed"))
        frac = lambda x: "1" if x == 1 else f"1/{1 / x:.1f}"
        lines.append(
            f"| {m} | {s:,.0f} | {THREADS / s * 1e6:.1f} | {frac(s / s0)} | {b:,.0f} | "
            f"{frac(b / b0)} | {verdict} |".replace(",", " ")
        )
    return lines, rate


def block(est, pin, load):
    k, ns = kernel_table(est, pin)
    w, rate = walker_table(est)
    d5 = est["soa_batch_aba_n5/1024"][0] / (1024 * 5) * 1e9 if 5 in ns else None
    f5 = est["soa_batch_aba_n5/1024"][2] / (1024 * 5) * 1e9 if 5 in ns else None
    p5 = pin_at(pin, 5)[0] if 5 in ns else None
    compass_us = THREADS / rate["compass"][0] * 1e6
    out = [
        f"Generated by `experiments/perf_table.py` from criterion's output and Pinocchio's CSV; "
        f"load average {load} during the runs.",
        "",
        "Batched ABA (`soa` bench, one thread) against Pinocchio's scalar ABA on the same planar "
        "chains, in the same minutes:",
        "",
        *k,
        "",
    ]
    if d5 is not None:
        out += [
            f"Target at n = 5: ≤ {ABA_TARGET_NS:g} ns per lane-DoF and ≥ {PIN_RATIO_TARGET:g}× "
            f"Pinocchio — measured {d5:.2f} ns and {p5 / d5:.0f}× (mean; the fastest sample "
            f"{f5:.2f} ns and {p5 / f5:.0f}×): "
            + ("met." if d5 <= ABA_TARGET_NS and p5 / d5 >= PIN_RATIO_TARGET else "missed."),
            "",
        ]
    out += [
        "Walkers (`models` bench, 2 threads): 1024 strides from the perturbed stable gait "
        "(DOPRI5 1e-10, 64 lanes) and the basin on 41 × 41 cells (engine defaults):",
        "",
        *w,
        "",
        f"Compass per lane-stride: {compass_us:.1f} µs on 2 threads (target ≤ "
        f"{COMPASS_STRIDE_TARGET_US:g}: " + ("met" if compass_us <= COMPASS_STRIDE_TARGET_US
                                             else "missed") + ").",
    ]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--criterion", default=os.path.join(
        os.environ.get("CARGO_TARGET_DIR", "target"), "criterion"))
    ap.add_argument("--pin", required=True, help="CSV printed by bench_pin")
    ap.add_argument("--load", required=True, help="load average during the runs, as text")
    ap.add_argument("--write", nargs="*", default=[], help="files whose marked block to replace")
    a = ap.parse_args()
    text = "\n".join(block(estimates(a.criterion), pinocchio(a.pin), a.load))
    if not a.write:
        print(text)
        return
    begin, end = "<!-- perf-table:begin -->", "<!-- perf-table:end -->"
    for path in a.write:
        with open(path) as f:
            s = f.read()
        i, j = s.find(begin), s.find(end)
        if i < 0 or j < i:
            sys.exit(f"{path}: no {begin} … {end} block")
        s = s[: i + len(begin)] + "\n" + text + "\n" + s[j:]
        with open(path, "w") as f:
            f.write(s)
        print(f"wrote the tables into {path}")


if __name__ == "__main__":
    main()
