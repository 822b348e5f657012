"""`pdw-sweep explore` in a real browser: headless Chromium driven by selenium over WebDriver.

On basins made by the release binary it clicks a gait cell and a fall cell (their pixels from
the file's axes), checks that the animation runs and that the outcome shown equals the cells'
labels in the file, drags a box and checks that the saved window equals `pdw-sweep basin` on
that box cell for cell (both files read with h5py), and moves a slider and checks that the gait
point moves; on a sweep file it clicks a stable branch point and checks its gait walks; on a
design file it sorts the designs table both ways (checked against the file read with h5py),
walks a design's gait and clicks a design without a gait for its message.
Screenshots and the measured times (click to first animation frame for every
preset, a 400x400 window of the simplest walker) go to a fresh temporary folder (its path is
printed), or to $PDW_EXPLORE_RESULTS when set (e.g. experiments/results/explore to refresh the
pictures the docs show); the test never writes into the repository otherwise.
Every wait is on a condition of the page (a frame counter advancing, a status shown), none on
a fixed time.

Skips when chromium or chromedriver is missing, except in CI (CI=true), where that fails.
Run: `python -m pytest -q tests/browser` after `cargo build --release`.
"""

import json
import os
import re
import shutil
import subprocess
import tempfile
import time

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
EXE = os.path.join(os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "release",
                   "pdw-sweep")
RESULTS = os.environ.get("PDW_EXPLORE_RESULTS") or tempfile.mkdtemp(prefix="pdw-explore-browser-")
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
DRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
# (name, basin arguments): every preset with a two-coordinate section
PRESETS = [
    ("simplest", ["--grid", "61x61"]),
    ("compass", ["--model", "compass", "--grid", "31x31"]),
    ("kneed", ["--model", "kneed", "--grid", "21x21"]),
    ("seed5", ["--model", "seed5", "--grid", "21x21"]),
]
# a small design search of the compass over slope and hip mass (about a second); its seeded
# designs include an uphill slope, where a passive walker has no gait
DESIGN = ["--model", "compass", "--free", "slope=-0.1:0.06", "--free", "hip_mass=4:16",
          "--budget", "7", "--init", "6", "--basin-grid", "4", "--max-strides", "10"]


def need_browser():
    missing = [p for p in (CHROMIUM, DRIVER) if not os.path.exists(p)]
    if missing:
        msg = f"no {', '.join(missing)}: install Debian's chromium and chromium-driver"
        if os.environ.get("CI") == "true":
            pytest.fail(msg + " (CI must run the browser test)")
        pytest.skip(msg)
    if not os.path.exists(EXE):
        pytest.fail(f"{EXE} not built: run cargo build --release first")


def basin(path, args):
    subprocess.run([EXE, "basin", *args, "--out", path, "--quiet"], check=True,
                   capture_output=True)


@pytest.fixture(scope="module")
def setup():
    need_browser()
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        if os.environ.get("CI") == "true":
            pytest.fail("selenium is not installed (CI must run the browser test)")
        pytest.skip("selenium is not installed: python -m pip install selenium")
    work = tempfile.mkdtemp()
    files = []
    for name, args in PRESETS:
        files.append(os.path.join(work, f"{name}.h5"))
        basin(files[-1], args)
    sweep = os.path.join(work, "sweep.h5")
    subprocess.run([EXE, "fixedpoint", "--sweep", "slope=0.005:0.018:40", "--out", sweep,
                    "--png", os.path.join(work, "sweep.png")], check=True, capture_output=True)
    files.append(sweep)
    design = os.path.join(work, "design.h5")
    subprocess.run([EXE, "design", *DESIGN, "--out", design, "--png",
                    os.path.join(work, "design.png"), "--quiet"], check=True, capture_output=True)
    files.append(design)
    server = subprocess.Popen([EXE, "explore", *files, "--port", "0", "--save-dir", work],
                              stdout=subprocess.PIPE, text=True)
    line = server.stdout.readline()
    url = re.search(r"http://\S+", line).group(0)
    opts = webdriver.ChromeOptions()
    for a in ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
              "--disable-background-networking", "--disable-component-update", "--disable-sync",
              f"--user-data-dir={tempfile.mkdtemp()}", "--window-size=1400,960"]:
        opts.add_argument(a)
    opts.binary_location = CHROMIUM
    driver = webdriver.Chrome(service=Service(DRIVER), options=opts)
    driver.get(url)
    os.makedirs(RESULTS, exist_ok=True)
    print(f"screenshots and measured.json go to {RESULTS}")
    yield {"driver": driver, "files": files, "work": work, "url": url}
    driver.quit()
    server.terminate()
    server.wait(10)
    shutil.rmtree(work, ignore_errors=True)


def wait(cond, what, timeout=60):
    t0 = time.time()
    while time.time() - t0 < timeout:
        v = cond()
        if v:
            return v
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


def frames_advance(d, n=1):
    """Waits until the walk's frame counter has advanced by `n` frames (the animation runs)."""
    f0 = int(text(d, "frame"))
    wait(lambda: int(text(d, "frame")) >= f0 + n, f"the animation to advance {n} frame(s)")


def js(d, expr):
    return d.execute_script(f"return {expr};")


def text(d, id_):
    return d.find_element("id", id_).text


def plot_rect(d):
    c = d.find_element("id", "basin")
    return c, {k: float(c.get_attribute("data-" + k)) for k in ("left", "top", "width", "height")}


def cell_pixel(r, nx, ny, i, j):
    """Centre of cell (row i, column j): row 0 at the bottom, as the page draws it."""
    return r["left"] + (j + 0.5) / nx * r["width"], r["top"] + r["height"] - (i + 0.5) / ny * r["height"]


def at(d, c, px, py):
    """An action chain on canvas `c` at pixel (px, py) from its top-left corner."""
    from selenium.webdriver.common.action_chains import ActionChains
    w, h = c.size["width"], c.size["height"]
    return ActionChains(d).move_to_element_with_offset(c, px - w / 2, py - h / 2)


def show_file(d, index):
    d.execute_script(f"document.getElementById('file').value = '{index}'; showFile({index});")
    wait(lambda: js(d, f"(window.explorer.grid && window.explorer.grid.file === {index}) || "
                       f"(window.explorer.sweep && window.explorer.sweep.file === {index})"),
         f"file {index} drawn")


def labels(path):
    import h5py
    with h5py.File(path) as f:
        legend = {int(k): v for k, v in json.loads(f["basin/outcome"].attrs["legend"]).items()}
        return f["basin/outcome"][()], legend, f["grid/x"][()], f["grid/y"][()]


def interior(outcome, name_of, want):
    """A cell labelled `want` whose 8 neighbours share its label, nearest the middle."""
    ny, nx = outcome.shape
    best = None
    for i in range(1, ny - 1):
        for j in range(1, nx - 1):
            block = outcome[i - 1:i + 2, j - 1:j + 2]
            if name_of[outcome[i, j]].startswith(want) and (block == outcome[i, j]).all():
                dist = abs(i - ny / 2) + abs(j - nx / 2)
                if best is None or dist < best[0]:
                    best = (dist, i, j)
    assert best, f"no interior {want} cell"
    return best[1], best[2]


def click_cell(d, path, i, j):
    outcome, name_of, _, _ = labels(path)
    c, r = plot_rect(d)
    px, py = cell_pixel(r, outcome.shape[1], outcome.shape[0], i, j)
    at(d, c, px, py).click().perform()
    want = name_of[outcome[i, j]]
    wait(lambda: js(d, "window.explorer.firstFrameMs") is not None and
         js(d, f"window.explorer.walkCell && window.explorer.walkCell.row === {i} && "
               f"window.explorer.walkCell.col === {j}"), f"the walk of cell [{i}, {j}]")
    return want


def test_click_walks_the_cell_with_the_files_label(setup):
    d, path = setup["driver"], setup["files"][0]
    show_file(d, 0)
    outcome, name_of, _, _ = labels(path)
    for kind in ("fall", "gait"):
        i, j = interior(outcome, name_of, kind)
        want = click_cell(d, path, i, j)
        assert text(d, "outcome") == want and text(d, "stored") == want
        frames_advance(d)
    frames_advance(d, 60)
    d.save_screenshot(os.path.join(RESULTS, "walk.png"))


def test_click_to_first_frame_for_every_preset(setup):
    d = setup["driver"]
    times = {}
    for k, (name, _) in enumerate(PRESETS):
        show_file(d, k)
        outcome, name_of, _, _ = labels(setup["files"][k])
        i, j = interior(outcome, name_of, "gait") if (outcome == 0).sum() > 9 else (0, 0)
        want = click_cell(d, setup["files"][k], i, j)
        assert text(d, "outcome") == want
        times[name] = round(js(d, "window.explorer.firstFrameMs"), 1)
        if name == "kneed":
            frames_advance(d, 60)
            d.save_screenshot(os.path.join(RESULTS, "walk-kneed.png"))
    record("click_to_first_frame_ms", times)
    print("click to first frame (ms):", times)


def record(key, value):
    path = os.path.join(RESULTS, "measured.json")
    data = json.load(open(path)) if os.path.exists(path) else {}
    data[key] = value
    with open(path, "w") as f:
        json.dump(data, f, indent=1, sort_keys=True)
        f.write("\n")


def drag_box(d, path, fx, fy):
    """Drags the box of fractions fx, fy of the plot; returns when the window is done."""
    c, r = plot_rect(d)
    x0, x1 = (r["left"] + f * r["width"] for f in fx)
    y0, y1 = (r["top"] + f * r["height"] for f in fy)
    before = js(d, "window.explorer.job")
    at(d, c, x0, y0).click_and_hold().move_by_offset(x1 - x0, y1 - y0).release().perform()
    wait(lambda: js(d, "window.explorer.job") != before and
         js(d, "window.explorer.grid.status === 'done' && "
               "window.explorer.grid.job === window.explorer.job"), "the refined window", 120)


def test_zoom_refines_as_basin_and_saves(setup):
    import h5py
    import numpy as np
    from selenium.webdriver.support.ui import Select
    d, work = setup["driver"], setup["work"]
    show_file(d, 0)
    Select(d.find_element("id", "res")).select_by_value("100")
    drag_box(d, setup["files"][0], (0.35, 0.65), (0.3, 0.6))
    g = js(d, "window.explorer.grid")
    xs, ys = g["x"]["values"], g["y"]["values"]
    d.find_element("id", "save").click()
    saved = wait(lambda: d.find_element("id", "saved").get_attribute("data-file"), "save")
    ref = os.path.join(work, "box.h5")
    basin(ref, ["--x", f"{g['x']['name']}={xs[0]!r}:{xs[-1]!r}",
                "--y", f"{g['y']['name']}={ys[0]!r}:{ys[-1]!r}", "--grid", f"{len(xs)}x{len(ys)}"])
    with h5py.File(os.path.join(work, saved)) as a, h5py.File(ref) as b:
        assert np.array_equal(a["grid/x"][()], b["grid/x"][()])
        assert np.array_equal(a["basin/outcome"][()], b["basin/outcome"][()])
        assert np.array_equal(a["basin/strides"][()], b["basin/strides"][()])
    # a click in the window walks that window's cell, with the window's label
    g = js(d, "window.explorer.grid")
    nx, ny = g["nx"], g["ny"]
    i, j = ny // 2, nx // 2
    c, r = plot_rect(d)
    at(d, c, *cell_pixel(r, nx, ny, i, j)).click().perform()
    wait(lambda: js(d, f"window.explorer.walkCell && window.explorer.walkCell.row === {i} && "
                       f"window.explorer.walkCell.job === window.explorer.job"), "a window walk")
    code = g["outcome"][i * nx + j]
    want = [l["name"] for l in g["legend"] if l["code"] == code][0]
    assert text(d, "outcome") == want and text(d, "stored") == want
    frames_advance(d, 60)
    d.save_screenshot(os.path.join(RESULTS, "zoom.png"))
    # the slope slider: the window and its gait are computed again
    before = text(d, "gaitpoint")
    from selenium.webdriver.common.keys import Keys
    slider = d.find_element("id", "set-slope")
    slider.send_keys(Keys.ARROW_RIGHT * 20)
    wait(lambda: text(d, "gaitpoint") != before, "the gait point to move", 120)
    assert "gait" in text(d, "gaitpoint")


def test_a_400x400_window_of_the_simplest_walker(setup):
    from selenium.webdriver.support.ui import Select
    d = setup["driver"]
    show_file(d, 0)
    Select(d.find_element("id", "res")).select_by_value("400")
    drag_box(d, setup["files"][0], (0.2, 0.8), (0.2, 0.8))
    s = js(d, "window.explorer.refineMs") / 1000
    assert js(d, "window.explorer.grid.nx") == 400
    record("zoom_400x400_simplest_s", round(s, 3))
    print(f"400x400 window of the simplest walker: {s:.2f} s")


def test_a_sweep_point_walks_with_its_multipliers(setup):
    d = setup["driver"]
    index = len(PRESETS)
    show_file(d, index)
    sw = js(d, "window.explorer.sweep")
    b = sw["branches"][0]
    k = b["stable"].index(True)
    xs = [p for br in sw["branches"] for p in br["parameter"]]
    ys = [s[0] for br in sw["branches"] for s in br["section"]]
    c, r = plot_rect(d)
    x0, x1 = min(xs), max(xs)
    y0, y1 = min(ys), max(ys)
    mx, my = 0.05 * (x1 - x0), 0.05 * (y1 - y0)
    px = r["left"] + (b["parameter"][k] - x0 + mx) / (x1 - x0 + 2 * mx) * r["width"]
    py = r["top"] + r["height"] - (b["section"][k][0] - y0 + my) / (y1 - y0 + 2 * my) * r["height"]
    at(d, c, px, py).click().perform()
    wait(lambda: "multipliers" in text(d, "cellinfo"), "the branch point's gait")
    assert text(d, "outcome").endswith("stable")
    frames_advance(d)


def design_rows(d):
    """The designs table's rows as the page shows them: lists of cell texts."""
    return d.execute_script(
        "return [...document.querySelectorAll('#designs tbody tr')]"
        ".map((tr) => [...tr.cells].map((c) => c.textContent));")


def heading(d, name):
    """The designs table's heading of column `name` and its index."""
    for k, th in enumerate(d.find_elements("css selector", "#designs th")):
        if th.text.split(" [")[0].split(" ")[0] == name:
            return th, k
    raise AssertionError(f"no column {name}")


def sort_by(d, name, order):
    """Clicks column `name`'s heading; checks the marker and the rows' order `order`."""
    th, k = heading(d, name)
    th.click()
    th, _ = heading(d, name)
    assert th.get_attribute("aria-sort") == order
    assert th.text.endswith("\u25b2" if order == "ascending" else "\u25bc")
    return [(int(r[0]), r[k]) for r in design_rows(d)]


def click_design(d, i):
    row = d.find_element("css selector", f"#designs tbody tr[data-design='{i}']")
    row.find_elements("css selector", "td")[0].click()


def test_a_design_files_table_sorts_and_its_designs_walk(setup):
    import h5py
    import numpy as np
    d, path = setup["driver"], setup["files"][-1]
    index = len(setup["files"]) - 1
    with h5py.File(path) as f:
        params, status = f["params"][()], f["status"][()]
        words = [w.replace("_", " ") for w in json.loads(f.attrs["status_names"])]
        free = json.loads(f.attrs["free_names"])
    d.execute_script(f"document.getElementById('file').value = '{index}'; showFile({index});")
    wait(lambda: js(d, f"window.explorer.design && window.explorer.design.file === {index}"),
         "the designs table")
    rows = design_rows(d)
    assert [int(r[0]) for r in rows] == list(range(len(params)))
    # the status in the words of the search picture's legend
    _, ks = heading(d, "status")
    assert [r[ks] for r in rows] == [words[c] for c in status]
    # a column with empty cells (designs without a gait have no period): empty last both ways
    for order in ("ascending", "descending"):
        per = sort_by(d, "period", order)
        n_empty = sum(1 for _, v in per if v == "")
        assert all(v == "" for _, v in per[len(per) - n_empty:])
        vals = [float(v) for _, v in per[:len(per) - n_empty]]
        assert vals == sorted(vals, reverse=order == "descending")
    # hip mass: ascending, then descending, as the file's values sort
    hm = params[:, free.index("hip_mass")]
    up = sort_by(d, "hip_mass", "ascending")
    assert [i for i, _ in up] == list(np.argsort(hm, kind="stable"))
    assert [i for i, _ in up] != list(range(len(hm))), "the file's designs were already sorted"
    shown = [float(v) for _, v in up]
    assert shown == sorted(shown)
    down = sort_by(d, "hip_mass", "descending")
    assert [i for i, _ in down] == list(np.argsort(-hm, kind="stable"))
    # a feasible design walks: its gait animates, the design shown is the row clicked
    i = int(max(np.flatnonzero(status == 0), key=lambda k: hm[k]))
    t0 = time.time()
    click_design(d, i)
    wait(lambda: js(d, f"window.explorer.walk && window.explorer.walk.design === {i} && "
                       "window.explorer.firstFrameMs !== null"), f"design {i}'s walk")
    wall_ms = (time.time() - t0) * 1000
    w = js(d, "window.explorer.walk")
    assert [w["params"][n] for n in free] == list(params[i])
    assert text(d, "outcome") == f"{i}: feasible"
    row = [r for r in design_rows(d) if int(r[0]) == i][0]
    assert text(d, "stored") == ", ".join(f"{n} = {row[1 + k]}" for k, n in enumerate(free))
    s0 = js(d, "window.explorer.t")
    frames_advance(d)
    wait(lambda: js(d, "window.explorer.t") != s0, "the walk's time to move")
    assert not d.find_element("id", "walkmsg").is_displayed()
    ms = round(js(d, "window.explorer.firstFrameMs"), 1)
    record("design_click_to_first_frame_ms", ms)
    print(f"design click to first frame: {ms} ms (page), {wall_ms:.0f} ms (test's wall clock)")
    d.execute_script("window.scrollTo(0, 0);")
    wait(lambda: js(d, "window.scrollY") == 0, "the page scrolled to the top")
    frames_advance(d, 60)
    d.save_screenshot(os.path.join(RESULTS, "design.png"))
    # every uphill design (slope < 0: a passive walker loses energy at each impact and gains
    # none from gravity) has no gait; a click on it says so instead of animating
    uphill = np.flatnonzero(params[:, free.index("slope")] < 0)
    assert len(uphill) > 0, "the search tried no uphill slope"
    for k in uphill:
        assert words[status[k]] == "no gait"
        click_design(d, int(k))
        wait(lambda: text(d, "outcome") == f"{k}: no gait", "the no-gait design")
        assert d.find_element("id", "walkmsg").is_displayed()
        msg = text(d, "walkmsg")
        assert f"design {k} has no gait to walk (status no gait" in msg, msg
        assert js(d, "window.explorer.walk") is None
        assert text(d, "error") == ""
