"""explore(): the local basin explorer started from Python serves the page and the file it was
given; its basin is the file's outcome array, read independently with h5py."""

import json
import os
import subprocess
import tempfile
import urllib.error
import urllib.request

import pytest

import pdw_sweep as pdw

from test_pdw_sweep import cli


def get(url):
    with urllib.request.urlopen(url, timeout=30) as r:
        return r.status, r.headers.get("Content-Type"), r.read()


def test_explore_serves_the_page_and_the_file():
    h5py = pytest.importorskip("h5py")
    exe = cli()
    if exe is None:
        pytest.skip("pdw-sweep binary not built")
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "b.h5")
        subprocess.run([exe, "basin", "--grid", "31x27", "--out", path, "--quiet"], check=True,
                       capture_output=True)
        url = pdw.explore(path, port=0, save_dir=d)
        base, token = url.split("?token=")
        assert base.startswith("http://127.0.0.1:") and not base.endswith(":0/")
        assert len(token) == 64
        st, ctype, page = get(url)
        assert st == 200 and ctype.startswith("text/html") and b"/app.js" in page
        st, _, body = get(base + "api/files?token=" + token)
        files = json.loads(body)["files"]
        assert files == [{"index": 0, "name": "b.h5", "kind": "basin", "model": "simplest"}]
        b = json.loads(get(base + "api/basin/0?token=" + token)[2])
        with h5py.File(path) as f:
            outcome = f["basin/outcome"][()]
            legend = json.loads(f["basin/outcome"].attrs["legend"])
        assert (b["ny"], b["nx"]) == outcome.shape
        assert b["outcome"] == outcome.ravel().tolist()
        assert {str(l["code"]): l["name"] for l in b["legend"]} == legend
        with pytest.raises(urllib.error.HTTPError) as e:
            get(base + "api/basin/5?token=" + token)
        assert e.value.code == 404 and "no file 5" in json.loads(e.value.read())["error"]


def test_explore_refuses_a_missing_file():
    with pytest.raises(ValueError, match="is not a file"):
        pdw.explore("/nonexistent/b.h5")
