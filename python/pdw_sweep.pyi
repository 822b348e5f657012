"""Type stubs of the `pdw_sweep` extension (see the docstrings in README.md, "Python")."""

from typing import Any, Optional, Sequence, Tuple, TypedDict

import numpy as np
import numpy.typing as npt

__version__: str

class Parameter(TypedDict):
    name: str
    unit: str
    default: float
    description: str

class ModelDescription(TypedDict):
    name: str
    description: str
    parameters: list[Parameter]
    state_names: list[str]
    section_names: list[str]

def models() -> list[ModelDescription]:
    """Every registered model: name, description, parameters (unit, default), coordinates."""

def fixed_point(
    model: str = "simplest",
    slope: Optional[float] = None,
    period: int = 1,
    gait: str = "all",
    tol: float = 1e-12,
    guess: Optional[Sequence[float]] = None,
    **params: float,
) -> list[dict[str, Any]]:
    """Period-one gaits (fixed points of the stride map), or with `period=K` the period-K
    orbits (fixed points of P^K), with the keys of `pdw-sweep fixedpoint --period K --json`'s
    `fixed_points`: gait, guess, period_k, section (ndarray, the first point), orbit (K × d_s
    ndarray, the K points in stride order), state_names, state (ndarray), period (the K strides
    together), step_length, speed, multipliers (complex ndarray of the K-step map, by decreasing
    modulus), stable, residual, iterations, validity (dict or None); for K > 1 also
    stride_periods, step_lengths and validity_per_stride.

    `slope` in rad; `params` are the model's parameters by name (see `models()`). `gait` is
    "stable", "unstable" or "all". Raises ValueError for invalid input (`period` outside
    1..=64), or when no orbit is found (the message lists every guess and why it failed)."""

def stride_map(
    model: str,
    states: npt.ArrayLike,
    slope: Optional[float] = None,
    **params: float,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.uint8], npt.NDArray[np.float64]]:
    """One step of the stride map from each row of `states` (N, d_s section coordinates),
    batched on the engine (2 threads, interpreter released). Returns (next states (N, d_s),
    outcome codes (N,) — legend in `stride_outcomes(model)`, 0 = reached the next heel strike —,
    step durations (N,)). Identical to N one-row calls."""

def stride_outcomes(model: str = "simplest", **params: float) -> dict[int, str]:
    """Legend of `stride_map`'s outcome codes: 0 ok, 1 timeout, 2 nonfinite, 3 step_too_small,
    4 max_steps, 5 too_many_events, 16 + k the model's fall of kind k (by name)."""

def basin(
    model: str = "simplest",
    slope: Optional[float] = None,
    grid: Tuple[int, int] = (101, 101),
    x: Optional[Tuple[str, float, float]] = None,
    y: Optional[Tuple[str, float, float]] = None,
    max_strides: int = 100,
    **params: float,
) -> Tuple[npt.NDArray[np.uint8], dict[int, str], dict[str, Any]]:
    """Basin of attraction of the stable gait over a grid of section states: `grid = (nx, ny)`
    points on the inclusive ranges `x = (name, lo, hi)`, `y = (name, lo, hi)` (default: the
    CLI's, 25 % around the gait); the other section coordinates at the gait's values. Returns
    (outcome codes (ny, nx), legend {code: name}, metrics: fractions, basin_entropy,
    boundary_entropy, box_size, x_name, y_name, x, y, gait, gait_multipliers). Labels equal
    `pdw-sweep basin`'s for the same grid."""

def continuation(
    model: str = "simplest",
    parameter: str = "slope",
    start: float = 0.001,
    stop: float = 0.019,
    points: int = 100,
    gait: str = "stable",
    **params: float,
) -> list[dict[str, Any]]:
    """Pseudo-arclength continuation of the gait in `parameter` from `start` to `stop`
    (`pdw-sweep fixedpoint --sweep NAME=start:stop:points`), plus the period-2 branch from the
    first period doubling. One dict per branch: name, period_k, parameter (n,), section (n, d_s),
    multipliers (n, m) complex, stable (n,), period (n,), bifurcations (list of dicts: kind,
    parameter, section, multipliers)."""

def simulate(
    model: str = "simplest",
    slope: Optional[float] = None,
    state: Optional[Sequence[float]] = None,
    gait: str = "stable",
    steps: int = 10,
    dt_out: Optional[float] = None,
    **params: float,
) -> dict[str, Any]:
    """A walk of `steps` steps from `state` (section coordinates or a full state just after a
    heel strike) or from the model's `gait`; the `pdw-sweep simulate` series as arrays: t (n,),
    x (n, d), state_names, mode, step, normal_force, tangential_force, friction_required,
    knee_torque (n, 2; NaN where a knee is free or absent), flags, energy (where defined),
    events (dict of arrays: t, kind, step, ends_step, mode_before, mode_after, pre, post),
    section (steps_done, d_s), steps_done, outcome ("ok" or how it ended), units (dict)."""
