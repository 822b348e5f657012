"""pdw_sweep against independent references: Garcia et al. 1998, the CLI, one-at-a-time calls,
conservation laws."""

import json
import os
import shutil
import subprocess
import tempfile

import numpy as np
import pytest

import pdw_sweep as pdw

# Garcia, Chatterjee, Ruina & Coleman 1998, simplest walker at slope 0.009 (stable gait).
GARCIA_THETA = 0.20031090049483
GARCIA_THETADOT = -0.19983247291764


def cli():
    """The pdw-sweep binary of this tree, if built (CI builds it before running pytest)."""
    root = os.path.join(os.path.dirname(__file__), "..", "..")
    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(root, "target"))
    path = os.path.join(target, "release", "pdw-sweep")
    return path if os.path.exists(path) else shutil.which("pdw-sweep")


def test_models_lists_parameters_with_units_and_defaults():
    ms = {m["name"]: m for m in pdw.models()}
    assert {"simplest", "compass", "rimless"} <= set(ms)
    slope = [p for p in ms["simplest"]["parameters"] if p["name"] == "slope"][0]
    assert slope["unit"] == "rad" and slope["default"] == 0.009
    assert ms["simplest"]["section_names"] == ["theta", "thetadot"]


def test_garcia_fixed_point_at_slope_0_009():
    fps = pdw.fixed_point("simplest", slope=0.009, gait="stable")
    assert len(fps) == 1
    fp = fps[0]
    assert fp["stable"] and fp["gait"] == "stable"
    assert abs(fp["section"][0] - GARCIA_THETA) < 1e-9
    assert abs(fp["section"][1] - GARCIA_THETADOT) < 1e-9
    assert fp["residual"] <= 1e-12
    assert fp["multipliers"].dtype == np.complex128
    assert np.all(np.abs(fp["multipliers"]) < 1)


def test_fixed_point_keys_and_values_equal_the_cli_json():
    exe = cli()
    if exe is None:
        pytest.skip("pdw-sweep binary not built")
    out = subprocess.run([exe, "fixedpoint", "--model", "compass", "--json"],
                         check=True, capture_output=True, text=True).stdout
    ref = json.loads(out)["fixed_points"]
    got = pdw.fixed_point("compass")
    assert len(got) == len(ref)
    for g, r in zip(got, ref):
        assert set(g) == set(r)
        np.testing.assert_array_equal(g["section"], r["section"])
        np.testing.assert_array_equal(g["state"], r["state"])
        np.testing.assert_array_equal(g["multipliers"].real, [m["re"] for m in r["multipliers"]])
        assert g["period"] == r["period"] and g["validity"] == r["validity"]


def test_errors_raise_value_error_with_the_cli_message():
    with pytest.raises(ValueError, match="unknown model `walker9`"):
        pdw.fixed_point("walker9")
    with pytest.raises(ValueError, match="hip_mass"):
        pdw.fixed_point("compass", hip_mass=-1.0)
    with pytest.raises(ValueError, match="period: 0 must be between 1 and 64"):
        pdw.fixed_point(period=0)
    with pytest.raises(ValueError, match="no period-2 orbit found"):
        pdw.fixed_point(period=2, slope=0.009)
    with pytest.raises(ValueError, match="3 columns given"):
        pdw.stride_map("simplest", np.zeros((2, 3)))
    with pytest.raises(ValueError, match="no section coordinate 'psi'"):
        pdw.basin(grid=(3, 3), x=("psi", 0.0, 1.0))


def test_batched_stride_map_equals_one_at_a_time():
    rng = np.random.default_rng(7)
    states = np.column_stack([rng.uniform(0.15, 0.25, 37), rng.uniform(-0.25, -0.15, 37)])
    nxt, codes, times = pdw.stride_map("simplest", states, slope=0.009)
    assert nxt.shape == (37, 2) and codes.shape == (37,) and times.shape == (37,)
    for i in range(37):
        n1, c1, t1 = pdw.stride_map("simplest", states[i:i + 1], slope=0.009)
        assert c1[0] == codes[i] and t1[0] == times[i]
        np.testing.assert_array_equal(n1[0], nxt[i])
    legend = pdw.stride_outcomes("simplest")
    assert legend[0] == "ok" and set(codes) <= set(legend)
    # The Garcia gait maps onto itself.
    n, c, _ = pdw.stride_map("simplest", [[GARCIA_THETA, GARCIA_THETADOT]], slope=0.009)
    assert c[0] == 0 and np.max(np.abs(n[0] - [GARCIA_THETA, GARCIA_THETADOT])) < 1e-9


def test_basin_labels_equal_the_cli_for_a_small_grid():
    exe = cli()
    h5py = pytest.importorskip("h5py") if exe else None
    if exe is None:
        pytest.skip("pdw-sweep binary not built")
    outcome, legend, metrics = pdw.basin("simplest", slope=0.009, grid=(9, 7),
                                         x=("theta", 0.15, 0.25), y=("thetadot", -0.25, -0.15),
                                         max_strides=60)
    assert outcome.shape == (7, 9) and legend[0] == "gait"
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "b.h5")
        subprocess.run([exe, "basin", "--grid", "9x7", "--x", "theta=0.15:0.25",
                        "--y", "thetadot=-0.25:-0.15", "--max-strides", "60", "--out", path,
                        "--quiet"], check=True, capture_output=True)
        with h5py.File(path) as f:
            np.testing.assert_array_equal(f["basin/outcome"][()], outcome)
    assert abs(sum(metrics["fractions"].values()) - 1) < 1e-12


def test_continuation_finds_garcia_period_doubling():
    branches = pdw.continuation("simplest", "slope", 0.010, 0.019, points=40)
    main = branches[0]
    assert main["period_k"] == 1 and main["section"].shape[1] == 2
    pd = [b for b in main["bifurcations"] if b["kind"] == "period_doubling"]
    # Garcia et al. 1998: the stable gait period-doubles near slope 0.0151 (0.0150884379 by
    # bisection on directly computed multipliers, crates/pdw-sweep/tests/cli.rs).
    assert pd and abs(pd[0]["parameter"] - 0.015088437941) < 1e-7
    assert abs(pd[0]["multipliers"][0] + 1) < 1e-6


def test_simulate_conserves_energy_between_impacts_and_repeats_the_gait():
    tr = pdw.simulate("simplest", slope=0.009, steps=4)
    assert tr["outcome"] == "ok" and tr["steps_done"] == 4
    assert tr["x"].shape == (tr["t"].size, 4) and tr["units"]["t"] == "sqrt(l/g)"
    e, step = tr["energy"], tr["step"]
    for k in range(4):
        ek = e[step == k]
        assert ek.max() - ek.min() < 1e-9
    # Closed-form energy of the simplest walker per unit hip mass.
    th, thd = tr["x"][:, 0], tr["x"][:, 1]
    np.testing.assert_allclose(e, 0.5 * thd**2 + np.cos(th - 0.009), rtol=0, atol=1e-15)
    np.testing.assert_allclose(tr["section"], [[GARCIA_THETA, GARCIA_THETADOT]] * 4, atol=1e-8)
    assert list(tr["events"]["kind"]) == ["heel_strike"] * 4
    grid = pdw.simulate("simplest", steps=1, dt_out=0.5)
    np.testing.assert_array_equal(grid["t"], 0.5 * np.arange(grid["t"].size))


def test_simulate_a_fall_is_an_outcome():
    tr = pdw.simulate("simplest", state=[0.3, -0.1], steps=3)
    assert tr["steps_done"] == 0 and tr["outcome"] == "fell backward"
    with pytest.raises(ValueError, match="3 values given"):
        pdw.simulate("simplest", state=[0.1, 0.2, 0.3])


def test_period_two_orbit_matches_the_cli():
    # Garcia et al. 1998: past the first period doubling (0.0151) the walker settles on a
    # period-2 gait; both of its points, and the 2-step multipliers, as `fixedpoint --period 2`.
    exe = cli()
    if exe is None:
        pytest.skip("pdw-sweep binary not built")
    ref = json.loads(
        subprocess.run(
            [exe, "fixedpoint", "--slope", "0.016", "--period", "2", "--gait", "stable", "--json"],
            check=True,
            capture_output=True,
        ).stdout
    )["fixed_points"]
    got = pdw.fixed_point(slope=0.016, period=2, gait="stable")
    assert len(got) == len(ref) == 1
    g, r = got[0], ref[0]
    assert set(g) == set(r)
    assert g["period_k"] == 2 and g["orbit"].shape == (2, 2)
    np.testing.assert_array_equal(g["orbit"], np.array(r["orbit"]))
    assert np.all(np.abs(g["multipliers"]) < 1.0)
