"""The full build of the edited design in a background thread, through the Python API
(``fabrication.build(design).write(out)``), into the folder the user named.

:class:`BuildJob` reports every stage of :class:`~fabrication.progress.Progress` to a callback and
ends in ``done`` (the report's path) or ``failed`` (the one-line error a command line would print).
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any, Callable

from ..progress import Progress

STAGES = ("geometry", "quality", "support", "panels", "beams", "nesting", "verify")
"""The stages a build reports, in order (for the progress bar; an unknown stage keeps the bar where it is)."""


class _Relay(Progress):
    """A silent :class:`Progress` that passes each stage and note on to ``tell(text, fraction)``."""

    def __init__(self, tell: Callable[[str, float | None], None]):
        super().__init__(quiet=True)
        self.tell = tell

    def start(self, stage: str, detail: str = "") -> None:
        super().start(stage, detail)
        k = next((i for i, s in enumerate(STAGES) if stage.startswith(s)), None)
        self.tell(f"{stage} {detail}".strip(), None if k is None else k / len(STAGES))

    def note(self, text: str) -> None:
        super().note(text)
        self.tell(f"{self._stage}: {text}", None)


class BuildJob:
    """Build ``design`` into ``out`` in a thread; ``status`` is ``running``, ``done`` or ``failed``."""

    def __init__(self, design: Any, out: str | Path, tell: Callable[[str, float | None], None] | None = None):
        self.design = design
        self.out = Path(str(out).strip()).expanduser()
        self.tell = tell or (lambda text, fraction: None)
        self.status = "running"
        self.message = ""
        self.report: Path | None = None
        self.thread = threading.Thread(target=self._run, name="ppfab-studio-build", daemon=True)

    def start(self) -> "BuildJob":
        from .. import build  # noqa: F401  (fails early when the pipeline cannot load)
        from ..pipeline.folder import check_target

        check_target(self.out, protect=self.design.input_files())       # refuse before the work
        self.thread.start()
        return self

    def _run(self) -> None:
        from ppfab.errors import PpfabError

        from ..pipeline.lock import OutputLock
        from ..pipeline.stages import build

        try:
            with OutputLock(self.out):
                relay = _Relay(self.tell)
                result = build(self.design, progress=relay)
                self.tell("writing files", 0.95)
                out = result.write(self.out, progress=relay)
            report = Path(out) / "report.html"
            self.report = report if report.exists() else None
            self.status = "done"
            self.message = f"wrote {out}"
            self.tell(self.message, 1.0)
        except PpfabError as exc:
            self.status, self.message = "failed", f"ppfab: error: {exc}"
            self.tell(self.message, None)
        except OSError as exc:
            self.status, self.message = "failed", f"ppfab: error: {exc.filename or ''} {exc.strerror or exc}"
            self.tell(self.message, None)
        except Exception as exc:                                      # the studio keeps running
            self.status, self.message = "failed", f"ppfab: error: the build stopped: {type(exc).__name__}: {exc}"
            self.tell(self.message, None)

    def join(self, timeout: float | None = None) -> None:
        self.thread.join(timeout)


class Cancelled(Exception):
    """Raised inside the optimiser's callback to stop it."""


class OptimizeJob:
    """Optimise a mesh design's ``[optimize]`` in a thread (``ppfab.optimize.optimize``), telling every
    iteration; :meth:`cancel` stops it at the next iteration.  ``result`` is the
    :class:`~ppfab.optimize.OptimizeResult` when ``status`` is ``done``."""

    def __init__(self, mesh: Any, params: Any, tell: Callable[[str, float | None], None] | None = None,
                 on_done: Callable[["OptimizeJob"], None] | None = None):
        self.mesh, self.params = mesh, params
        self.tell = tell or (lambda text, fraction: None)
        self.on_done = on_done
        self.status = "running"
        self.message = ""
        self.result: Any = None
        self._cancel = threading.Event()
        self.thread = threading.Thread(target=self._run, name="ppfab-studio-optimize", daemon=True)

    def start(self) -> "OptimizeJob":
        self.thread.start()
        return self

    def cancel(self) -> None:
        self._cancel.set()

    def _callback(self, record: Any) -> None:
        if self._cancel.is_set():
            raise Cancelled()
        self.tell(f"iteration {record.iteration}, stage {record.stage}: max δ_f {record.delta_f_max:.2e}, "
                  f"max δ_P {record.delta_p_max:.2e}", None)

    def _run(self) -> None:
        from ppfab.errors import PpfabError
        from ppfab.optimize import optimize

        try:
            self.result = optimize(self.mesh, self.params, callback=self._callback)
            self.status = "done"
            self.message = f"optimised: {self.result.message}"
        except Cancelled:
            self.status, self.message = "cancelled", "optimisation cancelled"
        except PpfabError as exc:
            self.status, self.message = "failed", f"ppfab: error: {exc}"
        except Exception as exc:
            self.status, self.message = "failed", f"ppfab: error: the optimisation stopped: {type(exc).__name__}: {exc}"
        self.tell(self.message, 1.0 if self.status == "done" else None)
        if self.on_done is not None:
            self.on_done(self)

    def join(self, timeout: float | None = None) -> None:
        self.thread.join(timeout)
