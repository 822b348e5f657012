"""pdw_sweep against independent references: Garcia et al. 1998, the CLI, one-at-a-time calls,
conservation laws."""

import json
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

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


def test_gaits_without_a_guess_equal_the_cli_search():
    """Both of Garcia's gaits at 0.009 (REFERENCES section 1) from a scan, with the CLI's counts."""
    got = pdw.gaits("simplest", slope=0.009)
    assert got["starts"] == 256 and len(got["gaits"]) == 2 and got["orbits"] == []
    stable = [g for g in got["gaits"] if g["stable"]][0]
    assert abs(stable["section"][0] - 0.20031090049483) < 1e-9
    assert stable["starts_settled"] > 0 and stable["starts_newton"] > 0
    settled = sum(g["starts_settled"] for g in got["gaits"])
    assert settled + got["fell"] + got["unsettled"] == 256
    assert set(got["box"]) == {"theta", "thetadot"}
    with pytest.raises(ValueError, match="no section coordinate 'phi'"):
        pdw.gaits("simplest", search_box={"phi": (0.0, 1.0)})
    exe = cli()
    if exe is None:
        pytest.skip("pdw-sweep binary not built")
    out = subprocess.run([exe, "fixedpoint", "--slope", "0.009", "--search", "--json"],
                         check=True, capture_output=True, text=True).stdout
    ref = json.loads(out)
    assert ref["scan"]["fell"] == got["fell"] and ref["scan"]["unsettled"] == got["unsettled"]
    for g, r in zip(got["gaits"], ref["fixed_points"]):
        np.testing.assert_array_equal(g["section"], r["section"])
        assert (g["starts_newton"], g["starts_settled"]) == (r["starts_newton"], r["starts_settled"])


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
    assert legend[13] == "heel_strike" and set(codes) <= set(legend)
    # The Garcia gait maps onto itself.
    n, c, _ = pdw.stride_map("simplest", [[GARCIA_THETA, GARCIA_THETADOT]], slope=0.009)
    assert c[0] == 13 and np.max(np.abs(n[0] - [GARCIA_THETA, GARCIA_THETADOT])) < 1e-9


def test_stride_map_speaks_the_basin_files_codes():
    """One table of ends: `stride_outcomes` names every code as a basin's legend does, a
    complete stride is 13 `heel_strike` (a stride's end only, never a cell's), a cell whose
    first stride falls has the code `stride_map` gives that stride, and a stride time budget
    too short for any stride is 5 `fall_no_heel_strike` in both (not the basin's 7 `timeout`)."""
    legend = pdw.stride_outcomes("simplest")
    # the simplest walker falls backward or forward (its terminal guards)
    assert legend == {2: "fall_forward", 3: "fall_backward", 5: "fall_no_heel_strike",
                      8: "nonfinite", 9: "integrator_failure", 13: "heel_strike"}
    # the basin's own grid values (a + (b - a) i / (n - 1), the last exactly b)
    xs = [0.02 + (0.6 - 0.02) * i / 8 for i in range(8)] + [0.6]
    ys = [-0.9 + (0.3 + 0.9) * i / 6 for i in range(6)] + [0.3]
    outcome, basin_legend, _ = pdw.basin("simplest", slope=0.009, grid=(9, 7),
                                         x=("theta", 0.02, 0.6), y=("thetadot", -0.9, 0.3),
                                         max_strides=20)
    for c, name in basin_legend.items():
        if c in legend:
            assert legend[c] == name
    assert 13 not in basin_legend and 13 not in outcome
    states = np.array([[x, y] for y in ys for x in xs])
    _, codes, _ = pdw.stride_map("simplest", states, slope=0.009)
    first = codes != 13
    assert np.any(np.isin(codes, [2, 3])), codes
    np.testing.assert_array_equal(outcome.ravel()[first], codes[first])
    _, codes, _ = pdw.stride_map("simplest", [[0.2, -0.2]], slope=0.009, max_stride_time=0.3)
    assert codes[0] == 5
    outcome, basin_legend, _ = pdw.basin("simplest", slope=0.009, grid=(3, 3),
                                         x=("theta", 0.19, 0.21), y=("thetadot", -0.21, -0.19),
                                         max_stride_time=0.3)
    assert np.all(outcome == 5) and basin_legend[5] == "fall_no_heel_strike"


def test_old_keyword_spellings_still_work():
    """`max_strides` (mfpt, mfpt_over) and `strides` (animate) count strides; the old keywords
    `max_steps` and `steps` still work, and both spellings with different values are refused."""
    kw = dict(sd="0.1deg", walkers=4, seed=1, slope=0.009)
    new, old = pdw.mfpt(max_strides=7, **kw), pdw.mfpt(max_steps=7, **kw)
    assert new["total_steps"] == old["total_steps"] and len(new["survival"]) <= 8
    with pytest.raises(ValueError, match="max_steps is the old spelling of max_strides"):
        pdw.mfpt(max_strides=7, max_steps=8, **kw)
    with tempfile.TemporaryDirectory() as d:
        a = pdw.animate("compass", out=os.path.join(d, "a.gif"), strides=1, size=(320, 240))
        b = pdw.animate("compass", out=os.path.join(d, "b.gif"), steps=1, size=(320, 240))
        assert open(a, "rb").read() == open(b, "rb").read()
        with pytest.raises(ValueError, match="steps is the old spelling of strides"):
            pdw.animate("compass", out=os.path.join(d, "c.gif"), strides=1, steps=3)


def cli_basin(exe, h5py, args):
    """Labels, legend and attractors of a `pdw-sweep basin` run (the reference)."""
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "b.h5")
        subprocess.run([exe, "basin", *args, "--out", path, "--quiet"], check=True,
                       capture_output=True)
        with h5py.File(path) as f:
            outcome = f["basin/outcome"][()]
            legend = {int(k): v for k, v in json.loads(f["basin/outcome"].attrs["legend"]).items()}
            atts = {}
            for name, g in f["attractors"].items():
                atts[name] = {
                    "period_k": int(g.attrs["period_k"]),
                    "section": g["section"][()],
                    "multipliers": g["multipliers_re"][()] + 1j * g["multipliers_im"][()],
                    "validity": g.attrs["validity"],
                }
    return outcome, legend, atts


@pytest.mark.parametrize("slope", [0.009, 0.016])
def test_basin_labels_and_attractors_equal_the_cli_for_a_small_grid(slope):
    # At 0.009 one stable period-one gait (code 0, "gait"); at 0.016, past the first period
    # doubling, no stable period-one gait: the cells reach the period-2 gait (Garcia et al. 1998).
    exe = cli()
    if exe is None:
        pytest.skip("pdw-sweep binary not built")
    h5py = pytest.importorskip("h5py")
    outcome, legend, metrics = pdw.basin("simplest", slope=slope, grid=(9, 7),
                                         x=("theta", 0.18, 0.30), y=("thetadot", -0.30, -0.18),
                                         max_strides=100)
    ref_outcome, ref_legend, ref_atts = cli_basin(
        exe, h5py, ["--slope", str(slope), "--grid", "9x7", "--x", "theta=0.18:0.30",
                    "--y", "thetadot=-0.30:-0.18", "--max-strides", "100"])
    assert outcome.shape == (7, 9)
    np.testing.assert_array_equal(outcome, ref_outcome)
    # the file's legend lists every fixed code; Python's only the codes the outcome can hold:
    # code 0 (`gait`) only with a stable period-one gait
    no_gait = metrics["gait"] is None
    assert no_gait == (slope == 0.016)
    assert {int(k): v for k, v in legend.items() if k != 255} == \
        {k: v for k, v in ref_legend.items() if k != 255 and not (k == 0 and no_gait)}
    got = {a["name"]: a for a in metrics["attractors"]}
    assert set(got) == set(ref_atts)
    for name, a in got.items():
        r = ref_atts[name]
        assert a["period_k"] == r["period_k"] and legend[a["code"]] == name
        np.testing.assert_array_equal(a["points"], r["section"])
        np.testing.assert_array_equal(a["multipliers"], r["multipliers"])
        word = {True: "valid", False: "invalid", None: "not checked"}[a["valid"]]
        assert word == r["validity"]
    assert abs(sum(metrics["fractions"].values()) - 1) < 1e-12
    if slope == 0.009:
        assert legend[0] == "gait" and "gait" in got and metrics["gait"] is not None
    else:
        assert metrics["gait"] is None and "period-2" in got
        code = got["period-2"]["code"]
        assert np.any(outcome == code) and metrics["fractions"]["period-2"] > 0
        # The attractor is the stable period-2 orbit of `fixed_point(period=2)`.
        ref = pdw.fixed_point(slope=slope, period=2, gait="stable")[0]
        np.testing.assert_allclose(got["period-2"]["points"], ref["orbit"], atol=1e-8)


def test_basin_default_grid_without_a_stable_period_one_gait():
    exe = cli()
    if exe is None:
        pytest.skip("pdw-sweep binary not built")
    h5py = pytest.importorskip("h5py")
    outcome, legend, metrics = pdw.basin("simplest", slope=0.016, grid=(5, 4), max_strides=40)
    ref_outcome, ref_legend, _ = cli_basin(
        exe, h5py, ["--slope", "0.016", "--grid", "5x4", "--max-strides", "40"])
    np.testing.assert_array_equal(outcome, ref_outcome)
    assert "period-2" in legend.values()


def test_3d_basin_equals_the_cli_file_and_refuses_bad_grids():
    # A 3-D grid over the compass walker's three section coordinates: the (nz, ny, nx) array
    # equals the CLI file's /basin/outcome, cell for cell, with the same legend and z axis.
    exe = cli()
    if exe is None:
        pytest.skip("pdw-sweep binary not built")
    h5py = pytest.importorskip("h5py")
    axes = dict(x=("stance", 0.2, 0.34), y=("stance_rate", -1.37, -0.82),
                z=("hip_rate", 0.4, 1.0))
    outcome, legend, metrics = pdw.basin("compass", grid=(6, 5, 4), max_strides=60, **axes)
    ref_outcome, ref_legend, ref_atts = cli_basin(
        exe, h5py, ["--model", "compass", "--grid", "6x5x4", "--x", "stance=0.2:0.34",
                    "--y", "stance_rate=-1.37:-0.82", "--z", "hip_rate=0.4:1.0",
                    "--max-strides", "60"])
    assert outcome.shape == (4, 5, 6) and ref_outcome.shape == (4, 5, 6)
    np.testing.assert_array_equal(outcome, ref_outcome)
    assert {int(k): v for k, v in legend.items() if k != 255} == \
        {k: v for k, v in ref_legend.items() if k != 255}
    assert {a["name"] for a in metrics["attractors"]} == set(ref_atts)
    assert metrics["z_name"] == "hip_rate"
    np.testing.assert_allclose(metrics["z"], [0.4, 0.6, 0.8, 1.0], rtol=0, atol=1e-15)
    # the fractions count every cell of the 3-D grid
    for name, f in metrics["fractions"].items():
        code = [c for c, n in legend.items() if n == name][0]
        assert f == np.count_nonzero(outcome == code) / outcome.size
    with pytest.raises(ValueError, match="three sizes, but no z axis"):
        pdw.basin("compass", grid=(5, 5, 3))
    with pytest.raises(ValueError, match="z needs a 3-D grid"):
        pdw.basin("compass", grid=(5, 5), z=("hip_rate", 0.4, 1.0))
    with pytest.raises(ValueError, match="already the x axis"):
        pdw.basin("compass", grid=(5, 5, 3), x=("stance", 0.2, 0.3), z=("stance", 0.1, 0.2))
    with pytest.raises(ValueError, match="needs about .* of memory"):
        pdw.basin("compass", grid=(1000, 1000, 1000), z=("hip_rate", 0.4, 1.0))


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
    tr = pdw.simulate("simplest", slope=0.009, strides=4)
    assert tr["outcome"] == "ok" and tr["strides_done"] == 4 and not tr["fell"]
    assert tr["samples"] == tr["t"].size and tr["event_count"] == tr["events"]["t"].size == 4
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
    grid = pdw.simulate("simplest", strides=1, dt_out=0.5)
    np.testing.assert_array_equal(grid["t"], 0.5 * np.arange(grid["t"].size))


def test_simulate_a_fall_is_an_outcome():
    tr = pdw.simulate("simplest", state=[0.3, -0.1], strides=3)
    assert tr["strides_done"] == 0 and tr["outcome"] == "fell backward" and tr["fell"]
    # the old spellings: steps= for strides=, steps_done for strides_done
    old = pdw.simulate("simplest", state=[0.3, -0.1], steps=3)
    assert old["steps_done"] == 0 and old["strides"] == 3
    with pytest.raises(ValueError, match="3 values given"):
        pdw.simulate("simplest", state=[0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match="give state or gait"):
        pdw.simulate("simplest", state=[0.3, -0.1], gait="stable")


def test_simulate_writes_the_cli_file(tmp_path):
    h5py = pytest.importorskip("h5py")
    out = tmp_path / "walk.h5"
    tr = pdw.simulate("simplest", strides=2, out=str(out))
    assert tr["out"] == str(out)
    with h5py.File(out, "r") as f:
        np.testing.assert_array_equal(f["t"][:], tr["t"])
        assert f.attrs["steps_done"] == "2"
    with pytest.raises(ValueError, match="exists; pass force=True"):
        pdw.simulate("simplest", strides=2, out=str(out))
    assert pdw.simulate("simplest", strides=2, out=str(out), force=True)["strides_done"] == 2


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


def test_continuation_gives_n_grid_points_per_branch_with_whole_orbits():
    n = 10
    branches = pdw.continuation("simplest", "slope", 0.010, 0.019, points=n)
    grid = np.linspace(0.010, 0.019, n)
    main = branches[0]
    assert main["name"] == "period-1" and main["period_k"] == 1
    # The period-1 gait exists over the whole range (unstable past the doubling): all N values.
    np.testing.assert_allclose(main["parameter"], grid, rtol=0, atol=1e-15)
    assert main["orbit"].shape == (n, 1, 2) and main["multipliers"].dtype == np.complex128
    assert main["step_length"].shape == (n, 1) and main["valid"].shape == (n, 1)
    # Each point is the fixed point at its grid value.
    fp = pdw.fixed_point(slope=main["parameter"][0], gait="stable")[0]
    np.testing.assert_allclose(main["section"][0], fp["section"], atol=1e-8)
    np.testing.assert_allclose(main["multipliers"][0], fp["multipliers"], atol=1e-6)
    np.testing.assert_allclose(main["speed"][0], fp["speed"], rtol=1e-8)
    # The period-2 branch holds the grid values past the doubling (0.0151), both orbit points.
    two = [b for b in branches if b["period_k"] == 2]
    assert len(two) == 1
    two = two[0]
    assert two["name"] == "period-2" and two["orbit"].shape[1:] == (2, 2)
    np.testing.assert_allclose(two["parameter"], grid[grid > 0.0151], rtol=0, atol=1e-15)
    i = int(np.argmin(np.abs(two["parameter"] - 0.016)))
    ref = pdw.fixed_point(slope=two["parameter"][i], period=2, gait="stable")[0]
    # The same orbit: the branch lists its points in stride order from wherever it starts.
    orbit = two["orbit"][i]
    shift = int(np.argmin(np.abs(orbit - ref["orbit"][0]).max(axis=1)))
    np.testing.assert_allclose(np.roll(orbit, -shift, axis=0), ref["orbit"], atol=1e-8)
    np.testing.assert_allclose(two["period"][i], ref["period"], rtol=1e-8)
    np.testing.assert_allclose(np.abs(two["multipliers"][i]), np.abs(ref["multipliers"]),
                               atol=1e-6)
    assert two["stable"][i]


def test_continuation_equals_the_cli_sweep_json():
    exe = cli()
    if exe is None:
        pytest.skip("pdw-sweep binary not built")
    branches = pdw.continuation("simplest", "slope", 0.010, 0.019, points=8)
    with tempfile.TemporaryDirectory() as d:
        out = subprocess.run([exe, "fixedpoint", "--sweep", "slope=0.010:0.019:8", "--json",
                              "--quiet", "--out", os.path.join(d, "s.h5")],
                             check=True, capture_output=True, text=True).stdout
    ref = json.loads(out)
    assert [b["name"] for b in branches] == [b["name"] for b in ref["branches"]]
    for b, r in zip(branches, ref["branches"]):
        pts = r["points"]
        assert b["period_k"] == r["period_k"] and len(b["parameter"]) == len(pts)
        np.testing.assert_array_equal(b["parameter"], [p["param"] for p in pts])
        np.testing.assert_array_equal(b["orbit"], [p["orbit"] for p in pts])
        np.testing.assert_array_equal(b["period"], [p["period"] for p in pts])
        np.testing.assert_array_equal(b["step_length"], [p["step_length"] for p in pts])
        np.testing.assert_array_equal(b["speed"], [p["speed"] for p in pts])
        np.testing.assert_array_equal(b["stable"], [p["stable"] for p in pts])
        np.testing.assert_array_equal(
            b["multipliers"], [[m["re"] + 1j * m["im"] for m in p["multipliers"]] for p in pts])
        bifs = [x for x in ref["bifurcations"] if x["branch"] == r["id"]]
        assert [x["parameter"] for x in b["bifurcations"]] == [x["parameter"] for x in bifs]


def test_validity_is_located_on_the_dense_solution_with_relative_margins():
    """The simplest walker at 0.009: valid under its mid-stance convention (Garcia et al. 1998)
    with the scuff's depth reported; every relative margin is raw / scale (its own units: 1) and
    the binding criterion is the smallest; the heel strike's impulses push."""
    g = pdw.fixed_point("simplest", slope=0.009, gait="stable")[0]
    v = g["validity"]
    assert v["valid"] and v["continuous"] and v["fell"] is None
    assert v["clearance_rule"] == "after_mid_stance" and not v["swing_foot_scuffs"]
    assert abs(v["scuff_depth"] - 6.384e-5) < 1e-8
    rel = {m["name"]: m["relative"] for m in v["margins"]}
    for m in v["margins"]:
        assert m["relative"] == m["raw"] / m["scale"] and m["scale"] == 1.0
    assert v["binding"] == min(rel, key=rel.get)
    assert v["min_relative_margin"] == min(rel.values())
    imp = v["impacts"][0]
    assert imp["event"] == "heel_strike" and imp["checked"] and imp["min_margin"] > 0
    assert not v["impact_violation"] and v["violations"] == []


def test_a_basin_grid_that_does_not_fit_in_memory_is_refused_before_computing():
    with pytest.raises(ValueError, match="needs about .* of memory"):
        pdw.basin(grid=(30000, 30000))


def test_mfpt_walkers_that_do_not_fit_in_memory_are_refused_before_walking():
    # the same estimate as `pdw-sweep mfpt --walkers`: refused at once, not after an abort
    with pytest.raises(ValueError, match="walkers 1000000000000: needs about .* of memory"):
        pdw.mfpt(model="rimless", sd=0.01, walkers=10**12)
    with pytest.raises(ValueError, match="needs about .* of memory"):
        pdw.mfpt(model="rimless", sd="0.01:0.02:2", walkers=10**12)
    with pytest.raises(ValueError, match="mesh 100000 .*needs about .* of memory"):
        pdw.mfpt(model="compass", sd=0.001, walkers=10, chain=True, mesh=100000)


INTERRUPT_SCRIPT = r"""
import os, signal, sys, threading, time
import pdw_sweep as pdw

which = sys.argv[1]
def long_call():
    if which == "basin":
        # ~160 000 cells of the kneed walker: about two minutes on two threads.
        return pdw.basin(model="kneed", grid=(400, 400))
    # Garcia's cascade over a slope range long enough to take minutes.
    return pdw.continuation(model="simplest", parameter="slope", start=0.0005, stop=0.019, points=4000)

threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
t0 = time.monotonic()
try:
    long_call()
    print("FINISHED", time.monotonic() - t0)
except KeyboardInterrupt:
    print("INTERRUPTED", time.monotonic() - t0)
# The next calls work and return arrays (numpy's API was imported with the module).
nxt, codes, _ = pdw.stride_map("simplest", [[0.2003109, -0.1998325]], slope=0.009)
fp = pdw.fixed_point(slope=0.009, gait="stable")[0]
print("AFTER", int(codes[0]), float(fp["section"][0]))
"""


@pytest.mark.parametrize("which", ["basin", "continuation"])
def test_ctrl_c_raises_keyboard_interrupt_at_once_and_the_next_call_works(which):
    """Ctrl-C (SIGINT) during a long call raises KeyboardInterrupt within a second, not when the
    call would have ended; the process goes on and the next calls return arrays (no panic)."""
    r = subprocess.run([os.sys.executable, "-c", INTERRUPT_SCRIPT, which],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.split("\n")
    first = lines[0].split()
    assert first[0] == "INTERRUPTED", r.stdout
    # The signal comes at 0.5 s; the uninterrupted call takes minutes.
    assert float(first[1]) < 10.0, r.stdout
    after = lines[1].split()
    assert after[0] == "AFTER" and after[1] == "13", r.stdout
    assert abs(float(after[2]) - GARCIA_THETA) < 1e-9, r.stdout


def test_slope_as_a_string_with_a_unit_equals_the_number():
    """slope="3deg", "3°", " 3 deg" are the CLI's --slope forms: 3π/180 rounded once, the compass
    preset's 0.05235987755982988; "0.05" and 0.05 are radians."""
    three_deg = 0.05235987755982988
    ref = pdw.fixed_point("compass", slope=three_deg, gait="stable")[0]
    for form in ["3deg", "3°", " 3 deg"]:
        fp = pdw.fixed_point("compass", slope=form, gait="stable")[0]
        assert np.array_equal(fp["section"], ref["section"]), form
    a = pdw.fixed_point("simplest", slope="0.009", gait="stable")[0]
    b = pdw.fixed_point("simplest", slope=0.009, gait="stable")[0]
    assert np.array_equal(a["section"], b["section"])
    with pytest.raises(ValueError, match="furlong"):
        pdw.fixed_point("simplest", slope="3 furlong")
    with pytest.raises(TypeError, match="neither a number"):
        pdw.fixed_point("simplest", slope=[3])


def test_a_steep_slope_warns_naming_its_degrees():
    """slope=1 (meant as 1°) is 57°: a UserWarning through warnings.warn, once per call."""
    with pytest.warns(UserWarning, match=r"slope 1(\.0)? rad = 57\.3° .*did you mean") as rec:
        nxt, outcome, _ = pdw.stride_map("compass", np.array([[0.27, -1.09, 0.72]]), slope=1.0)
    assert len([w for w in rec if "far steeper" in str(w.message)]) == 1
    assert len(outcome) == 1
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pdw.fixed_point("simplest", slope="0.5deg", gait="stable")


def test_basin_attractors_say_what_makes_them_physically_invalid():
    # The kneed preset at slope 0.051 walks only if its stance-knee lock pulls (the knee torque
    # of `simulate` goes negative along the stride); the compass gait needs nothing of the kind.
    _, _, kneed = pdw.basin("kneed", slope=0.051, grid=(7, 7))
    gait = {a["name"]: a for a in kneed["attractors"]}["gait"]
    assert gait["valid"] is False and "a knee lock must pull" in gait["invalid"]
    tr = pdw.simulate("kneed", slope=0.051, steps=1, dt_out=0.002)
    assert np.nanmin(tr["knee_torque"]) < 0
    _, _, compass = pdw.basin("compass", slope="3deg", grid=(7, 7))
    gait = {a["name"]: a for a in compass["attractors"]}["gait"]
    assert gait["valid"] is True and gait["invalid"] == []


def test_continuation_follows_the_cascade_and_starts_anywhere():
    # max_period=4: period-1, period-2 and period-4 branches, each period-4 point a fixed point
    # of the four-stride orbit found directly (Newton on P^4, fixed_point(period=4)).
    grid = np.linspace(0.014, 0.0185, 6)
    deep = pdw.continuation("simplest", "slope", 0.014, 0.0185, points=6, max_period=4)
    assert [b["name"] for b in deep] == ["period-1", "period-2", "period-4"]
    four = deep[2]
    assert four["period_k"] == 4 and four["orbit"].shape[1:] == (4, 2)
    i = int(np.argmax(four["parameter"]))
    ref = pdw.fixed_point(slope=four["parameter"][i], period=4, guess=four["section"][i])[0]
    assert min(np.abs(ref["orbit"] - four["section"][i]).max(axis=1)) < 1e-8
    # Started in the middle, the same points as started at the first value.
    mid = pdw.continuation(
        "simplest", "slope", 0.014, 0.0185, points=6, max_period=4, start_at=grid[3]
    )
    assert [b["name"] for b in mid] == ["period-1", "period-2", "period-4"]
    for a, b in zip(deep, mid):
        np.testing.assert_array_equal(a["parameter"], b["parameter"])
        np.testing.assert_allclose(a["section"], b["section"], rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="max_period: 3 is not a power of two"):
        pdw.continuation("simplest", "slope", 0.014, 0.0185, points=6, max_period=3)
    with pytest.raises(ValueError, match="start_at: 0.5 is outside the swept range"):
        pdw.continuation("simplest", "slope", 0.014, 0.0185, points=6, start_at=0.5)


def test_simulate_is_dense_by_default_and_steps_keeps_the_old_series():
    tr = pdw.simulate("simplest", slope=0.009, steps=3)
    ev = tr["events"]["t"]
    period = ev[2] - ev[1]
    assert abs(tr["dt_out"] - period / 100) < 1e-9 * period
    assert "period" in tr["dt_out_source"]
    for k in range(3):
        grid = [t for t, s in zip(tr["t"], tr["step"]) if s == k and t not in ev]
        assert 98 <= len(grid) <= 102
    for te in ev:
        assert np.count_nonzero(tr["t"] == te) == 2
    old = pdw.simulate("simplest", slope=0.009, steps=3, dt_out="steps")
    assert old["dt_out"] is None and old["t"].size < tr["t"].size
    for bad in ["fast", 0.0, -1.0, [0.1]]:
        with pytest.raises(ValueError, match="dt_out"):
            pdw.simulate("simplest", steps=1, dt_out=bad)


def test_simulate_positions_follow_the_simplest_walkers_geometry():
    # Garcia et al. 1998 (the model's docs): hip (-sin θ, cos θ) from the stance foot; each
    # step's stance foot 2|sin θ⁻| further down the slope than the last.
    tr = pdw.simulate("simplest", slope=0.009, steps=3)
    assert tr["point_names"] == ["stance_foot", "hip", "swing_foot"]
    pos, th = tr["positions"], tr["x"][:, 0]
    assert pos.shape == (tr["t"].size, 3, 2) and tr["com"].shape == (tr["t"].size, 2)
    feet = np.concatenate([[0.0], np.cumsum(2 * np.abs(np.sin(tr["events"]["pre"][:, 0])))])
    foot = feet[tr["step"]]
    np.testing.assert_allclose(pos[:, 1, 0], foot - np.sin(th), rtol=0, atol=1e-12)
    np.testing.assert_allclose(pos[:, 1, 1], np.cos(th), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(tr["com"], pos[:, 1, :])
    # at each heel strike the swing foot is on the slope, where the next stance foot stands
    for te in tr["events"]["t"]:
        i = int(np.flatnonzero(tr["t"] == te)[0])
        assert abs(pos[i, 2, 1]) < 1e-9 and abs(pos[i, 2, 0] - pos[i + 1, 0, 0]) < 1e-9


def test_basin_and_continuation_name_the_coordinates():
    _, _, metrics = pdw.basin("compass", slope="3deg", grid=(4, 4))
    assert "slope normal" in metrics["coordinates"]["stance"]
    branches = pdw.continuation("simplest", "slope", 0.009, 0.01, points=2)
    assert "stance-leg angle" in branches[0]["coordinates"]["theta"]


def test_mfpt_survival_estimator_and_thread_count():
    r = pdw.mfpt("rimless", sd="0.5deg", walkers=300, max_strides=5000, seed=1)
    surv = r["survival"]
    # survival starts at 1, never rises; steps / falls is the estimate
    assert surv[0] == 1.0 and np.all(np.diff(surv) <= 0)
    assert r["falls"] + r["censored"] == 300
    assert r["mfpt"] == r["total_steps"] / r["falls"]
    assert abs(r["restricted_mean"] - surv[1:].sum()) < 1e-9
    assert sum(r["failures"].values()) == r["falls"]
    # the same walkers on one thread (sd as radians: the same number as '0.5deg')
    r1 = pdw.mfpt("rimless", sd=0.5 * np.pi / 180, walkers=300, max_strides=5000, seed=1, threads=1)
    assert r1["total_steps"] == r["total_steps"]
    with pytest.raises(ValueError, match="sd"):
        pdw.mfpt("rimless", sd="-1deg")


def test_mfpt_curve_is_the_single_runs_at_each_sd():
    c = pdw.mfpt("rimless", sd="0.4deg:0.6deg:3", walkers=150, max_strides=5000, seed=4)
    assert c["sd"].shape == (3,)
    assert abs(c["sd"][0] - np.deg2rad(0.4)) < 1e-15 and abs(c["sd"][2] - np.deg2rad(0.6)) < 1e-15
    for i, sd in enumerate(c["sd"]):
        r = pdw.mfpt("rimless", sd=float(sd), walkers=150, max_strides=5000, seed=4)
        assert r["total_steps"] == c["total_steps"][i] and r["falls"] == c["falls"][i]
        assert r["mfpt"] == c["mfpt"][i]
    assert c["mfpt"][0] > c["mfpt"][1] > c["mfpt"][2]
    with pytest.raises(ValueError, match="below the last"):
        pdw.mfpt("rimless", sd="1deg:0.5deg:3")


def test_mfpt_on_step_heights():
    # stairs without spread: the wheel rolls down its own stairs gait and never falls
    r0 = pdw.mfpt("rimless", terrain="step-down", sd=0.0, step_down=0.01, walkers=20, max_strides=200)
    assert r0["terrain"] == "step-down" and r0["mean"] == 0.01
    assert r0["falls"] == 0 and r0["censored"] == 20
    r = pdw.mfpt("rimless", terrain="step-down", sd=0.01, walkers=300, max_strides=5000, seed=2)
    assert r["falls"] + r["censored"] == 300 and r["falls"] > 0
    assert r["mfpt"] == r["total_steps"] / r["falls"]
    # a wider spread loses walkers sooner (the same draws, scaled)
    r2 = pdw.mfpt("rimless", terrain="step-down", sd=0.02, walkers=300, max_strides=5000, seed=2)
    assert r2["mfpt"] < r["mfpt"]
    with pytest.raises(ValueError, match="not a height"):
        pdw.mfpt("rimless", terrain="step-down", sd="1deg")
    # the chain's rule with a node at a step height of exactly 0 (odd, mean 0) is warned of
    kw = dict(terrain="step-down", sd=0.01, walkers=50, max_strides=500, seed=2, chain=True, mesh=20)
    odd = pdw.mfpt("rimless", nodes=5, **kw)["chain"]["node_warning"]
    assert odd.startswith("WARNING") and "nodes 5" in odd
    assert pdw.mfpt("rimless", nodes=6, **kw)["chain"]["node_warning"] is None
    # the compass walks on step heights; draws beyond its 1 m legs are refused
    rc = pdw.mfpt("compass", terrain="step-down", sd=0.002, walkers=20, max_strides=30)
    assert rc["falls"] + rc["censored"] == 20
    with pytest.raises(ValueError, match="step_down"):
        pdw.mfpt("compass", terrain="step-down", sd=0.2)


def test_round_feet_walk_on_step_heights_and_on_slopes(tmp_path):
    # the compass preset (models/compass.toml) with arc feet of a tenth of its leg
    spec = tmp_path / "round.toml"
    text = (Path(__file__).resolve().parents[2] / "models" / "compass.toml").read_text()
    spec.write_text(text.replace("[parameters]", "foot_radius = 0.1\n\n[parameters]", 1))
    r = pdw.mfpt(str(spec), terrain="step-down", sd=0.004, walkers=300, max_strides=2000, seed=3)
    assert r["falls"] + r["censored"] == 300 and r["falls"] > 150
    assert r["mfpt"] == r["total_steps"] / r["falls"]
    # random slopes: the Monte Carlo walk on tilted landing lines; no Markov chain
    r = pdw.mfpt(str(spec), sd="0.5deg", walkers=100, max_strides=2000, seed=1)
    assert r["falls"] + r["censored"] == 100 and r["falls"] > 50
    with pytest.raises(ValueError, match="foot_radius"):
        pdw.mfpt(str(spec), sd="0.2deg", walkers=2, chain=True)


def test_mfpt_chain_agrees_with_the_monte_carlo_and_reports_its_meshes():
    r = pdw.mfpt("rimless", sd="0.5deg", walkers=2000, max_strides=10000, seed=1, chain=True, mesh=100)
    c = r["chain"]
    assert r["censored"] == 0 and r["dist"] == "normal"
    assert list(c["mesh"]) == [100, 200] and c["nodes"] == 11 and c["quadrature"] == "Gauss-Hermite"
    # the second method: the fine mesh's chain within 3 Monte Carlo standard errors plus the
    # mesh change
    tol = 3 * r["restricted_stderr"] + abs(c["mfpt"][1] - c["mfpt"][0])
    assert abs(c["mfpt"][1] - r["restricted_mean"]) < tol
    # the eigenvalue check: 1/(1 - lambda) - 1 is the quasi-stationary MFPT of the solve
    assert np.allclose(c["mfpt_lambda"], 1 / (1 - c["lambda"]) - 1, rtol=1e-9)
    assert np.allclose(c["mfpt_lambda"], c["mfpt_quasi_stationary"], rtol=1e-6)
    change = abs(c["mfpt"][1] - c["mfpt"][0]) / max(c["mfpt"])
    assert abs(c["refinement_change"] - change) < 1e-12
    assert (c["warning"] is None) == (change <= 0.1)
    assert c["agreement"] is None and c["node_warning"] is None
    # the quadrature check: the coarse mesh with twice the nodes, its warning by the 0.5 % rule
    assert c["quadrature_nodes"] == 22 and np.isfinite(c["quadrature_mfpt"])
    q = abs(c["quadrature_mfpt"] - c["mfpt"][0]) / max(c["quadrature_mfpt"], c["mfpt"][0])
    assert abs(c["quadrature_change"] - q) < 1e-12
    assert (c["quadrature_warning"] is None) == (q <= 0.005)
    # a quadrature of 4 nodes: the chain's 83.7 against the walkers' 115.8 ± 2.6 is flagged,
    # by the rule the docs give (3 standard errors plus the refinement's change)
    r4 = pdw.mfpt("rimless", sd="0.5deg", walkers=2000, max_strides=10000, seed=1, chain=True,
                  mesh=100, nodes=4)
    c4 = r4["chain"]
    beyond = abs(c4["mfpt"][1] - r4["restricted_mean"]) - abs(c4["mfpt"][1] - c4["mfpt"][0])
    assert beyond > 3 * r4["restricted_stderr"]
    assert c4["agreement"].startswith("WARNING") and "quadrature (nodes)" in c4["agreement"]
    # the box: a corner and one edge per section axis
    assert c["box"]["corner"].shape == (1,) and c["box"]["edges"].shape == (1, 1)
    assert c["box"]["corner"][0] < r["start"][0] < c["box"]["corner"][0] + c["box"]["edges"][0, 0]


def test_mfpt_chain_at_mid_stance_agrees_with_the_landing_chain_and_the_walkers():
    kw = dict(sd="0.5deg", walkers=2000, max_strides=10000, seed=1, chain=True, mesh=200)
    land = pdw.mfpt("rimless", **kw)
    mid = pdw.mfpt("rimless", chain_section="mid-stance", **kw)
    a, b = land["chain"], mid["chain"]
    assert a["section"] == "landing" and b["section"] == "mid-stance"
    # the same walkers; the mid-stance chain has no layer per node: 11 times fewer states
    assert mid["restricted_mean"] == land["restricted_mean"]
    assert list(a["states"]) == [11 * 200, 11 * 400] and list(b["states"]) == [200, 400]
    # the second section against the first and against the walkers, each within the meshes'
    # changes (plus 3 standard errors for the walkers)
    tol = abs(a["mfpt"][1] - a["mfpt"][0]) + abs(b["mfpt"][1] - b["mfpt"][0])
    assert abs(a["mfpt"][1] - b["mfpt"][1]) < tol + 0.02 * a["mfpt"][1]
    assert abs(b["mfpt"][1] - mid["restricted_mean"]) < 3 * mid["restricted_stderr"] + tol
    assert np.allclose(b["mfpt_lambda"], b["mfpt_quasi_stationary"], rtol=1e-6)
    # the cloud of the same section: its nodes the visited hub rates at the grid's spacing
    cl = pdw.mfpt("rimless", chain_section="mid-stance", chain_mesh="cloud", **kw)["chain"]
    assert cl["layout"] == "cloud" and b["layout"] == "grid" and "cloud" not in b
    assert list(cl["states"]) == list(cl["cloud"]["nodes"])
    assert (cl["cloud"]["nodes"] >= cl["cloud"]["seeds"]).all()
    assert cl["cloud"]["cell"][1] == pytest.approx(cl["cloud"]["cell"][0] * 199 / 399)
    tol_c = tol + abs(cl["mfpt"][1] - cl["mfpt"][0])
    assert abs(cl["mfpt"][1] - b["mfpt"][1]) < tol_c + 0.02 * b["mfpt"][1]
    with pytest.raises(ValueError, match="chain_mesh: a cloud is built on the mid-stance section only"):
        pdw.mfpt("rimless", sd="1deg", chain=True, chain_mesh="cloud")
    with pytest.raises(ValueError, match="chain_mesh: 'mesh' is not one of grid, cloud"):
        pdw.mfpt("rimless", sd="1deg", chain=True, chain_section="mid-stance", chain_mesh="mesh")
    with pytest.raises(ValueError, match="chain_section: 'middle' is not one of landing, mid-stance"):
        pdw.mfpt("rimless", sd="1deg", chain=True, chain_section="middle")
    with pytest.raises(ValueError, match="chain_section: model 'kneed' has 2 modes"):
        pdw.mfpt("kneed", sd="0.1deg", chain=True, chain_section="mid-stance")


def test_mfpt_stride_map():
    kw = dict(sd="2deg", slope="8deg", walkers=200, max_strides=500, seed=4)
    auto = pdw.mfpt("rimless", **kw)
    integrated = pdw.mfpt("rimless", stride_map="integrated", **kw)
    assert auto["stride_map"] == "closed form" and integrated["stride_map"] == "integrated"
    # the closed form and the integrator walk the same walkers to the same fates here
    assert auto["falls"] > 0 and (auto["survival"] == integrated["survival"]).all()
    curve = pdw.mfpt("rimless", **{**kw, "sd": "1deg:2deg:2"})
    assert curve["stride_map"] == "closed form" and curve["mfpt"][1] == auto["mfpt"]
    assert pdw.mfpt("compass", sd="0.1deg", walkers=4, max_strides=5)["stride_map"] == "integrated"
    with pytest.raises(ValueError, match="stride_map: the model compass has no stride map in closed form"):
        pdw.mfpt("compass", sd="0.1deg", stride_map="closed-form")
    with pytest.raises(ValueError, match="stride_map: 'exact' is not one of auto, closed-form, integrated"):
        pdw.mfpt("rimless", sd="1deg", stride_map="exact")


def test_mfpt_uniform_and_file_distributions():
    u = pdw.mfpt("rimless", sd="0.5deg", walkers=300, max_strides=20000, seed=1, dist="uniform")
    n = pdw.mfpt("rimless", sd="0.5deg", walkers=300, max_strides=20000, seed=1)
    # bounded draws of the same spread make the wheel fall less often than normal ones
    assert u["dist"].startswith("uniform") and u["mfpt"] > n["mfpt"]
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "xi.txt")
        with open(path, "w") as f:
            f.write("# two values\n-1\n1\n")
        r = pdw.mfpt("rimless", sd="1deg", walkers=200, max_strides=1000, seed=1, dist="file:" + path)
        assert r["dist"].startswith("file:" + path) and r["falls"] > 0
        with open(path, "w") as f:
            f.write("# nothing\n")
        with pytest.raises(ValueError, match="holds no value"):
            pdw.mfpt("rimless", sd="1deg", dist="file:" + path)
    with pytest.raises(ValueError, match="dist: 'cauchy' is not one of"):
        pdw.mfpt("rimless", sd="1deg", dist="cauchy")
    with pytest.raises(ValueError, match="cannot read"):
        pdw.mfpt("rimless", sd="1deg", dist="file:/no/such/file")
    with pytest.raises(ValueError, match="mesh, nodes: set only with chain=True"):
        pdw.mfpt("rimless", sd="1deg", mesh=10)
    with pytest.raises(ValueError, match="mesh: 1 must be at least 2"):
        pdw.mfpt("rimless", sd="1deg", chain=True, mesh=1)
    with pytest.raises(ValueError, match="nodes: 81 must be between 2 and 80"):
        pdw.mfpt("rimless", sd="1deg", chain=True, nodes=81)
    with pytest.raises(ValueError, match="chain: runs at one sd"):
        pdw.mfpt("rimless", sd="0.4deg:0.6deg:3", chain=True)


def test_disturb_once_and_largest():
    r = pdw.disturb("rimless", once=-0.01, strides=60)
    once = r["once"]
    assert not once["fell"] and once["strides"] == 60 and r["strides"] == 60
    dev = once["deviation"]
    # the wheel's multiplier cos² 2α = 1/2 (8 spokes) per stride, once the start's offset is gone
    assert abs(dev[5] / dev[4] - 0.5) < 0.02
    assert dev[once["returned_after"] - 1] < once["return_tol"] == 1e-6
    # the old spelling of strides gives the same walk
    old = pdw.disturb("rimless", once=-0.01, steps=60)["once"]
    assert old["strides"] == 60 and list(old["deviation"]) == list(dev)
    big = pdw.disturb("simplest", largest=True, tol=1e-6, strides=100)
    down = big["largest"][0]
    assert down["direction"] == "step down" and big["tol"] == 1e-6
    ok, fell = down["survived"], down["falls_at"]
    assert 0 < ok < fell <= ok + 1e-6
    assert not pdw.disturb("simplest", once=ok, strides=100)["once"]["fell"]
    assert pdw.disturb("simplest", once=fell, strides=100)["once"]["fell"]
    up = big["largest"][1]
    assert up["direction"] == "step up" and up["falls_at"] < up["survived"] < 0
    with pytest.raises(ValueError, match="give once D or largest"):
        pdw.disturb("rimless")
    with pytest.raises(ValueError, match="strides: 0 is outside"):
        pdw.disturb("rimless", once=0.0, strides=0)
    with pytest.raises(ValueError, match="strides: 2000000 is outside"):
        pdw.disturb("rimless", once=0.0, strides=2_000_000)
