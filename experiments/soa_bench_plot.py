#!/usr/bin/env python3
"""Turn the criterion results of `cargo bench -p pdw-benches --bench soa` into a log-log plot
(time per forward-dynamics call vs number of joints n, every method) and a Markdown table.

Reads <target>/criterion/<group>/<id>/new/estimates.json, where <target> is $CARGO_TARGET_DIR
(default: ./target) or --target. Writes experiments/results/soa_scaling/{soa_scaling.png,
soa_scaling.md} (or --out).
"""
import argparse
import json
import os
import sys

SCALAR = [
    ("soa_aba", "ABA (O(n) articulated body)"),
    ("soa_crba_cholesky", "CRBA + Cholesky (O(n^2) + O(n^3))"),
    ("soa_naive_lu", "naive dense H^T Phi^T M Phi H + LU (O(n^3))"),
]
BATCH = ["soa_batch_aba_n2", "soa_batch_aba_n5"]


def estimate(target, group, ident):
    path = os.path.join(target, "criterion", group, str(ident), "new", "estimates.json")
    if not os.path.exists(path):
        return None
    with open(path) as f:
        est = json.load(f)
    return est["median"]["point_estimate"], est["mean"]["standard_error"]


def ids(target, group):
    d = os.path.join(target, "criterion", group)
    if not os.path.isdir(d):
        return []
    out = []
    for name in os.listdir(d):
        if name.isdigit() and os.path.exists(os.path.join(d, name, "new", "estimates.json")):
            out.append(int(name))
    return sorted(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    here = os.path.dirname(os.path.abspath(__file__))
    ap.add_argument("--target", default=os.environ.get("CARGO_TARGET_DIR", os.path.join(here, "..", "target")))
    ap.add_argument("--out", default=os.path.join(here, "results", "soa_scaling"))
    ap.add_argument("--note", default="", help="free text appended to the table (machine, load)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    data = {}
    for group, _ in SCALAR:
        data[group] = {n: estimate(args.target, group, n) for n in ids(args.target, group)}
    if not any(data.values()):
        sys.exit(f"no criterion results under {args.target}/criterion (run the soa bench first)")

    lines = ["# Planar forward dynamics: time per call (median of criterion samples)", ""]
    lines.append("Random planar revolute chains, one thread. ns/DoF = time / n.")
    lines.append("")
    ns = sorted(set().union(*[set(d) for d in data.values()]))
    header = "| n | " + " | ".join(f"{g} (ns) | {g} (ns/DoF)" for g, _ in SCALAR) + " | naive / aba | crba / aba |"
    lines.append(header)
    lines.append("|" + "---|" * (1 + 2 * len(SCALAR) + 2))
    for n in ns:
        row = [str(n)]
        vals = {}
        for g, _ in SCALAR:
            e = data[g].get(n)
            if e is None:
                row += ["–", "–"]
            else:
                vals[g] = e[0]
                row += [f"{e[0]:.1f}", f"{e[0] / n:.1f}"]
        a = vals.get("soa_aba")
        row.append(f"{vals['soa_naive_lu'] / a:.1f}" if a and "soa_naive_lu" in vals else "–")
        row.append(f"{vals['soa_crba_cholesky'] / a:.2f}" if a and "soa_crba_cholesky" in vals else "–")
        lines.append("| " + " | ".join(row) + " |")
    lines.append("")
    lines.append("## Batched ABA (lanes × n matrices, one thread)")
    lines.append("")
    lines.append("| group | lanes | time per call (µs) | ns per lane | ns per lane-DoF |")
    lines.append("|---|---|---|---|---|")
    batch_rows = []
    for g in BATCH:
        n = int(g.rsplit("n", 1)[1])
        for lanes in ids(args.target, g):
            e = estimate(args.target, g, lanes)
            if e is None:
                continue
            t = e[0]
            batch_rows.append((g, n, lanes, t))
            lines.append(f"| {g} | {lanes} | {t / 1e3:.2f} | {t / lanes:.1f} | {t / (lanes * n):.2f} |")
    if args.note:
        lines += ["", args.note]
    table = "\n".join(lines) + "\n"
    with open(os.path.join(args.out, "soa_scaling.md"), "w") as f:
        f.write(table)
    print(table)

    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        sys.exit("matplotlib missing: pip install matplotlib")
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.8))
    for (g, label), marker in zip(SCALAR, "os^"):
        pts = sorted((n, e[0]) for n, e in data[g].items() if e)
        if pts:
            ax1.loglog([p[0] for p in pts], [p[1] for p in pts], marker=marker, label=label)
    if data["soa_aba"]:
        n0 = min(data["soa_aba"])
        t0 = data["soa_aba"][n0][0]
        xs = [n0, max(ns)]
        ax1.loglog(xs, [t0 * x / n0 for x in xs], "k:", lw=0.8, label="∝ n")
        ax1.loglog(xs, [t0 * (x / n0) ** 3 for x in xs], "k--", lw=0.8, label="∝ n³")
    ax1.set_xlabel("joints n")
    ax1.set_ylabel("time per forward-dynamics call (ns)")
    ax1.set_title("scalar forward dynamics")
    ax1.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=8)
    for g, marker in zip(BATCH, "os"):
        pts = sorted((lanes, t / (lanes * n)) for gg, n, lanes, t in batch_rows if gg == g)
        if pts:
            ax2.semilogx([p[0] for p in pts], [p[1] for p in pts], marker=marker, label=g.replace("soa_batch_aba_", "batched ABA, "))
    if data["soa_aba"]:
        for n, ls in [(2, ":"), (5, "--")]:
            e = data["soa_aba"].get(n)
            if e:
                ax2.axhline(e[0] / n, color="gray", ls=ls, lw=0.8, label=f"scalar ABA n={n}")
    ax2.set_xlabel("lanes")
    ax2.set_ylabel("ns per lane-DoF")
    ax2.set_title("batched ABA (one thread)")
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(fontsize=8)
    fig.tight_layout()
    png = os.path.join(args.out, "soa_scaling.png")
    fig.savefig(png, dpi=120)
    print(f"wrote {png}")


if __name__ == "__main__":
    main()
