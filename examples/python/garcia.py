"""Garcia et al. (1998)'s simplest walker with pdw_sweep: the stable gait at slope 0.009, its
Floquet multipliers, and its basin of attraction drawn with matplotlib.

    python3 examples/python/garcia.py [basin.png]
"""

import sys

import matplotlib

matplotlib.use("Agg")  # headless
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import pdw_sweep as pdw  # noqa: E402

SLOPE = 0.009
# Garcia et al. 1998: theta*, thetadot* of the stable gait at this slope.
GARCIA = (0.20031090049483, -0.19983247291764)

fp = pdw.fixed_point("simplest", slope=SLOPE, gait="stable")[0]
print(f"stable gait at slope {SLOPE}: theta = {fp['section'][0]:.14f}, "
      f"thetadot = {fp['section'][1]:.14f}")
print(f"Garcia et al. 1998:           theta = {GARCIA[0]:.14f}, thetadot = {GARCIA[1]:.14f}")
err = np.max(np.abs(fp["section"] - GARCIA))
print(f"difference {err:.1e}; multipliers {np.round(fp['multipliers'], 6)}; "
      f"period {fp['period']:.6f} sqrt(l/g)")
assert err < 1e-9, "the Garcia fixed point is not reproduced"

outcome, legend, m = pdw.basin("simplest", slope=SLOPE, grid=(121, 121),
                               x=("theta", 0.15, 0.25), y=("thetadot", -0.25, -0.15),
                               max_strides=100)
codes = sorted(int(c) for c in np.unique(outcome))
cmap = plt.get_cmap("tab10", len(codes))
index = np.searchsorted(codes, outcome)
fig, ax = plt.subplots(figsize=(6, 5))
extent = (m["x"][0], m["x"][-1], m["y"][0], m["y"][-1])
im = ax.imshow(index, origin="lower", extent=extent, aspect="auto", cmap=cmap,
               vmin=-0.5, vmax=len(codes) - 0.5, interpolation="nearest")
cbar = fig.colorbar(im, ticks=range(len(codes)))
cbar.ax.set_yticklabels([legend[c] for c in codes])
ax.plot(*fp["section"], "k+", ms=12, mew=2, label="stable gait")
ax.set_xlabel("theta (rad)")
ax.set_ylabel("thetadot (rad/sqrt(l/g))")
ax.set_title(f"simplest walker basin, slope {SLOPE} rad ({m['fractions']['gait']:.1%} gait)")
ax.legend(loc="upper right")
out = sys.argv[1] if len(sys.argv) > 1 else "garcia_basin.png"
fig.savefig(out, dpi=100)
print(f"basin: {outcome.shape[1]}x{outcome.shape[0]} cells, gait fraction "
      f"{m['fractions']['gait']:.4f}, basin entropy {m['basin_entropy']:.4f}; wrote {out}")
