"""``ppfab sweep``: variants of a tiny design on Dask (a real scheduler and workers, the local cluster), the
results table written per variant under the overwrite rule, reruns, failures, interruption and ``--best``."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import small_design

pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

from fabrication.cli import main  # noqa: E402
from fabrication.sweep.engine import run_sweep  # noqa: E402
from fabrication.sweep.spec import load_sweep  # noqa: E402
from fabrication.sweep.store import held_signals  # noqa: E402
from fabrication.sweep.variants import make_variants  # noqa: E402
from fabrication.sweep.worker import VariantTask, compute  # noqa: E402


def tiny_base() -> str:
    """A 3 × 2 PP vault of 2 m panels with a tenth of a second of nesting (about half a CPU second a build)."""
    return small_design(3, 2, u_range=(-3.0, 3.0), v_range=(-2.0, 2.0), name="tiny").replace(
        "time_budget = 0.5", "time_budget = 0.1")


def write_sweep(folder: Path, body: str, base: str | None = None) -> Path:
    (folder / "base.toml").write_text(base if base is not None else tiny_base())
    p = folder / "sweep.toml"
    p.write_text('[sweep]\nbase = "base.toml"\n' + body)
    return p


def read_rows(out: Path) -> list[dict]:
    import pyarrow.parquet as pq

    return list(pq.read_table(out / "results.parquet").to_pylist())


def csv_rows(out: Path) -> list[dict]:
    import csv

    with open(out / "results.csv", newline="") as fh:
        return list(csv.DictReader(fh))


GEOMETRY_SWEEP = """stage = "geometry"
[vary]
"geometry.params.faces_u" = [2, 3]
"panels.gap" = { from = 10.0, to = 20.0, step = 10.0 }
[cost]
panel_type = 100.0
"""


def local(spec_path: Path, out: Path, **kw):
    """The default local cluster, kept light: one worker thread in this process."""
    return run_sweep(load_sweep(spec_path), out, workers=1, processes=False, quiet=True, **kw)


# -- the local cluster, reruns, failures ----------------------------------------------------------------------
def test_local_cluster_sweep_writes_every_variant(tmp_path):
    import fabrication.sweep

    spec = write_sweep(tmp_path, GEOMETRY_SWEEP)
    out = tmp_path / "res"
    report = fabrication.sweep(spec, out, workers=1, processes=False)       # the module is the function
    rows = read_rows(out)
    assert (report.variants, report.computed, report.failed) == (4, 4, 0)
    assert sorted(r["index"] for r in rows) == [0, 1, 2, 3]
    assert len({r["variant"] for r in rows}) == 4
    assert all(r["status"] == "ok" for r in rows)
    # the varied values reached the designs: faces_u 2 → 2 × 2 panels, 3 → 3 × 2; cost = 100 per type
    for r in rows:
        assert r["panels"] == 2 * r["geometry.params.faces_u"]
        assert r["cost"] == pytest.approx(100.0 * r["panel_types"])
        assert r["glass_sheets"] is None                     # not measured at stage geometry
    # CSV holds the same rows; every design file is a ppfab design with the row's values
    assert [c["variant"] for c in csv_rows(out)] == [r["variant"] for r in rows]
    from fabrication.design import load_design

    for r in rows:
        d = load_design(out / r["design"])
        assert d.geometry.params["faces_u"] == r["geometry.params.faces_u"]
        assert d.panels.gap == r["panels.gap"]
    page = (out / "index.html").read_text()
    assert "plotly" in page and all(r["design"] in page for r in rows)
    assert len(page) > 1_000_000                             # plotly's JavaScript is in the page
    assert page.count("<select") == 2 and '<option value="panel_types"' in page      # the axes can be chosen
    assert '<option value="glass_sheets"' not in page                                # not measured here
    assert "<script src" not in page                         # the JavaScript is inlined: works offline


def test_rerun_computes_nothing_new(tmp_path):
    spec = write_sweep(tmp_path, GEOMETRY_SWEEP)
    out = tmp_path / "res"
    local(spec, out)
    before = {p.name: (p.read_bytes(), p.stat().st_mtime_ns) for p in out.iterdir() if p.is_file()}
    again = local(spec, out)
    assert (again.computed, again.skipped) == (0, 4)
    after = {p.name: (p.read_bytes(), p.stat().st_mtime_ns) for p in out.iterdir() if p.is_file()}
    assert after == before                                   # not one file rewritten
    # another Pareto plot: the page alone is written again
    assert main(["sweep", str(spec), "-o", str(out), "--quiet", "--pareto", "glass_area_m2", "cost"]) == 0
    assert (out / "results.parquet").read_bytes() == before["results.parquet"][0]
    assert "glass_area_m2 against cost" in (out / "index.html").read_text()
    # one more value: only the two new variants are computed
    spec.write_text(spec.read_text().replace("[2, 3]", "[2, 3, 4]"))
    more = local(spec, out)
    assert (more.computed, more.skipped) == (2, 4)
    assert len(read_rows(out)) == 6
    # another base design: new keys, every variant computed; the old rows stay in the table, not on the page
    (tmp_path / "base.toml").write_text(tiny_base().replace('name = "tiny"', 'name = "tiny 2"'))
    other = local(spec, out)
    assert (other.computed, len(other.rows), len(read_rows(out))) == (6, 6, 12)
    assert "also holds 6 variant(s) of earlier sweeps" in (out / "index.html").read_text()


def test_bad_value_fails_alone_with_its_message(tmp_path):
    spec = write_sweep(tmp_path, 'stage = "geometry"\n[vary]\n"panels.gap" = [10.0, -5.0, 20.0]\n')
    out = tmp_path / "res"
    report = local(spec, out)
    rows = {r["panels.gap"]: r for r in read_rows(out)}
    assert report.failed == 1 and len(rows) == 3
    assert rows[10.0]["status"] == rows[20.0]["status"] == "ok"
    bad = rows[-5.0]
    assert bad["status"] == "failed" and "panels.gap" in bad["reason"] and "\n" not in bad["reason"]
    assert bad["panels"] is None
    # the command line exits 0 when some variants were built; a rerun does not try the failed one again
    assert main(["sweep", str(spec), "-o", str(out), "--quiet"]) == 0
    assert len(read_rows(out)) == 3
    again = local(spec, out, retry_failed=True)              # only the failed one is tried again
    assert (again.computed, again.failed) == (1, 1)
    # only failures: exit 1
    spec.write_text(spec.read_text().replace("[10.0, -5.0, 20.0]", "[-5.0, -6.0]"))
    assert main(["sweep", str(spec), "-o", str(tmp_path / "res2"), "--quiet"]) == 1


def test_interrupted_sweep_leaves_a_consistent_table(tmp_path):
    spec = write_sweep(tmp_path, GEOMETRY_SWEEP)
    out = tmp_path / "res"
    seen = []

    def stop_after_two(row: dict) -> None:
        seen.append(row["variant"])
        if len(seen) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        local(spec, out, on_row=stop_after_two)
    rows = read_rows(out)
    assert [r["variant"] for r in rows] == sorted(seen, key=lambda k: [r["variant"] for r in rows].index(k))
    assert len(rows) == 2 and len(csv_rows(out)) == 2
    rest = local(spec, out)
    assert (rest.computed, rest.skipped) == (2, 2) and len(read_rows(out)) == 4


def test_signal_is_held_during_a_commit_and_delivered_after():
    """Delivered after, to the handler in place: here Python's own (a test process may have inherited another
    SIGINT disposition from whatever started it, so the test sets the default one for its duration)."""
    got = []
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            with held_signals():
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.05)
                got.append("inside")                             # not interrupted here
    finally:
        signal.signal(signal.SIGINT, before)
    assert got == ["inside"]


# -- file safety ----------------------------------------------------------------------------------------------
def test_refuses_a_folder_ppfab_did_not_write(tmp_path, capsys):
    spec = write_sweep(tmp_path, GEOMETRY_SWEEP)
    out = tmp_path / "theirs"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert main(["sweep", str(spec), "-o", str(out), "--quiet"]) == 2
    assert "not a ppfab sweep folder" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]


def test_refuses_a_results_file_changed_since(tmp_path, capsys):
    spec = write_sweep(tmp_path, GEOMETRY_SWEEP)
    out = tmp_path / "res"
    local(spec, out)
    edited = (out / "results.csv").read_text() + "my note\n"
    (out / "results.csv").write_text(edited)
    spec.write_text(spec.read_text().replace("[2, 3]", "[2, 3, 4]"))
    assert main(["sweep", str(spec), "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "results.csv" in err and "changed" in err and len(err.strip().splitlines()) == 1
    assert (out / "results.csv").read_text() == edited
    assert len(read_rows(out)) == 4


def test_best_writes_the_best_design(tmp_path):
    spec = write_sweep(tmp_path, GEOMETRY_SWEEP)
    out = tmp_path / "res"
    assert main(["sweep", str(spec), "-o", str(out), "--quiet", "--best", "glass_area_m2"]) == 0
    rows = [r for r in read_rows(out) if r["status"] == "ok"]
    best = min(rows, key=lambda r: r["glass_area_m2"])
    from fabrication.design import load_design

    d = load_design(out / "best-glass_area_m2.toml")
    assert (d.geometry.params["faces_u"], d.panels.gap) == (best["geometry.params.faces_u"], best["panels.gap"])
    # --best-out onto a file ppfab did not write: refused, untouched
    mine = tmp_path / "mine.toml"
    mine.write_text("# my design\n")
    assert main(["sweep", str(spec), "-o", str(out), "--quiet", "--best", "cost", "--best-out", str(mine)]) == 2
    assert mine.read_text() == "# my design\n"
    # a figure not measured at this stage
    assert main(["sweep", str(spec), "-o", str(out), "--quiet", "--best", "glass_sheets"]) == 2


# -- the sweep file -------------------------------------------------------------------------------------------
@pytest.mark.parametrize("body, key", [
    ('[vary]\n"panels.gap" = [1.0]\n[cost]\nglass = 3.0\n', "cost.glass"),
    ('sample = "zip"\n[vary]\n"panels.gap" = [1.0, 2.0]\n"beams.depth" = [100.0]\n', "vary"),
    ('[vary]\n"beams.depth" = { min = 100.0, max = 200.0 }\n', "vary.beams.depth"),
    ('stage = "geometry"\npareto = ["glass_sheets", "cost"]\n[vary]\n"panels.gap" = [1.0]\n', "sweep.pareto"),
    ('[vary]\n', "vary"),
    ('stage = "everything"\n[vary]\n"panels.gap" = [1.0]\n', "sweep.stage"),
])
def test_bad_sweep_file_is_refused_in_one_line(tmp_path, capsys, body, key):
    spec = write_sweep(tmp_path, body)
    assert main(["sweep", str(spec), "-o", str(tmp_path / "res"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"ppfab: error: {key}:") and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "res").exists()


def test_latin_hypercube_is_stratified_and_seeded(tmp_path):
    spec = write_sweep(tmp_path, 'sample = "lhs"\nsamples = 10\nseed = 3\n[vary]\n'
                                 '"beams.depth" = { min = 100.0, max = 200.0 }\n'
                                 '"geometry.params.faces_u" = { min = 2, max = 11 }\n')
    s = load_sweep(spec)
    a, b = make_variants(s), make_variants(s)
    assert [v.key for v in a] == [v.key for v in b] and len(a) == 10
    depth = sorted(v.values["beams.depth"] for v in a)
    assert [int((d - 100.0) // 10.0) for d in depth] == list(range(10))     # one value in each tenth
    faces = sorted(v.values["geometry.params.faces_u"] for v in a)
    assert faces == list(range(2, 12))                                       # integers, each once


def test_grid_and_zip_counts(tmp_path):
    spec = write_sweep(tmp_path, '[vary]\n"panels.gap" = { from = 10.0, to = 20.0, count = 3 }\n'
                                 '"beams.joint" = ["halflap", "segmented"]\n')
    assert len(make_variants(load_sweep(spec))) == 6
    spec = write_sweep(tmp_path, 'sample = "zip"\n[vary]\npanels.gap = [10.0, 20.0]\nbeams.depth = [150, 160]\n')
    vs = make_variants(load_sweep(spec))
    assert [(v.values["panels.gap"], v.values["beams.depth"]) for v in vs] == [(10.0, 150), (20.0, 160)]


# -- a real Dask scheduler and two workers, one killed during the run ---------------------------------------------
def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def wait_for_workers(address: str, n: int, timeout: float = 120.0) -> None:
    from distributed import Client

    with Client(address, timeout="30s") as c:
        c.wait_for_workers(n, timeout=timeout)


@pytest.mark.slow
def test_scheduler_and_workers_survive_a_killed_worker(tmp_path):
    spec = write_sweep(tmp_path, 'stage = "nesting"\n[vary]\n"panels.gap" = [10.0, 14.0, 18.0, 22.0]\n'
                                 '"beams.depth" = [150.0, 170.0, 190.0]\n')
    out = tmp_path / "res"
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = {**os.environ, "PYTHONWARNINGS": "ignore"}
    dask = [sys.executable, "-m", "dask"]
    procs: list[subprocess.Popen] = []
    log = open(tmp_path / "cluster.log", "wb")
    try:
        procs.append(subprocess.Popen(dask + ["scheduler", "--host", "127.0.0.1", "--port", str(port),
                                              "--no-dashboard"], stdout=log, stderr=log, env=env))
        for _ in range(2):
            procs.append(subprocess.Popen(dask + ["worker", address, "--nthreads", "1", "--no-nanny",
                                                  "--no-dashboard", "--host", "127.0.0.1"],
                                          stdout=log, stderr=log, env=env, cwd=tmp_path))
        wait_for_workers(address, 2)
        sweep = subprocess.Popen([sys.executable, "-m", "fabrication.cli", "sweep", str(spec), "-o", str(out),
                                  "--scheduler", address, "--quiet"], stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, env=env)
        procs.append(sweep)
        killed, in_flight = None, []
        deadline = time.monotonic() + 300
        from distributed import Client

        with Client(address, timeout="30s") as watcher:
            while killed is None and sweep.poll() is None and time.monotonic() < deadline:
                time.sleep(0.05)
                if not (out / "results.parquet").exists():
                    continue
                # once the first row is written: kill a worker that holds a variant at this moment
                busy = {w: keys for w, keys in watcher.processing().items() if keys}
                if not busy:
                    continue
                addr, keys = next(iter(busy.items()))
                pid = watcher.run(os.getpid, workers=[addr])[addr]
                victim = next(p for p in procs[1:3] if p.pid == pid)
                victim.send_signal(signal.SIGKILL)
                killed, in_flight = pid, [str(k).removeprefix("ppfab-variant-") for k in keys]
        _, err = sweep.communicate(timeout=600)
        assert sweep.returncode == 0, err.decode()
        assert killed is not None, "the sweep finished before a worker could be killed"
    finally:
        for p in reversed(procs):
            if p.poll() is None:
                p.terminate()
        for p in procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
        log.close()
    rows = read_rows(out)
    variants = make_variants(load_sweep(spec))
    assert sorted(r["variant"] for r in rows) == sorted(v.key for v in variants)    # each once
    assert all(r["status"] == "ok" for r in rows), [r["reason"] for r in rows]
    survivors = {r["worker"] for r in rows if not r["worker"].endswith(f":{killed}")}
    assert len(survivors) == 1                                # the rest ran on the worker left
    assert in_flight                                          # the variants the killed worker held …
    for key in in_flight:                                     # … were run again by the scheduler, elsewhere
        assert next(r for r in rows if r["variant"] == key)["worker"] in survivors
    base_dir = str(tmp_path)
    for v in variants:
        alone = compute(VariantTask(v.key, v.index, v.doc, "nesting", base_dir))
        row = next(r for r in rows if r["variant"] == v.key)
        for name, value in alone.items():
            assert row[name] == pytest.approx(value, rel=1e-12, abs=1e-9), (v.values, name)


@pytest.mark.slow
def test_files_stage_writes_a_verified_build_per_variant(tmp_path):
    from fabrication.verify import verify

    spec = write_sweep(tmp_path, 'stage = "files"\n[vary]\n"panels.gap" = [12.0]\n')
    out = tmp_path / "res"
    report = local(spec, out)
    (row,) = read_rows(out)
    assert report.computed == 1 and row["status"] == "ok", row["reason"]
    build = out / "builds" / row["variant"]
    assert row["report"] == f"builds/{row['variant']}/report.html" and (out / row["report"]).is_file()
    assert verify(build).ok
    assert row["report"] in (out / "index.html").read_text()


@pytest.mark.slow
def _default_sigint() -> None:
    """In the child before it runs Python: SIGINT as a terminal gives it.  A test worker may run with SIGINT
    ignored, and a Python started with it ignored never raises KeyboardInterrupt (the sweep then ran all 12
    variants through the Ctrl-C and exited 0 in one run of the suite)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_ctrl_c_on_the_command_line_leaves_a_consistent_table(tmp_path):
    spec = write_sweep(tmp_path, 'stage = "nesting"\n[vary]\n"panels.gap" = [10.0, 12.0, 14.0, 16.0, 18.0, 20.0]\n'
                                 '"beams.depth" = [150.0, 170.0]\n')
    out = tmp_path / "res"
    sweep = subprocess.Popen([sys.executable, "-m", "fabrication.cli", "sweep", str(spec), "-o", str(out),
                              "--workers", "1", "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             start_new_session=True, preexec_fn=_default_sigint)
    try:
        deadline = time.monotonic() + 300
        while sweep.poll() is None and time.monotonic() < deadline and not (out / "results.csv").exists():
            time.sleep(0.05)
        sweep.send_signal(signal.SIGINT)
        _, err = sweep.communicate(timeout=120)
    finally:
        if sweep.poll() is None:
            os.killpg(sweep.pid, signal.SIGKILL)
            sweep.wait()
    assert sweep.returncode == 130, err.decode()
    assert "interrupted" in err.decode() and "Traceback" not in err.decode()
    rows = read_rows(out)
    assert 1 <= len(rows) < 12
    assert [c["variant"] for c in csv_rows(out)] == [r["variant"] for r in rows]
    assert not [p for p in out.iterdir() if ".tmp-" in p.name]
    again = run_sweep(load_sweep(spec), out, workers=1, processes=False, quiet=True)
    assert again.computed == 12 - len(rows) and len(read_rows(out)) == 12


def test_unreachable_scheduler_is_one_line(tmp_path):
    from fabrication.sweep.engine import SchedulerError

    spec = write_sweep(tmp_path, GEOMETRY_SWEEP)
    address = f"tcp://127.0.0.1:{free_port()}"
    with pytest.raises(SchedulerError) as err:
        run_sweep(load_sweep(spec), tmp_path / "res", scheduler=address, quiet=True, connect_timeout=2.0)
    assert str(err.value).startswith(f"cannot reach the Dask scheduler at {address}") and "\n" not in str(err.value)
    assert err.value.exit_code == 2
    assert not (tmp_path / "res" / "results.parquet").exists()


def test_a_second_sweep_into_the_same_folder_is_refused(tmp_path):
    from fabrication.pipeline.lock import OutputLock

    spec = write_sweep(tmp_path, GEOMETRY_SWEEP)
    out = tmp_path / "res"
    with OutputLock(out):                                    # what a running sweep holds
        other = subprocess.run([sys.executable, "-m", "fabrication.cli", "sweep", str(spec), "-o", str(out),
                                "--quiet"], capture_output=True, text=True, timeout=300)
    assert other.returncode != 0 and str(os.getpid()) in other.stderr, other.stderr
    assert len(other.stderr.strip().splitlines()) == 1
    assert not (out / "results.parquet").exists()


def test_index_html_plot_in_a_browser(tmp_path):
    """In a real headless Chromium (skipped without it): the page draws the front offline, a menu redraws it
    for another pair of figures, and a point carries its design file's link."""
    import shutil

    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    if not (chromium and driver):
        pytest.skip("needs Debian's chromium and chromium-driver (.ci/run installs them)")
    webdriver = pytest.importorskip("selenium.webdriver")
    from selenium.webdriver.chrome.service import Service

    spec = write_sweep(tmp_path, GEOMETRY_SWEEP)
    out = tmp_path / "res"
    local(spec, out)
    rows = read_rows(out)
    o = webdriver.ChromeOptions()
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"):
        o.add_argument(a)
    o.binary_location = chromium
    d = webdriver.Chrome(service=Service(driver), options=o)
    try:
        d.get((out / "index.html").as_uri())
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and not d.execute_script(
                "var g = document.getElementById('pareto'); return !!(g && g.data);"):
            time.sleep(0.1)
        shown = d.execute_script("var g = document.getElementById('pareto');"
                                 "return g.data[0].x.length + g.data[1].x.length;")
        assert shown == len(rows)
        d.execute_script("var s = document.getElementById('pareto-x'); s.value = 'glass_area_m2';"
                         "s.dispatchEvent(new Event('change'));")
        x, title, links = d.execute_script("var g = document.getElementById('pareto');"
                                           "return [g.data[0].x.concat(g.data[1].x), g.layout.xaxis.title.text,"
                                           " g.data[0].customdata.concat(g.data[1].customdata)];")
        assert title == "glass_area_m2"
        assert sorted(x) == pytest.approx(sorted(r["glass_area_m2"] for r in rows))
        assert sorted(links) == sorted(r["design"] for r in rows)
        assert d.get_log("browser") == []
    finally:
        d.quit()
