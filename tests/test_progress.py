"""The progress display: every stage reports what it has done (nesting by budget spent and sheets, files by
file sets and files written, optimisation by iteration and δ), a keep-alive fills any gap, no library warning
reaches the terminal, ``--quiet`` and ``--json`` stay quiet, and no stage line carries a stray ``;``."""

from __future__ import annotations

import io
import json
import time
import tomllib
import warnings

import pytest

from fabrication.cli import main
from fabrication.progress import Event, Progress

from conftest import small_design


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """A tiny build with its progress on a captured stream, the events recorded by a hook."""
    from fabrication import build, parse_design

    out = tmp_path_factory.mktemp("progress") / "out"
    stream = io.StringIO()
    p = Progress(stream=stream, interval=0.3, tick=0.1)
    seen: list[Event] = []
    p.hooks.append(seen.append)
    design = parse_design(tomllib.loads(small_design(faces_u=4, faces_v=3)))
    with warnings.catch_warnings(record=True):
        b = build(design, progress=p)
        b.write(out, progress=p)
    return p, seen, stream.getvalue()


def test_every_stage_starts_and_ends_and_the_hook_sees_every_event(run):
    p, seen, _ = run
    assert seen == p.events
    starts = [e.stage for e in p.events if e.kind == "start"]
    dones = [e.stage for e in p.events if e.kind == "done"]
    assert starts == dones and {"geometry", "nesting", "step", "dxf", "report", "verify"} <= set(starts)
    assert all(b.t >= a.t for a, b in zip(p.events, p.events[1:]))


def test_nesting_reports_budget_spent_and_sheets(run):
    p, _, _ = run
    adv = [e for e in p.events if e.stage == "nesting" and e.kind == "advance"]
    glass = [e for e in adv if e.text.startswith("glass")]
    plates = [e for e in adv if e.text.startswith("plates")]
    for part in (glass, plates):
        assert len(part) >= 20                              # about every 1/200 of the budget
        done = [e.done for e in part]
        assert done == sorted(done) and done[-1] == part[-1].total == pytest.approx(0.5)
        assert "sheets" in part[-1].text


def test_file_writers_report_their_sets_in_order(run):
    p, _, _ = run
    adv = [e for e in p.events if e.kind == "advance" and e.text.startswith("file set")]
    assert [e.done for e in adv] == list(range(len(adv))) and len(adv) >= 8
    assert adv[-1].text == f"file set {len(adv)} of {len(adv)}"


def test_long_stages_are_kept_alive(run):
    """A stage of this process longer than a few intervals shows keep-alives between its reports, counted rather
    than timed (a call into the CAD kernel or rhino3dm holds the interpreter lock and delays the ticker)."""
    p, _, _ = run
    # a writer of the second process is reported whole when it is joined (start and done at once, with the
    # child's wall time); this process kept reporting its own stages meanwhile
    elsewhere = {e.stage for e in p.events if e.kind == "start" and "second process" in e.text}
    long = {s: t for s, t in p.times.items() if t > 3 * (p.interval + p.tick) and s not in elsewhere}
    quiet = 0                                   # long stages with fewer than two reports of their own
    for stage, seconds in long.items():
        own = [e for e in p.events if e.stage == stage and e.kind in ("advance", "update")]
        ticks = [e for e in p.events if e.stage == stage and e.kind == "tick"]
        # a stage that reports often (nesting: every 1/200 of its budget) needs no keep-alive between reports
        assert len(own) >= 2 or len(ticks) >= 1, (stage, seconds, len(own), len(ticks))
        quiet += len(own) < 2
    assert sum(e.kind == "tick" for e in p.events) >= quiet


def test_stage_lines_are_clean(run):
    _, _, text = run
    lines = [ln for ln in text.splitlines() if ln.startswith("[ppfab]")]
    assert len(lines) >= 15
    for ln in lines:
        assert ";  " not in ln and not ln.rstrip().endswith(";") and "; (" not in ln
    nesting = next(ln for ln in text.splitlines() if "bound" in ln and "plates:" in ln)
    assert "); plates:" in nesting


def test_optimisation_reports_iterations_and_delta():
    import numpy as np

    from ppfab.io import load_mesh
    from ppfab.optimize import optimize

    from conftest import shared_file

    stream = io.StringIO()
    p = Progress(stream=stream, interval=0.0)
    p.start("geometry")
    optimize(load_mesh(shared_file("compas_libigl__tubemesh.off")), {"families": "rows"}, callback=p.iteration)
    p.done("ok")
    its = [e for e in p.events if e.kind == "update"]
    assert len(its) >= 3 and [e.done for e in its] == sorted(e.done for e in its)
    assert all("max δ_f" in e.text and "max δ_P" in e.text for e in its)
    assert np.isfinite([float(e.text.split("max δ_f ")[1].split(",")[0]) for e in its]).all()


def test_library_warnings_go_to_the_log_not_the_terminal(tmp_path, capsys, monkeypatch):
    """A warning raised inside a build (as matplotlib's overflow warnings were) does not reach stderr."""
    import fabrication.pipeline.stages as stages

    real = stages.stage_quality

    def noisy(*a, **k):
        warnings.warn("overflow encountered in multiply", RuntimeWarning)
        warnings.warn("Attempting to set identical low and high xlims", UserWarning)
        return real(*a, **k)

    monkeypatch.setattr(stages, "stage_quality", noisy)
    design = tmp_path / "d.toml"
    design.write_text(small_design(faces_u=3, faces_v=3), encoding="utf-8")
    assert main(["build", str(design), "-o", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    assert "Warning" not in err and "warn(" not in err
    assert "[ppfab] nesting" in err


def test_quiet_and_json_print_no_progress(tmp_path, capsys):
    design = tmp_path / "d.toml"
    design.write_text(small_design(faces_u=3, faces_v=3), encoding="utf-8")
    assert main(["build", str(design), "-o", str(tmp_path / "q"), "--quiet"]) == 0
    cap = capsys.readouterr()
    assert cap.err == "" and cap.out == ""
    assert main(["build", str(design), "-o", str(tmp_path / "j"), "--json"]) == 0
    cap = capsys.readouterr()
    assert cap.err == "" and json.loads(cap.out)["summary"]["panels"] == 9


def test_a_terminal_gets_a_bar_with_the_time_left():
    class Tty(io.StringIO):
        def isatty(self):
            return True

    s = Tty()
    p = Progress(stream=s, tick=0.05)
    p.start("nesting")
    for k in range(1, 5):
        p.advance(k, 10, "glass, 9 parts: best 2 sheets")
        time.sleep(0.06)
    p.done("glass: 2 sheets")
    text = s.getvalue()
    assert "%|" in text and "<" in text and "glass, 9 parts: best 2 sheets" in text     # bar, time left, status
    assert text.rstrip().endswith("glass: 2 sheets (" + text.rstrip().rsplit("(", 1)[1])


def test_a_log_has_whole_lines_with_the_count_and_time_left_of_verify(run):
    """In a log every line is whole: verify's status lines carry how many checks of all are done and the time
    left, nothing is written into the middle of a stage line, and each stage ends in a line that starts with
    its header and carries its summary."""
    import re

    p, _, text = run
    lines = text.splitlines()
    status = [ln for ln in lines if ln.startswith("  verify: ")]
    assert status, text
    assert all(re.match(r"  verify: \d+ of \d+ checks, ", ln) for ln in status), status
    assert any("s left)" in ln for ln in status), status
    assert not any("verify: " in ln and not ln.startswith("  verify: ") for ln in lines)
    summaries = [ln for ln in lines if ln.startswith("[ppfab] ") and re.search(r"\(\d+\.\d s\)$", ln)]
    for stage in ("geometry", "nesting", "step", "dxf", "report", "verify"):
        assert any(ln.startswith(f"[ppfab] {stage:<10}") for ln in summaries), (stage, text)


def test_a_warning_during_a_stage_gets_a_line_of_its_own():
    """A warning logged while a stage line is open is printed on its own line, in a log and on a terminal
    alike, and the stage's summary line still starts with its header."""
    import logging

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    logger = logging.getLogger("ppfab.test")       # its own level: earlier tests may have quietened "ppfab"
    level, disabled = logger.level, logging.root.manager.disable
    logger.setLevel(logging.WARNING)
    logging.disable(logging.NOTSET)
    try:
        for stream, bar in ((io.StringIO(), False), (Terminal(), False)):
            p = Progress(stream=stream, tick=0.0, bar=bar)
            with p.logs_here():
                p.start("beams", "10 plates")
                logger.warning("B-U01: a warning about one plate")
                p.done("10 plates, 2 slots")
            lines = stream.getvalue().replace("\r\033[K", "\n").splitlines()
            assert "B-U01: a warning about one plate" in lines, lines
            assert lines[-1].startswith("[ppfab] beams") and lines[-1].endswith("10 plates, 2 slots (0.0 s)"), lines
    finally:
        logger.setLevel(level)
        logging.disable(disabled)
    assert logging.getLogger("ppfab").propagate and not logging.getLogger("ppfab").handlers
