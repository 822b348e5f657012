"""The Python functions of the CLI's commands (orbit_diagram, basin_over, follow, design,
animate) against the CLI on the same input, and against second methods: a plain basin, the
fixed point, Goswami et al. 1998's period-doubling slope; the signatures and the basin legend."""

import inspect
import warnings
import json
import os
import pathlib
import subprocess
import tempfile

import numpy as np
import pytest

import pdw_sweep as pdw

from test_pdw_sweep import cli


def run_cli(*args):
    exe = cli()
    if exe is None:
        pytest.skip("pdw-sweep binary not built")
    r = subprocess.run([exe, *args], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r.stdout


def functions():
    return {n: f for n, f in vars(pdw).items() if callable(f) and not n.startswith("_")}


# Every function shows its real defaults (pyo3 renders a constant or tuple default as `...`
# unless the function names a text signature).
SIGNED = sorted(functions())


@pytest.mark.parametrize("name", SIGNED)
def test_signatures_show_real_defaults(name):
    f = functions()[name]
    assert f.__text_signature__ is not None
    assert "..." not in f.__text_signature__
    sig = inspect.signature(f)
    for p in sig.parameters.values():
        assert p.default is not Ellipsis, (name, p.name)
    assert "..." not in str(sig) and "Ellipsis" not in str(sig)


def test_signature_defaults_are_the_cli_defaults():
    b = inspect.signature(pdw.basin).parameters
    assert b["grid"].default == (101, 101) and b["threads"].default == 2
    assert b["max_strides"].default == 100
    g = inspect.signature(pdw.gaits).parameters
    assert g["starts"].default == 256
    d = inspect.signature(pdw.design).parameters
    # `pdw-sweep design`'s defaults (docs/cli.md)
    assert d["budget"].default == 60 and d["mu"].default == 0.6
    assert d["knee_margin"].default == 0.1 and d["basin_grid"].default == 15
    # no box: scaled to each design's gait, as the CLI without --basin-box
    assert d["basin_box"].default is None and d["max_strides"].default == 40
    assert d["out"].default is None and d["force"].default is False
    a = inspect.signature(pdw.animate).parameters
    assert a["strides"].default == 2 and a["steps"].default is None and a["fps"].default is None
    assert a["size"].default == (640, 400) and a["from_file"].default is None
    assert inspect.signature(pdw.basin_over).parameters["grid"].default == (41, 41)


def test_basin_legend_lists_exactly_the_codes_the_result_can_hold():
    # at 0.016 rad the simplest walker's period-one gait is unstable (period doubling near
    # 0.0151, Garcia et al. 1998): no code 0
    out, legend, m = pdw.basin("simplest", slope=0.016, grid=(15, 15))
    assert m["gait"] is None
    assert 0 not in legend and "gait" not in m["fractions"]
    assert set(np.unique(out)) <= set(legend)
    assert any(a["period_k"] == 2 for a in m["attractors"])
    # with a stable gait, code 0 is listed and reached
    out, legend, m = pdw.basin("simplest", slope=0.009, grid=(15, 15))
    assert legend[0] == "gait" and 0 in np.unique(out)
    assert set(np.unique(out)) <= set(legend)


def test_orbit_diagram_equals_the_cli_and_the_fixed_point():
    with tempfile.TemporaryDirectory() as d:
        ref = json.loads(run_cli("fixedpoint", "--sweep", "slope=0.014:0.018:5", "--json",
                                 "--quiet", "--out", os.path.join(d, "bif.h5")))
    od = pdw.orbit_diagram("simplest", start=0.014, stop=0.018, points=5)
    ro = ref["orbit_diagram"]
    np.testing.assert_array_equal(od["values"], ro["parameter"])
    first = od["points"][:, :, 0]
    want = np.array([[np.nan if v is None else v for v in row] for row in ro["points"]])
    np.testing.assert_array_equal(first, want)
    assert od["points"].shape == (5, 64, 2) and od["section_names"] == ["theta", "thetadot"]
    # 0.014: the stable period-one gait, every recorded point on it
    fp = pdw.fixed_point("simplest", slope=0.014, gait="stable")[0]
    assert od["period"][0] == 1
    np.testing.assert_allclose(od["points"][0], np.tile(fp["section"], (64, 1)), atol=1e-7)
    # 0.016: past the period doubling, a period-2 orbit
    assert od["period"][2] == 2 and np.all(od["fall_stride"] == -1)


def test_basin_over_equals_the_cli_and_a_plain_basin():
    with tempfile.TemporaryDirectory() as d:
        ref = json.loads(run_cli("basin", "--over", "slope=0.009:0.012:2", "--grid", "9x9",
                                 "--json", "--quiet", "--out", os.path.join(d, "bs.h5")))
    bs = pdw.basin_over("simplest", over="slope=0.009:0.012:2", grid=(9, 9))
    assert bs["columns"] == ref["columns"] and bs["kinds"] == ref["kinds"]
    np.testing.assert_array_equal(bs["values"], [v["param"] for v in ref["values"]])
    want = [[v["fractions"][c] for c in ref["columns"]] for v in ref["values"]]
    np.testing.assert_array_equal(bs["fractions"], want)
    np.testing.assert_array_equal(bs["outcome_fractions"], ref["outcome_fractions"])
    np.testing.assert_allclose(bs["fractions"].sum(axis=1), 1.0, atol=1e-12)
    # the same range given as parameter/start/stop/points
    again = pdw.basin_over("simplest", parameter="slope", start=0.009, stop=0.012, points=2,
                           grid=(9, 9))
    np.testing.assert_array_equal(again["fractions"], bs["fractions"])
    # at A the box is a plain basin's default box: the same fractions
    out, legend, m = pdw.basin("simplest", slope=0.009, grid=(9, 9))
    gait = bs["columns"].index("gait")
    assert bs["fractions"][0, gait] == m["fractions"]["gait"]
    assert bs["box"]["x"][1:3] == (m["x"][0], m["x"][-1])
    with pytest.raises(ValueError, match="over"):
        pdw.basin_over("simplest", over="slope=0.009:0.012:2", slope=0.01)
    with pytest.raises(ValueError, match="no parameter 'nope'"):
        pdw.basin_over("simplest", over="nope=1:2:2")


def test_follow_equals_the_cli_and_goswami_1998():
    with tempfile.TemporaryDirectory() as d:
        ref = json.loads(run_cli("fixedpoint", "--model", "compass", "--follow", "pd",
                                 "--sweep", "hip_mass=8:12:3", "--free", "slope", "--json",
                                 "--quiet", "--out", os.path.join(d, "pd.h5")))
    c = pdw.follow("compass", kind="pd", sweep="hip_mass=8:12:3", free="slope")
    pts = np.array(ref["curve"]["points"])
    np.testing.assert_array_equal(c["p_step"], pts[:, 0])
    np.testing.assert_array_equal(c["p_free"], pts[:, 1])
    np.testing.assert_array_equal(c["section"], [g["section"] for g in ref["gaits"]])
    np.testing.assert_array_equal(c["critical_multiplier"],
                                  [g["critical_multiplier"] for g in ref["gaits"]])
    assert c["complete"] == ref["complete"] and c["start"]["free"] == ref["start"]["free"]
    # Goswami et al. 1998 (IJRR 17(12)): period doubling near 4.39 deg at mu = m_H/m = 2
    assert abs(np.degrees(c["p_free"][1]) - 4.39) < 0.005
    # at a period doubling one multiplier is -1
    assert np.all(np.abs(c["critical_multiplier"] + 1) < 1e-6)
    with pytest.raises(ValueError, match="not supported"):
        pdw.follow("compass", kind="ns", sweep="hip_mass=8:12:3", free="slope")
    with pytest.raises(ValueError, match="same parameter"):
        pdw.follow("compass", sweep="slope=0.01:0.02:3", free="slope")


def test_design_equals_the_cli_file():
    h5py = pytest.importorskip("h5py")
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "design.h5")
        run_cli("design", "--model", "compass", "--free", "hip_mass=5:15", "--budget", "4",
                "--objective", "margin", "--quiet", "--out", out)
        with h5py.File(out, "r") as f:
            params = f["params"][()]
            status = f["status"][()]
            cost = f["cost"][()]
            rho = f["rho"][()]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = pdw.design("compass", free={"hip_mass": (5.0, 15.0)}, budget=4, objective="margin")
    # a best design within 1 % of the range from a bound is named and warned about
    hm = got["best"]["params"]["hip_mass"]
    assert bool(got["best"]["on_bound"]) == (min(hm - 5.0, 15.0 - hm) <= 0.1)
    assert [str(w.message) for w in caught if "bound" in str(w.message)] == got["best"]["on_bound"]
    np.testing.assert_array_equal(got["params"], params)
    np.testing.assert_array_equal(got["status"], status)
    np.testing.assert_array_equal(got["cost"], cost)
    np.testing.assert_array_equal(got["rho"], rho)
    # the start is the model's own hip mass; the best design has the smallest cost
    own = [p["default"] for m in pdw.models() if m["name"] == "compass"
           for p in m["parameters"] if p["name"] == "hip_mass"][0]
    assert got["params"][0, 0] == own
    assert got["best"]["cost"] == np.min(got["cost"])
    # margin objective: a feasible design's cost is its largest |multiplier| (docs/cli.md)
    feasible = got["status"] == 0
    np.testing.assert_array_equal(got["cost"][feasible], got["rho"][feasible])
    with pytest.raises(ValueError, match="mu"):
        pdw.design("compass", free={"hip_mass": (5.0, 15.0)}, mu=-1.0)
    with pytest.raises(ValueError, match="not a chain walker"):
        pdw.design("simplest", free={"slope": (0.005, 0.01)})
    with pytest.raises(ValueError, match="at least one"):
        pdw.design("compass")


def test_animate_writes_the_cli_gif():
    with tempfile.TemporaryDirectory() as d:
        a, b = os.path.join(d, "cli.gif"), os.path.join(d, "py.gif")
        subprocess.run([cli() or pytest.skip("pdw-sweep binary not built"), "animate",
                        "--model", "compass", "--slope", "3deg", "--out", a],
                       check=True, capture_output=True)
        got = pdw.animate("compass", slope="3deg", out=b)
        assert os.fspath(got) == b
        with open(a, "rb") as fa, open(b, "rb") as fb:
            data = fb.read()
            assert data[:6] == b"GIF89a" and fa.read() == data
        with pytest.raises(ValueError, match="exists"):
            pdw.animate("compass", slope="3deg", out=b)
        pdw.animate("compass", slope="3deg", out=b, force=True)


def test_design_out_writes_the_cli_file():
    h5py = pytest.importorskip("h5py")
    with tempfile.TemporaryDirectory() as d:
        a, b = os.path.join(d, "cli.h5"), os.path.join(d, "py.h5")
        run_cli("design", "--model", "compass", "--free", "hip_mass=5:15", "--budget", "3",
                "--objective", "margin", "--quiet", "--out", a)
        got = pdw.design("compass", free={"hip_mass": (5.0, 15.0)}, budget=3,
                         objective="margin", out=b)
        with h5py.File(a, "r") as fa, h5py.File(b, "r") as fb:
            # the same datasets, the same settings and every value equal (NaN where NaN)
            assert sorted(fa.keys()) == sorted(fb.keys())
            assert fa.attrs["settings"] == fb.attrs["settings"]
            for k in fa.keys():
                if isinstance(fa[k], h5py.Dataset):
                    np.testing.assert_array_equal(fa[k][()], fb[k][()])
                    assert fa[k].attrs.get("units") == fb[k].attrs.get("units")
            np.testing.assert_array_equal(fb["cost"][()], got["cost"])
            assert "pdw_sweep.design" in fb["provenance"].attrs["command"]
        # the picture beside it, as the CLI draws it
        assert os.path.getsize(os.path.join(d, "py.png")) > 0
        assert got["out"] == b and got["png"] == os.path.join(d, "py.png")
        # the same file continues its search, as the CLI's rerun does: the 3 stored designs
        # replayed, one more evaluated
        more = pdw.design("compass", free={"hip_mass": (5.0, 15.0)}, budget=4,
                          objective="margin", out=b)
        assert more["designs"] == 4 and more["new"] == 1
        np.testing.assert_array_equal(more["cost"][:3], got["cost"])
        # other settings are refused naming the Python option, force starts over
        with pytest.raises(ValueError, match="out: .* other settings.*pass force"):
            pdw.design("compass", free={"hip_mass": (5.0, 15.0)}, budget=1, out=b)
        again = pdw.design("compass", free={"hip_mass": (5.0, 15.0)}, budget=1, out=b,
                           force=True)
        assert again["designs"] == 1
        # the report is the CLI's --json
        j = json.loads(run_cli("design", "--model", "compass", "--free", "hip_mass=5:15",
                               "--budget", "3", "--objective", "margin", "--quiet", "--json",
                               "--out", a, "--force"))
        for k in ("designs", "new", "counts", "objective", "free_names"):
            assert j[k] == got[k], k
        assert j["best"]["params"] == got["best"]["params"]
        assert j["best"]["reproduce"] == got["best"]["reproduce"]


def gif_header(path):
    """Width, height, the first frame's delay (centiseconds) and the frame count of a GIF,
    walked block by block (GIF89a: header, screen descriptor, global colour table, then
    extensions and images)."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:6] == b"GIF89a"
    w, h, flags = int.from_bytes(data[6:8], "little"), int.from_bytes(data[8:10], "little"), data[10]
    i = 13 + (3 * 2 ** ((flags & 7) + 1) if flags & 0x80 else 0)
    delay, frames = None, 0

    def skip_blocks(i):
        while data[i]:
            i += data[i] + 1
        return i + 1

    while data[i] != 0x3B:
        if data[i] == 0x21:
            if data[i + 1] == 0xF9 and delay is None:
                delay = int.from_bytes(data[i + 4:i + 6], "little")
            i = skip_blocks(i + 2)
        else:
            assert data[i] == 0x2C
            flags = data[i + 9]
            i += 10 + (3 * 2 ** ((flags & 7) + 1) if flags & 0x80 else 0)
            frames += 1
            i = skip_blocks(i + 1)
    return w, h, delay, frames


def test_animate_options_and_from_file_equal_the_cli():
    with tempfile.TemporaryDirectory() as d:
        a, b = os.path.join(d, "cli.gif"), os.path.join(d, "py.gif")
        run_cli("animate", "--model", "compass", "--strides", "1", "--fps", "25", "--size",
                "320x240", "--out", a)
        pdw.animate("compass", strides=1, fps=25, size=(320, 240), out=b)
        with open(a, "rb") as fa, open(b, "rb") as fb:
            assert fa.read() == fb.read()
        # 25 fps: 4 cs; one stride of about 0.734 s: round(0.734 / 0.04) = 18 frames, + 1
        assert gif_header(b) == (320, 240, 4, 19)
        t = os.path.join(d, "t.h5")
        run_cli("simulate", "--model", "compass", "--steps", "2", "--out", t)
        c, p = os.path.join(d, "tcli.gif"), os.path.join(d, "tpy.gif")
        run_cli("animate", "--from", t, "--out", c)
        pdw.animate(from_file=t, out=p)
        with open(c, "rb") as fa, open(p, "rb") as fb:
            assert fa.read() == fb.read()
        for bad, says in [(dict(strides=0), "strides: 0 strides"), (dict(steps=0), "strides"),
                          (dict(fps=60.0), "fps"),
                          (dict(size=(10, 10)), "size"),
                          (dict(from_file=os.path.join(d, "none.h5")), "none.h5"),
                          (dict(from_file=t, slope=0.01), "from_file")]:
            with pytest.raises(ValueError, match=says):
                pdw.animate("compass", out=os.path.join(d, "bad.gif"), **bad)


def test_the_stub_file_has_every_function_s_signature():
    """python/pdw_sweep.pyi (what editors show) names every function with the parameters and
    defaults of the compiled one."""
    import ast
    stub = pathlib.Path(__file__).resolve().parent.parent / "pdw_sweep.pyi"
    tree = ast.parse(stub.read_text())
    defs = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}
    for name, f in functions().items():
        assert name in defs, name
        a = defs[name].args
        params = a.posonlyargs + a.args + a.kwonlyargs
        defaults = [None] * (len(a.posonlyargs + a.args) - len(a.defaults)) + a.defaults
        defaults += a.kw_defaults
        want = {p.name: p for p in inspect.signature(f).parameters.values()
                if p.kind is not inspect.Parameter.VAR_KEYWORD}
        got = [p.arg for p in params]
        assert got == list(want), (name, got, list(want))
        for p, d in zip(params, defaults):
            if d is None:
                continue
            try:
                value = ast.literal_eval(d)
            except ValueError:
                continue  # a name (THREADS) rather than a literal
            assert value == want[p.arg].default, (name, p.arg, value, want[p.arg].default)
