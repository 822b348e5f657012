#!/usr/bin/env python3
"""The Markov chain's accuracy against its time, grid against cloud: the compass at 3°,
σ = 0.2°, 2000 walkers of seed 1, the chain on the mid-stance section with 20 Gauss–Hermite
nodes, on a regular grid (`--chain-mesh grid`) and on a cloud of the visited states
(`--chain-mesh cloud`) at several spacings. Runs `pdw-sweep mfpt` once per (layout, mesh) — each
run gives the mesh and twice as fine — reads each file's chain numbers (`chain_mfpt_*`,
`chain_secs_*`) and the walkers' MFPT, and plots |chain − walkers| / walkers against the
chain's seconds on log axes, the walkers' 3 standard errors as a band.

Usage: experiments/chain_accuracy_speed.py [--bin target/release/pdw-sweep] [--out DIR]
Writes DIR/chain_accuracy_speed.{png,md} and one HDF5 file per run (default DIR:
experiments/results/metastable). Needs h5py and matplotlib.
"""
import argparse
import os
import subprocess
import sys

RUNS = [("grid", 15), ("grid", 30), ("cloud", 15), ("cloud", 30), ("cloud", 60)]


def run(binary, layout, mesh, out):
    path = os.path.join(out, f"compass_chain_{layout}_{mesh}.h5")
    cmd = [
        binary, "mfpt", "--model", "compass", "--sd", "0.2deg", "--walkers", "2000",
        "--max-steps", "2000", "--seed", "1", "--chain", "--chain-section", "mid-stance",
        "--chain-mesh", layout, "--mesh", str(mesh), "--nodes", "20", "--quiet", "--force",
        "--out", path,
    ]
    print(" ".join(cmd), file=sys.stderr)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    # the run's survival curve is not this experiment's figure
    os.remove(path[: -len(".h5")] + ".png")
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default="target/release/pdw-sweep")
    ap.add_argument("--out", default="experiments/results/metastable")
    a = ap.parse_args()
    import h5py
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    points = {}  # layout -> {mesh: (mfpt, secs, states)}
    walkers = None
    for layout, mesh in RUNS:
        with h5py.File(run(a.bin, layout, mesh, a.out)) as f:
            at = f["mfpt"].attrs
            walkers = (float(at["mfpt"]), float(at["stderr"]))
            for label in ("coarse", "fine"):
                n = int(at[f"chain_mesh_{label}"])
                states = int(at.get(f"chain_cloud_nodes_{label}", n ** 3))
                points.setdefault(layout, {})[n] = (
                    float(at[f"chain_mfpt_{label}"]),
                    float(at[f"chain_secs_{label}"]),
                    states,
                )
    mc, se = walkers
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    rows = ["| layout | mesh | states | MFPT | error against the walkers | seconds |", "|---|---|---|---|---|---|"]
    for layout, marker in (("grid", "s"), ("cloud", "o")):
        ms = sorted(points[layout])
        xs = [points[layout][m][1] for m in ms]
        ys = [abs(points[layout][m][0] - mc) / mc for m in ms]
        ax.plot(xs, ys, marker=marker, label=f"{layout} (mesh {', '.join(map(str, ms))})")
        for m, x, y in zip(ms, xs, ys):
            ax.annotate(str(m), (x, y), textcoords="offset points", xytext=(4, 4), fontsize=8)
            v, s, st = points[layout][m]
            rows.append(f"| {layout} | {m} | {st} | {v:.2f} | {100 * y:.1f} % | {s:.1f} |")
    ax.axhspan(0, 3 * se / mc, color="0.85", label="walkers' 3 standard errors")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylim(3 * se / mc / 10, 1.2)
    ax.set_xlabel("chain: seconds to build and solve (2 threads)")
    ax.set_ylabel("|chain − walkers| / walkers")
    ax.set_title(f"compass 3°, σ = 0.2°: walkers {mc:.1f} ± {se:.1f} steps")
    ax.legend(fontsize=8)
    fig.tight_layout()
    png = os.path.join(a.out, "chain_accuracy_speed.png")
    fig.savefig(png, dpi=120)
    md = os.path.join(a.out, "chain_accuracy_speed.md")
    with open(md, "w") as f:
        f.write(f"walkers: {mc:.3f} ± {se:.3f} steps\n\n" + "\n".join(rows) + "\n")
    print("\n".join(rows))
    print(f"wrote {png}, {md}", file=sys.stderr)


if __name__ == "__main__":
    main()
