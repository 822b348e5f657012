"""The CLI's HDF5 files read by h5py, an independent reader: dimension scales on the basin grid,
units on every dataset, provenance, the slice, the fill value in the legend."""

import json
import os
import shutil
import subprocess
import tempfile

import pytest

h5py = pytest.importorskip("h5py")


def cli():
    """The pdw-sweep binary of this tree (CI builds it before running pytest)."""
    root = os.path.join(os.path.dirname(__file__), "..", "..")
    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(root, "target"))
    path = os.path.join(target, "release", "pdw-sweep")
    return path if os.path.exists(path) else shutil.which("pdw-sweep")


@pytest.fixture(scope="module")
def compass_basin():
    exe = cli()
    if exe is None:
        pytest.skip("the pdw-sweep binary is not built (cargo build --release)")
    d = tempfile.mkdtemp()
    out = os.path.join(d, "c.h5")
    subprocess.run([exe, "basin", "--model", "compass", "--grid", "12x10", "--quiet",
                    "--out", out], check=True)
    yield out
    shutil.rmtree(d)


def test_grid_axes_are_dimension_scales(compass_basin):
    with h5py.File(compass_basin, "r") as f:
        out = f["basin/outcome"]
        assert out.shape == (10, 12)
        assert h5py.h5ds.is_scale(f["grid/x"].id) and h5py.h5ds.is_scale(f["grid/y"].id)
        # row index = y, column index = x
        assert out.dims[0][0].name == "/grid/y"
        assert out.dims[1][0].name == "/grid/x"
        assert f["basin/final"].dims[1][0].name == "/grid/x"
        assert len(f["basin/final"].dims[2]) == 0
        assert (out.dims[1][0][:] == f["grid/x"][:]).all()


def test_every_dataset_has_units_and_the_file_its_provenance(compass_basin):
    with h5py.File(compass_basin, "r") as f:
        missing = []
        f.visititems(lambda n, o: missing.append(n)
                     if isinstance(o, h5py.Dataset) and "units" not in o.attrs else None)
        assert missing == []
        assert f["grid/x"].attrs["units"] == "rad"
        assert json.loads(f["basin/final"].attrs["units"]) == ["rad", "rad/s", "rad/s"]
        p = f["provenance"].attrs
        for k in ["crate_version", "git_commit", "build_profile", "simd_path", "host",
                  "command", "options", "created", "commands"]:
            assert k in p, k
        assert json.loads(p["options"])["integrator"]["method"] == "dop853"
        legend = json.loads(f["basin/outcome"].attrs["legend"])
        assert legend["255"] == "not_computed"
        s = f["slice"].attrs
        assert (s["x"], s["y"]) == ("stance", "stance_rate")
        assert json.loads(s["fixed"])["hip_rate"]["source"] == "fixed point"
        assert bool(s["on_fixed_point"])
