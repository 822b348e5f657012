#!/usr/bin/env python3
"""Read a pdw-sweep basin file with h5py (an independent HDF5 reader) and check its schema.

    python3 experiments/read_basin.py basin.h5 [--png out.png]

Prints the run's attributes, the outcome fractions recomputed here from /basin/outcome next to
the ones stored in /metrics, and exits non-zero if the file breaks the documented schema.
With --png (needs matplotlib) it also draws the basin. Needs: h5py, numpy.
"""
import json
import sys

import h5py
import numpy as np


def main(path, png=None):
    problems = []
    with h5py.File(path, "r") as f:
        a = f.attrs
        fmt = a["format"]
        if fmt != "pdw-sweep basin v1":
            problems.append(f"format is {fmt!r}")
        for k in ["version", "command", "created", "model", "slope", "params", "integrator",
                  "tolerances", "max_strides", "elapsed_s", "complete"]:
            print(f"{k:>12}: {a[k]}")
        params = json.loads(a["params"])
        x, y = f["grid/x"][:], f["grid/y"][:]
        xn, yn = f["grid/x"].attrs["name"], f["grid/y"].attrs["name"]
        outcome = f["basin/outcome"][:]
        strides = f["basin/strides"][:]
        final = f["basin/final"][:]
        done = f["basin/rows_done"][:].astype(bool)
        legend = {int(k): v for k, v in json.loads(f["basin/outcome"].attrs["legend"]).items()}
        names = json.loads(f["basin/final"].attrs["names"])
        print(f"{'grid':>12}: {xn} {x[0]}..{x[-1]} ({x.size}), {yn} {y[0]}..{y[-1]} ({y.size})")
        print(f"{'params':>12}: {params}")
        print(f"{'legend':>12}: {legend}")
        print(f"{'final':>12}: {final.shape} ({', '.join(names)})")
        print(f"{'compression':>12}: {f['basin/final'].compression}, chunks {f['basin/final'].chunks}")
        if outcome.shape != (y.size, x.size) or strides.shape != outcome.shape:
            problems.append(f"outcome/strides shape {outcome.shape}, {strides.shape}")
        if final.shape != (y.size, x.size, len(names)):
            problems.append(f"final shape {final.shape}")
        if "gait" not in legend.values():
            problems.append("no 'gait' in legend")
        codes = set(np.unique(outcome[done]).tolist())
        if not codes <= set(legend):
            problems.append(f"codes {codes - set(legend)} not in legend")
        if a["complete"] and "shard_count" not in a and not done.all():
            problems.append("complete but rows missing")
        if "metrics" in f:
            stored = json.loads(f["metrics"].attrs["fractions"])
            n = outcome[done].size
            print(f"{'outcome':>12}  {'here':>9}  {'stored':>9}")
            for c, name in sorted(legend.items()):
                here = np.count_nonzero(outcome[done] == c) / n
                st = stored.get(name, float("nan"))
                print(f"{name:>12}  {here:9.6f}  {st:9.6f}")
                if abs(here - st) > 1e-12:
                    problems.append(f"fraction of {name}: {here} here, {st} stored")
            m = f["metrics"].attrs
            print(f"{'S_b':>12}: {m['basin_entropy']}   S_bb: {m['boundary_entropy']}   box: {m['entropy_box']}")
        for name, g in f.get("attractors", {}).items():
            mult = g["multipliers_re"][:] + 1j * g["multipliers_im"][:]
            print(f"{'attractor':>12}: {name} period {g.attrs['period_strides']} "
                  f"section {g['section'][:].tolist()} |λ| {np.abs(mult).tolist()}")
    if png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        plt.imshow(outcome, origin="lower", extent=[x[0], x[-1], y[0], y[-1]], aspect="auto",
                   interpolation="nearest", cmap="tab10", vmin=0, vmax=9)
        plt.xlabel(xn)
        plt.ylabel(yn)
        plt.savefig(png, dpi=120)
    for p in problems:
        print("PROBLEM:", p, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    args = sys.argv[1:]
    if not args:
        sys.exit(__doc__)
    png = args[args.index("--png") + 1] if "--png" in args else None
    sys.exit(main(args[0], png))
