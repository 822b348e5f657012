"""Type stubs of the `pdw_sweep` extension (functions and results: python/README.md)."""

import os
from typing import Any, List, Optional, Sequence, Tuple, TypedDict, Union

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
    slope: Optional[Union[float, str]] = None,
    period: int = 1,
    gait: str = "all",
    tol: float = 1e-12,
    guess: Optional[Sequence[float]] = None,
    jacobian: bool = False,
    **params: float,
) -> list[dict[str, Any]]:
    """Period-one gaits (fixed points of the stride map), or with `period=K` the period-K
    orbits (fixed points of P^K), with the keys of `pdw-sweep fixedpoint --period K --json`'s
    `fixed_points`: gait, guess, period_k, section (ndarray, the first point), orbit (K × d_s
    ndarray, the K points in stride order), state_names, state (ndarray), period (the K strides
    together), step_length, speed, multipliers (complex ndarray of the K-step map, by decreasing
    modulus), stable, residual, iterations, validity (dict or None); for K > 1 also
    stride_periods, step_lengths and validity_per_stride.

    A validity dict has the keys of `fixedpoint --json`'s `validity`, located on the dense
    solution: valid, min_normal_force, max_friction_required, min_knee_torque,
    normal_force_negative, knee_unlocks, swing_foot_scuffs, impact_violation, continuous, fell,
    t_min_normal_force, t_max_friction_required, knee_torque {stance, swing}, clearance_rule
    ("whole_swing" or "after_mid_stance"), min_clearance, scuff_depth, scuff_intervals,
    t_mid_stance, impact_friction_required, impacts (event, t, checked, friction_required,
    energy_lost, min_margin, entries), margins (name, raw, scale, scale_name, relative, t),
    binding (the criterion with the smallest relative margin), min_relative_margin and
    violations (criterion, t_start, t_end, worst).

    `slope` in rad, or a string with a unit as the CLI's --slope takes it ("3deg", "3°",
    "0.05"; a slope above 0.3 rad gives a UserWarning naming its degrees); `params` are the
    model's parameters by name (see `models()`). `gait` is
    "stable", "unstable" or "all". Raises ValueError for invalid input (`period` outside
    1..=64), or when no orbit is found (the message lists every guess and why it failed).

    With `jacobian=True` (period one) each gait also has: jacobian (d_s × d_s, DP by the
    variational equations), eigenvalues (complex, by decreasing modulus) and eigenvectors
    (complex d_s × d_s, column k for eigenvalue k, unit norm), impacts (every reset along the
    stride: event, t, mode_before, mode_after, pre (the pre-impact state), saltation (d × d)),
    lyapunov (the finite-time Lyapunov exponents over lyapunov_strides = 100 strides)."""

def gaits(
    model: str = "simplest",
    slope: Optional[Union[float, str]] = None,
    starts: int = 256,
    search_box: Optional[dict[str, tuple[float, float]]] = None,
    gait: str = "all",
    tol: float = 1e-12,
    threads: int = 2,
    **params: float,
) -> dict[str, Any]:
    """Every gait found without a guess, as `pdw-sweep fixedpoint --search` finds them: Newton
    from `starts` states spread over a box of the section (a Halton sample of the model's own
    box, with the coordinates named in `search_box` replaced by their `(lo, hi)`), and the
    stride map iterated 200 strides from each to see where it settles (a gait, a period-K orbit
    up to K = 8, a fall).

    Returns a dict: `gaits` (the dicts of `fixed_point`, each with `starts_newton`, the starts
    from which Newton converged to it, and `starts_settled`, the starts whose iterates settled
    on it, and `starts_near_gaits`, the starts seeded 1e-3 from the unstable gaits along their
    unstable eigenvector that settled on it), `orbits` (the period-K attractors, K ≥ 2:
    period_k, orbit (K × d_s ndarray), multipliers, stable, period, residual, starts_settled,
    starts_near_gaits), `starts`, `fell` (starts whose iterates fell), `unsettled` (neither fell
    nor settled), `near_gait_starts` and `box` ({name: (lo, hi)}). The
    result is the same for any `threads`. Raises ValueError for invalid input (a name not in the
    section, an empty range, a model without a box of its own and no `search_box` for every
    coordinate)."""


def stride_map(
    model: str,
    states: npt.ArrayLike,
    slope: Optional[Union[float, str]] = None,
    **params: float,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.uint8], npt.NDArray[np.float64]]:
    """One stride of the stride map (heel strike to heel strike) from each row of `states`
    (N, d_s section coordinates), batched on the engine (2 threads, interpreter released).
    Returns (next states (N, d_s), end codes (N,), stride durations (N,)). The codes are those
    of a basin file's /basin/outcome for the same ends (legend in `stride_outcomes(model)`):
    13 heel_strike (reached the next heel strike: a complete stride), 2 fall_forward,
    3 fall_backward, 10 fall_knee_bent, 11 fall_knee_buckled, 12 fall_rolls_back, 6 fall (a
    fall of another kind), 5 fall_no_heel_strike (no heel strike within the stride time
    budget), 8 nonfinite, 9 integrator_failure (the step size collapsed, the integrator's step
    budget ran out, or more than 64 events in one stride: the three are one class, as in a
    basin). Identical to N one-row calls. (Older builds used other codes: 0 ok, 1 timeout,
    2 nonfinite, 3 step_too_small, 4 max_steps, 5 too_many_events, 16 + k a fall of kind k.)"""

def stride_outcomes(model: str = "simplest", **params: float) -> dict[int, str]:
    """Legend of `stride_map`'s codes, {code: name}, for the ends a stride of `model` can have:
    heel_strike, fall_no_heel_strike, nonfinite, integrator_failure and the model's fall kinds
    (its terminal guards). Codes and names are the one table of ends, the basin file's legend
    for the same ends (`heel_strike`, 13, is a stride's end only, never a basin cell's)."""

def basin(
    model: str = "simplest",
    slope: Optional[Union[float, str]] = None,
    grid: Union[Tuple[int, int], Tuple[int, int, int]] = (101, 101),
    x: Optional[Tuple[str, float, float]] = None,
    y: Optional[Tuple[str, float, float]] = None,
    z: Optional[Tuple[str, float, float]] = None,
    max_strides: int = 100,
    threads: int = 2,
    **params: float,
) -> Tuple[npt.NDArray[np.uint8], dict[int, str], dict[str, Any]]:
    """Basins of every attractor over a grid of section states, as `pdw-sweep basin`: `grid =
    (nx, ny)` points on the inclusive ranges `x = (name, lo, hi)`, `y = (name, lo, hi)` (default:
    the CLI's, 25 % around the stable period-one gait, else around the first period-one orbit
    found; both must be given when there is none); the other section coordinates at that
    orbit's values. The attractors reached from the grid's box (period-k gaits, chaotic ones)
    are discovered first from a fixed seed set, then each cell is labelled by the attractor it
    reaches, a fall, `other`, `nonfinite` or `timeout`. Labels, legend and attractors equal the
    CLI's for the same grid, for any `threads`. With `z = (name, lo, hi)` (a third section
    coordinate) and `grid = (nx, ny, nz)` the grid is 3-D and the outcome array (nz, ny, nx),
    the order of the CLI file's `/basin/outcome`; metrics then has `z_name` and `z` (nz,) too.

    Returns (outcome codes (ny, nx) uint8, legend {code: name}: exactly the codes the outcome
    can hold — the fixed codes (0 `gait` only when there is a stable period-one gait; falls,
    other, nonfinite, timeout, ...) and one
    code from 16 up per other attractor (`period-2`, `period-2b`, `chaotic`, ...), metrics):
    metrics has fractions {name: fraction of cells}, basin_entropy, boundary_entropy, box_size,
    x_name, y_name, x (nx,), y (ny,), attractors (list of dicts in discovery order: name, code,
    kind ("periodic" or "chaotic"), period_k (0 if chaotic), points (k × d_s, the orbit in
    stride order; a chaotic attractor's sample), multipliers (complex, of the k-stride map;
    empty if chaotic), period_time, radius), gait and gait_multipliers (the stable period-one
    gait's section and multipliers, None without one). Raises ValueError for invalid input."""

def continuation(
    model: str = "simplest",
    parameter: str = "slope",
    start: float = 0.001,
    stop: float = 0.019,
    points: int = 100,
    gait: str = "stable",
    threads: int = 2,
    max_period: int = 2,
    start_at: Optional[float] = None,
    **params: float,
) -> list[dict[str, Any]]:
    """`pdw-sweep fixedpoint --sweep NAME=start:stop:points --max-period P --from MU`:
    pseudo-arclength continuation of the period-one gait (`gait`: the stable one, else the
    first found; or "unstable") in `parameter`, and the period-doubling cascade followed down to
    period `max_period` (a power of two, 1 to 64; default 2): on each period-k branch the
    period-2k branch is switched onto at its first period doubling. Each branch is put on the
    `points` evenly spaced values start, ..., stop: exactly one point per value where the branch
    exists (a branch that folds back: one per crossing; a period-2k branch: the values past its
    doubling), corrected at that value. A value whose correction fails, or a switch that fails,
    is a UserWarning.

    The start gait is found at `start_at` (within start..stop) and continued both ways into one
    branch; without it, at `start` (from the model's guesses, else by a scan of the section) or,
    when `start` has no gait, at the values inward from it (the middle, then the quarter
    points). Raises ValueError when none of them has a gait, naming the values tried.

    One dict per branch (n = its points, K = period_k, m = multipliers per point): name
    ("period-1", "period-2", "period-4", ...), period_k, parameter (n,), section (n, d_s; the orbit's first
    point), orbit (n, K, d_s; all K points in stride order), period (n,; the K strides
    together), step_length (n, K; per stride), speed (n,; K step lengths over the period),
    stable (n,), valid (n, K; validity along each stride, True where unchecked), validity
    (n lists of K dicts or None, the keys of `fixed_point`'s validity), multipliers (n, m)
    complex (of the K-stride map, signed), bifurcations (list of dicts located on this branch:
    kind ("period_doubling", "fold", "branch_point", "neimark_sacker"), parameter, section,
    multipliers), internal_points (the continuation's own steps). Equal to the CLI's `--json`
    branches."""

def gait_sensitivity(
    model: str = "simplest",
    slope: Optional[Union[float, str]] = None,
    indicators: Optional[Union[str, Sequence[str]]] = None,
    guess: Optional[Sequence[float]] = None,
    **params: float,
) -> dict[str, Any]:
    """Gait sensitivity norm (Hobbelen & Wisse 2007) of the stable period-one gait (or the gait
    found from `guess`) against the slope of the next landing line, as `pdw-sweep fixedpoint
    --gsn`: norm, indicators (names; default step-time, step-length; also speed),
    per_indicator (ndarray), the linear system x' = A x + B e, g = C x + D e as ndarrays A
    (n × n), B (n × 1), C (m × n), D (m × 1) with x = (section state, last landing slope),
    gramian, indicator_values, spectral_radius, fd_error (accuracy of the differences),
    section, slope. An unstable gait raises ValueError (its norm is infinite)."""
    ...

def mfpt(
    model: str = "simplest",
    slope: Optional[Union[float, str]] = None,
    sd: Optional[Union[float, str]] = None,
    walkers: int = 1000,
    max_strides: int = 1000,
    seed: int = 0,
    threads: int = 2,
    terrain: str = "slope",
    chain: bool = False,
    mesh: Optional[int] = None,
    nodes: Optional[int] = None,
    dist: str = "normal",
    chain_section: str = "landing",
    chain_mesh: str = "grid",
    stride_map: str = "auto",
    max_steps: Optional[int] = None,
    **params: float,
) -> dict[str, Any]:
    """Mean first-passage time on a random slope per step (`pdw-sweep mfpt`, Monte Carlo):
    walkers start on the stable gait of the mean slope `slope`; every landing line has a slope
    drawn from N(slope, sd²) (`sd` in rad or '1deg'). Returns mfpt and stderr (steps / falls,
    the maximum-likelihood estimate), restricted_mean and restricted_stderr (mean of
    min(T, max_strides)), walkers, falls, censored, total_steps, survival (max_strides + 1,),
    failures (fall kind → count), start (section state), mean, sd. The same on any `threads`.
    `max_strides`: heel strikes at most per walker (censored beyond); `max_steps` is its old
    spelling, still accepted.
    With `sd="A:B:N"` (e.g. "0.3deg:0.7deg:5", as `mfpt --sd A:B:N`): one run per standard
    deviation with the same seed, a dict of arrays sd, mfpt, stderr, restricted_mean, falls,
    censored, total_steps (one value per σ) and mean. `terrain="step-down"`: a random foothold
    height per step instead (`sd` a plain length, the mean the model's `step_down`, a step down
    positive); both dicts also hold `terrain`. `dist`: the draws' distribution ("normal",
    "uniform" of unit variance, "file:PATH" of values), in words as `dist`. `chain=True` (one
    sd) adds `chain`: the Markov chain at mesh and 2 mesh (arrays of two: mesh, mfpt, lambda,
    mfpt_lambda, mfpt_quasi_stationary, fall_per_step, out_of_mesh, states), refinement_change,
    warning (None when converged), quadrature_nodes, quadrature_mfpt, quadrature_change,
    quadrature_warning (the coarse mesh with twice the nodes; None within 0.5 %, all None on a
    cloud), nodes, quadrature, box (corner, edges, widening_passes,
    out_share), section (`chain_section`: "landing", or "mid-stance": no layers, one-mode
    models), layout (`chain_mesh`: "grid", or "cloud": the visited mid-stance states thinned to
    the grid's spacing and closed under their landings, with cloud: cell, seeds, nodes, passes
    per mesh). `stride_map`: "auto" (the walkers' strides in closed form where the model has
    one — the rimless wheel — integrated otherwise), "closed-form" or "integrated"; both dicts
    hold `stride_map`, which ran ("closed form" or "integrated")."""
    ...

def disturb(
    model: str = "simplest",
    terrain: str = "step-down",
    once: Optional[Union[float, str]] = None,
    largest: bool = False,
    strides: int = 200,
    tol: float = 1e-5,
    slope: Optional[Union[float, str]] = None,
    **params: float,
) -> dict[str, Any]:
    """One disturbance from the stable gait (`pdw-sweep disturb`, the dict of its `--json`):
    model, terrain, parameter, nominal, unit, strides, and with `once=d` (stride 1's foothold d
    lower; terrain "slope": its line d rad steeper, or a string with its unit) under `once`:
    disturbance, fell, strides, fall, deviation (per stride, section ∞-norm from the gait),
    returned_after (first stride within return_tol, or None), return_tol; with `largest=True`
    under `largest` one dict per direction (direction, survived, falls_at, at_double_spacing),
    bisected to `tol`. `steps=` is the old spelling of `strides=`."""
    ...

def simulate(
    model: str = "simplest",
    slope: Optional[Union[float, str]] = None,
    state: Optional[Sequence[float]] = None,
    gait: Optional[str] = None,
    strides: int = 10,
    dt_out: Union[float, str, None] = None,
    out: Optional[Union[str, "os.PathLike[str]"]] = None,
    force: bool = False,
    **params: float,
) -> dict[str, Any]:
    """A walk of `strides` strides from `state` (section coordinates or a full state just after a
    heel strike) or from the model's `gait` (default "stable"): the report of `pdw-sweep simulate
    --json` (model, slope, start, strides, strides_done, samples, event_count, outcome "ok" or
    how it ended, fell, dt_out, dt_out_source, out) and the series as arrays: t (n,), x (n, d),
    state_names, mode, step, normal_force, tangential_force, friction_required, knee_torque (n, 2;
    NaN where a knee is free or absent), flags, energy (where defined), events (dict of arrays:
    t, kind, step, ends_step, mode_before, mode_after, pre, post), section (strides_done, d_s),
    units (dict), positions (n, P, 2) of the points point_names and com (n, 2) in the walk's fixed
    slope frame (positions_frame; none for round feet). With `out` (.h5, .hdf5, .csv) the CLI's
    file is written too (an existing one only with force=True). dt_out=None: 100 samples per
    stride from a gait (T/50, T = sqrt(L/g), from a state) and both sides of every event;
    "steps": every accepted integrator step and event; a number: exactly at t = k dt_out.
    `steps=` is the old spelling of `strides=` (and the key steps_done of strides_done).
    Docs: docs/python.md."""

def orbit_diagram(
    model: str = "simplest",
    parameter: str = "slope",
    start: float = 0.001,
    stop: float = 0.019,
    points: int = 100,
    gait: str = "stable",
    guess: Optional[Sequence[float]] = None,
    tol: float = 1e-12,
    threads: int = 2,
    **params: float,
) -> dict[str, Any]:
    """The orbit diagram of `pdw-sweep fixedpoint --sweep parameter=start:stop:points`: at each
    value the stride map iterated from the continued period-one gait, 300 strides dropped, 64
    recorded. Keys: parameter, values (N,), points (N, 64, d_s; NaN after a fall),
    section_names, period (N,; 0 = none detected), fall_stride (N,; -1 = none), fall (names or
    None), transient, record. Docs: docs/python.md."""

def basin_over(
    model: str = "simplest",
    over: Optional[str] = None,
    parameter: Optional[str] = None,
    start: Optional[float] = None,
    stop: Optional[float] = None,
    points: int = 6,
    slope: Optional[Union[float, str]] = None,
    grid: Tuple[int, int] = (41, 41),
    x: Optional[Tuple[str, float, float]] = None,
    y: Optional[Tuple[str, float, float]] = None,
    max_strides: int = 100,
    threads: int = 2,
    **params: float,
) -> dict[str, Any]:
    """Basin stability over a parameter, `pdw-sweep basin --over NAME=A:B:N` (over="NAME=A:B:N",
    or parameter, start, stop, points). Keys: parameter, values (N,), columns, kinds, fractions
    (N, C), outcome_columns, outcome_fractions (N, 10), attractors (per value), box,
    max_strides. Docs: docs/python.md."""

def follow(
    model: str = "simplest",
    kind: str = "pd",
    sweep: Optional[str] = None,
    free: Optional[str] = None,
    gait: str = "all",
    guess: Optional[Sequence[float]] = None,
    tol: float = 1e-12,
    map_grid: Optional[Tuple[int, int]] = None,
    threads: int = 2,
    slope: Optional[Union[float, str]] = None,
    **params: float,
) -> dict[str, Any]:
    """The curve of period doublings (kind="pd") or folds ("fold") of the period-one gait in
    two parameters, `pdw-sweep fixedpoint --follow KIND --sweep SWEEP --free FREE`
    (sweep="NAME=A:B:N", free="NAME" or "NAME=LO:HI"). Keys: kind, params, p_step, p_free,
    section, state, critical_multiplier, multipliers, period, residual, test_value,
    newton_iterations, complete, start, region_map (with map_grid=(nx, ny)). Docs:
    docs/python.md."""

def design(
    model: str = "compass",
    free: Optional[Union[dict[str, Tuple[float, float]], str, Sequence[str]]] = None,
    objective: str = "basin",
    budget: int = 60,
    seed: int = 0,
    init: int = 0,
    mu: float = 0.6,
    knee_margin: float = 0.1,
    min_margin: float = 0.0,
    basin_grid: int = 15,
    basin_box: Optional[Tuple[float, float]] = None,
    max_strides: int = 40,
    threads: int = 2,
    out: Optional[Union[str, "os.PathLike[str]"]] = None,
    png: Optional[Union[str, "os.PathLike[str]"]] = None,
    force: bool = False,
    slope: Optional[Union[float, str]] = None,
    starts: int = 1,
    **params: float,
) -> dict[str, Any]:
    """The design search of `pdw-sweep design` (free={name: (lo, hi)} or "NAME=LO:HI" texts;
    basin_box=None scales the box with each design's gait). out= writes the CLI's design file
    and its picture (png=, default beside it); an existing one of the same settings continues
    its search (force=True starts over). Keys: the report of `design --json` (designs, new,
    starts, counts, min_margin, best, out, png) and every design as arrays: free_names,
    objective, params (n, k), status, status_names, reasons, bindings, fates, section (n, 3),
    cost, basin_fraction, rho, min_normal_force, max_friction, min_knee_torque, period,
    step_length, min_relative_margin, basin_box_stance, basin_box_stance_rate, ….
    Docs: docs/python.md."""

def explore(
    path: Union[str, "os.PathLike[str]", List[Union[str, "os.PathLike[str]"]]],
    port: int = 0,
    save_dir: Union[str, "os.PathLike[str]"] = ".",
    threads: int = 2,
) -> str:
    """Serves the basin file(s) on 127.0.0.1 with the page of `pdw-sweep explore` (click a
    cell to watch it walk, drag a box to refine) on a background thread and returns the URL
    with the session token (every API request needs it); port=0 picks a free port. The server runs until the interpreter exits."""
    ...

def animate(
    model: str = "simplest",
    slope: Optional[Union[float, str]] = None,
    out: Union[str, "os.PathLike[str]"] = "gait.gif",
    force: bool = False,
    strides: int = 2,
    fps: Optional[float] = None,
    size: Tuple[int, int] = (640, 400),
    from_file: Optional[Union[str, "os.PathLike[str]"]] = None,
    steps: Optional[int] = None,
    **params: float,
) -> Any:
    """Writes the GIF of `pdw-sweep animate` (`strides` strides (`steps`: the old spelling) of the gait at `fps` frames per
    second, default 16.7, one GIF second per model time unit; or, with from_file, a trajectory
    file of `pdw-sweep simulate`, its model rebuilt from the file) to `out` (an existing file
    only with force=True) and returns its path."""

def lyapunov(
    model: str = "simplest",
    state: Optional[Sequence[float]] = None,
    strides: int = 100,
    slope: Optional[Union[float, str]] = None,
    **params: float,
) -> npt.NDArray[np.float64]:
    """Finite-time Lyapunov exponents of the stride map (per stride, descending) over `strides`
    strides from section state `state` (default: the stable gait, else the first found), by QR
    iteration of DP along the orbit."""

def mfpt_over(
    over: str,
    model: str = "simplest",
    slope: Optional[Union[float, str]] = None,
    sd: Optional[Union[float, str]] = None,
    walkers: int = 1000,
    max_strides: int = 1000,
    seed: int = 0,
    threads: int = 2,
    dist: str = "normal",
    max_steps: Optional[int] = None,
    **params: float,
) -> dict[str, Any]:
    """MFPT and gait sensitivity norm over a model parameter, as `pdw-sweep mfpt --over`
    (Monte Carlo; the same walkers and seed at every value): param, values, mean (slope at each
    value), mfpt, stderr, falls, gsn, stable (bool; False where the model has no stable gait,
    the numbers then NaN) as ndarrays, spearman (rank correlation of gsn and mfpt), sd, dist
    (the draws' distribution in words; `dist` as `mfpt`'s: normal, uniform, file:PATH)."""
    ...
