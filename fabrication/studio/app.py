"""The browser interface of ``ppfab studio`` on viser (a 3D scene, GUI controls and transform gizmos served
from one Python process; its web client ships in the wheel, so nothing is fetched at run time).

:class:`Studio` draws the :class:`~fabrication.studio.model.StudioModel`: the panels coloured by a metric, the
beams of the planar families as light strips along the node axes, the node axes, and one gizmo per handle;
beside the view the construction's parameters (a control for every number), the handles' numbers, undo/redo,
the live figures, save and build.  Every callback catches what a user can get wrong and shows it as one line;
the server keeps running.  Only the loopback address is bound unless ``host`` says otherwise.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import threading
import time
import typing
from pathlib import Path
from typing import Any

import numpy as np

from .figures import face_corners
from .model import METRICS, StudioModel, face_metric
from .gizmos import draw_handles, move_handles
from .scene import FOLD_RGB, legend_html, quat_matrix, ramp
from .table_editor import TableEditor, is_table
from .values import field_value, parse_list, plain

log = logging.getLogger("ppfab")

SEND_PAUSE = 0.003
"""Seconds a redraw yields (Python's GIL) after the status and figures, so the server's event loop sends them
before the scene's messages are built: the figures reach the page first (``benchmarks/studio_latency.py``)."""


class Studio:
    """The running studio (see the module docstring): ``server`` is the viser server, ``model`` the state."""

    def __init__(self, model: StudioModel, host: str = "127.0.0.1", port: int = 8080, design_path: str = ""):
        import viser

        from .guard import Gate, guarded_server, new_key

        self.model = model
        self.lock = threading.RLock()
        self.metric = "panel area"
        self.job: Any = None
        self.opt_job: Any = None
        self.gate = Gate(new_key(), host)
        self.server: Any = guarded_server(self.gate, lambda: viser.ViserServer(host=host, port=port, verbose=False),
                                          lambda server: server.stop())
        self.server.gui.configure_theme(control_width="large", dark_mode=False, show_logo=False,
                                        show_share_button=False)
        setattr(self.server, "request_share_url", _no_share)  # a page may not open a public tunnel to the studio
        self.server.scene.set_up_direction("+z")
        # no environment map (its images would be fetched from the network): plain lights only
        self.server.scene.configure_environment_map(None)
        self.server.scene.configure_default_lights(True, cast_shadow=False)
        self._syncing = False
        self._handles: dict[str, Any] = {}
        self._items: dict[str, Any] = {}
        self._controls: dict[str, tuple[Any, str]] = {}
        self.field_message: Any = None          # the refusal shown right under the field that was refused
        self.redraws = 0
        self._build_gui(design_path)
        self.server.on_client_connect(self._frame_camera)
        self._rebuild_param_controls()
        self.redraw(handles=True)

    # -- GUI ------------------------------------------------------------------------------------------
    def _build_gui(self, design_path: str) -> None:
        gui: Any = self.server.gui
        name = self.model.method or f"mesh {self.model.geometry.get('mesh')}"
        gui.add_markdown(f"**ppfab studio** — {name}")
        outside = self.model.outside_files()
        self.outside_note: Any = None
        if outside:
            listed = ", ".join(f"`{p}`" for p in outside)
            self.outside_note = gui.add_markdown(f"**this design reads files outside its folder:** {listed}")
        self.status = gui.add_markdown("")
        self.figures = gui.add_markdown("")
        with gui.add_folder("View"):
            self.metric_dd = gui.add_dropdown("colour by", METRICS, initial_value=self.metric)
            self.metric_dd.on_update(lambda _: self._guard(self._set_metric))
            self.legend = gui.add_html("")
            self.show_beams = gui.add_checkbox("beams", True)
            self.show_axes = gui.add_checkbox("node axes", True)
            for cb in (self.show_beams, self.show_axes):
                cb.on_update(lambda _: self._guard(lambda: self.redraw(handles=False)))
        with gui.add_folder("Edit"):
            undo = gui.add_button("Undo")
            redo = gui.add_button("Redo")
            undo.on_click(lambda _: self._guard(lambda: self._history(self.model.undo)))
            redo.on_click(lambda _: self._guard(lambda: self._history(self.model.redo)))
        self.params_folder = gui.add_folder("Parameters")
        self.live: Any = None
        if self.model.method is None and "optimize" in self.model.doc:
            with gui.add_folder("Optimise ([optimize])"):
                run = gui.add_button("Optimise")
                stop = gui.add_button("Cancel")
                run.on_click(lambda _: self._guard(self._optimize))
                stop.on_click(lambda _: self._guard(self._cancel_optimize))
                self.opt_msg = gui.add_markdown("")
                from .live_panel import LivePanel

                self.live = LivePanel(self)
        with gui.add_folder("Save and build"):
            default = str(Path(design_path).with_name(Path(design_path).stem + "_edited.toml")) if design_path else ""
            self.save_path = gui.add_text("save as", default)
            self.save_path.on_update(lambda _: self._guard(self._check_target))
            self.replace_box = gui.add_checkbox("replace the existing file", False, visible=False,
                                                hint="the file named in 'save as' exists and this studio did "
                                                     "not write it; tick to overwrite it")
            self.replace_box.on_update(lambda _: self._guard(self._confirm_replace))
            self.save_note = gui.add_markdown("")
            self._replace_for: str | None = None
            save = gui.add_button("Save")
            save.on_click(lambda _: self._guard(self._save))
            self.out_path = gui.add_text("build folder", "")
            build = gui.add_button("Build")
            build.on_click(lambda _: self._guard(self._build))
            self.progress = gui.add_progress_bar(0.0, visible=False)
            self.open_report = gui.add_button("Open report", visible=False)
            self.open_report.on_click(lambda _: self._guard(self._show_report))
            self.build_msg = gui.add_markdown("")
        self._guard(self._check_target)

    def _field_types(self) -> dict[str, Any]:
        from ppfab.constructions import get_construction

        if self.model.method is None:
            return {}
        cls = get_construction(self.model.method).params
        hints = typing.get_type_hints(cls)
        return {f.name: (hints[f.name], f.metadata) for f in dataclasses.fields(cls)}

    def _rebuild_param_controls(self) -> None:
        """One control per parameter: a slider for an integer (resolution), a number for a float, a vector
        for a short list, text (JSON) for a nested list; then the handle set's numbers and the placement."""
        gui: Any = self.server.gui
        for handle, _ in self._controls.values():
            handle.remove()
        self._controls = {}
        params = self.model.params
        with self.params_folder:
            for key, (tp, meta) in self._field_types().items():
                value = params.get(key)
                if value is None:
                    continue
                self._controls[key] = (self._control(key, tp, meta, value), key)
            from .handles import handle_set

            for k, sc in enumerate(handle_set(self.model.method).scalars(params)):
                h = gui.add_number(sc.label, sc.get(params), step=0.01)
                h.on_update(lambda e, sc=sc, k=k: self._guard(lambda: self._scalar(sc, float(e.target.value)),
                                                              field=f"#scalar{k}"))
                self._controls[f"#scalar{k}"] = (h, f"#scalar{k}")
            geo = self.model.geometry
            for key, make in (("geometry.scale", lambda: gui.add_number("scale", float(geo.get("scale", 1.0)))),
                              ("geometry.rotate_z_deg", lambda: gui.add_slider(
                                  "rotate_z_deg", -180.0, 180.0, 1.0, float(geo.get("rotate_z_deg", 0.0))))):
                h = make()
                h.on_update(lambda e, key=key: self._guard(lambda: self._set(key, e.target.value), field=key))
                self._controls[key] = (h, key)

    def _control(self, key: str, tp: Any, meta: Any, value: Any) -> Any:
        gui: Any = self.server.gui
        hint = str(meta.get("doc", "")) or None
        if tp is bool:
            h = gui.add_checkbox(key, bool(value), hint=hint)
        elif tp is int:
            lo = int(meta.get("min", 0))
            hi = int(min(meta.get("max", 200), max(200, 2 * int(value))))
            h = gui.add_slider(key, lo, hi, 1, int(value), hint=hint)
        elif tp is float:
            h = gui.add_number(key, float(value), step=0.001, hint=hint)
        elif tp is str:
            choices = meta.get("choices")
            h = gui.add_dropdown(key, list(choices), initial_value=value, hint=hint) if choices else \
                gui.add_text(key, str(value), hint=hint)
        elif isinstance(value, list) and len(value) in (2, 3) and all(isinstance(x, (int, float)) for x in value):
            add = gui.add_vector2 if len(value) == 2 else gui.add_vector3
            h = add(key, tuple(float(x) for x in value), step=0.01, hint=hint)
        elif is_table(value):                  # a nested list of numbers: one line of fields per row
            def apply(make: Any, key: str = key) -> None:
                self._apply_table(key, make)
            return TableEditor(gui, key, value, hint, apply, lambda: self._syncing)
        else:
            h = gui.add_text(key, json.dumps(value), multiline=False, hint=hint)

            def on_text(e: Any, key: str = key) -> None:
                self._guard(lambda: self._set(key, parse_list(str(e.target.value), key)), field=key)
            h.on_update(on_text)
            return h
        h.on_update(lambda e, key=key: self._guard(lambda: self._set(key, plain(e.target.value)), field=key))
        return h

    def _sync_controls(self) -> None:
        """Show the model's values in the controls (after undo/redo or a handle drag); a table whose rows
        changed is drawn anew (all controls are)."""
        params = self.model.params
        self._syncing = True
        try:
            for key, (h, _) in self._controls.items():
                if key.startswith("#"):
                    continue
                value = self.model.geometry.get(key.split(".", 1)[1]) if key.startswith("geometry.") else params.get(key)
                if value is None:
                    continue
                if isinstance(h, TableEditor):
                    if not h.sync(value):
                        self._syncing = False
                        self._rebuild_param_controls()
                        return
                    continue
                if isinstance(h.value, str) and not isinstance(value, str):
                    value = json.dumps(value)
                elif isinstance(h.value, tuple):
                    value = tuple(value)
                if h.value != value:
                    h.value = value
        finally:
            self._syncing = False

    # -- callbacks ------------------------------------------------------------------------------------
    def _guard(self, fn: Any, field: str = "") -> None:
        """Run a callback; any error a user can cause becomes the status line, the server keeps running.

        ``field``: the control whose edit runs ``fn``.  When the edit is refused, every control shows the model's
        value again (the refused value does not stay in its field as if applied) and the reason is shown right
        under that field, where the user looks, until the next edit is applied."""
        if self._syncing:
            return
        with self.lock:
            try:
                fn()
            except Exception as exc:                # the message is the user's: never a traceback
                log.info("studio: %s", exc, exc_info=True)
                self.model.error = str(exc)
                self._sync_controls()
                self._show_field_message(field, str(exc))
                self._show_status()
            else:
                if field:
                    self._show_field_message("", "")

    def _show_field_message(self, field: str, text: str) -> None:
        """Show ``text`` under the control ``field`` (remove the message when ``field`` is empty)."""
        if self.field_message is not None:
            self.field_message.remove()
            self.field_message = None
        control = self._controls.get(field)
        if not field or not text or control is None:
            return
        handle = control[0]
        shown = field_value(handle.value)
        with self.params_folder:
            self.field_message = self.server.gui.add_markdown(
                f"**not applied:** {text} — {field.removeprefix('geometry.')} stays {shown}",
                order=float(handle.order) + 1e-6)

    def _set(self, key: str, value: Any) -> None:
        if isinstance(value, float) and not np.isfinite(value):
            raise ValueError(f"{key.removeprefix('geometry.')}: {value} is not a number; type a number")
        applied = self.model.set_param(key, value)
        self.redraw(handles=True)
        if not applied:                        # refused by the model: its reason goes under the field
            raise ValueError(self.model.error)

    def _apply_table(self, key: str, make: Any) -> None:
        """A table editor's edit: set ``make()`` (guarded; a refusal reverts the fields), then show the model's
        value in every control (a table that gained or lost a row is drawn anew)."""
        def edit() -> None:
            self._set(key, make())
            self._sync_controls()
        self._guard(edit, field=key)

    def _scalar(self, sc: Any, value: float) -> None:
        doc_params = sc.set(self.model.params, value)
        applied = self.model.set_param("geometry.params", {k: v for k, v in doc_params.items() if v is not None})
        self.redraw(handles=True)
        if not applied:
            raise ValueError(self.model.error)

    def _history(self, step: Any) -> None:
        if step():
            self._sync_controls()
            if self.live is not None and self.live.on:       # the live mesh starts again from the design restored
                self.live.restart()
        self.redraw(handles=True)

    def _set_metric(self) -> None:
        self.metric = str(self.metric_dd.value)
        self.redraw(handles=False)

    def _check_target(self) -> None:
        """Say what Save would do with the file named in "save as"; offer the replace box for a file that
        exists and that this studio did not write (a new name withdraws any consent given before)."""
        from ppfab.errors import DesignError

        self._replace_for = None
        self.replace_box.value = False
        text = str(self.save_path.value)
        try:
            target = self.model.save_rules.target(text) if text.strip() else None
        except DesignError as exc:
            target, self.save_note.content = None, str(exc)
        else:
            self.save_note.content = "" if target is None else {
                "new": "", "session": f"`{target.path}` was saved by this studio: Save replaces it",
                "foreign": f"`{target.path}` exists and was not written by this studio: tick the box to replace it",
                "input": f"`{target.path}` is the design or mesh this studio read: it is never overwritten"}[target.kind]
        self.replace_box.visible = target is not None and target.kind == "foreign"

    def _confirm_replace(self) -> None:
        """The replace box: consent for the file named now, and only for it."""
        self._replace_for = str(self.save_path.value) if self.replace_box.value else None

    def _save(self) -> None:
        text = str(self.save_path.value)
        replace = self._replace_for is not None and self._replace_for == text and bool(self.replace_box.value)
        try:
            path = self.model.save(text, replace)
        finally:
            self._check_target()
        self.model.error = ""
        self.build_msg.content = f"saved `{path}`"

    def _build(self) -> None:
        from .jobs import BuildJob

        if self.job is not None and self.job.status == "running":
            raise ValueError("a build is running; wait for it to finish")
        out = str(self.out_path.value).strip()
        if not out:
            raise ValueError("give the build folder first")
        self.progress.visible = True
        self.progress.value = 0.0

        def tell(text: str, fraction: float | None) -> None:
            if fraction is not None:
                self.progress.value = 100.0 * fraction
            report = self.job.report if self.job is not None else None
            self.build_msg.content = f"{text}\n\nreport: `{report}`" if report else text
            self.open_report.visible = report is not None

        job = BuildJob(self.model.design(), out, tell)
        self.job = job.start()                  # published once its thread runs (join before start raises)

    def _show_report(self) -> None:
        """Open the build's report in the browser of the machine the studio runs on (a page served over http
        may not link to a local file)."""
        import webbrowser

        if self.job is not None and self.job.report is not None:
            webbrowser.open(self.job.report.as_uri())

    def _optimize(self) -> None:
        from ppfab.optimize.params import OptimizeParams
        from ppfab.schema import parse_params
        from ppfab.topology import families_of

        from .jobs import OptimizeJob

        if self.opt_job is not None and self.opt_job.status == "running":
            raise ValueError("the optimisation is running; cancel it first")
        if self.live is not None and self.live.on:
            raise ValueError("the live relaxation is on; switch 'live: drag anchors' off first")
        params = parse_params(OptimizeParams, dict(self.model.doc.get("optimize", {})), "optimize")
        families = tuple(families_of(params.families))

        def tell(text: str, fraction: float | None) -> None:
            self.opt_msg.content = text

        def done(job: Any) -> None:
            if job.status == "done":
                with self.lock:
                    self.model.adopt(job.result.mesh, families)
                    self.redraw(handles=False)

        self.opt_job = OptimizeJob(self.model.state.raw, params, tell, done).start()

    def _cancel_optimize(self) -> None:
        if self.opt_job is not None:
            self.opt_job.cancel()

    # -- scene ----------------------------------------------------------------------------------------
    def _show_status(self) -> None:
        st = self.model.state
        dp = ", ".join(f"δ_P {k} {v:.1e}" for k, v in st.delta_p.items()) or "no planar family"
        folds = int(st.folded.sum())
        lines = [f"re-solve {1000 * st.seconds:.0f} ms · {dp}"]
        if folds:
            lines.append(f"**{folds} faces fold** (marked red)")
        refused = self.model.refused_folds
        if refused is not None and refused.any():
            lines.append(f"**the refused edit folds {int(refused.sum())} faces** (marked red on the last valid mesh)")
        if self.model.error:
            lines.append(f"**not applied:** {self.model.error}")
        self.status.content = "\n\n".join(lines)
        self.figures.content = st.figures.markdown()

    def redraw(self, handles: bool = True) -> None:
        """Redraw the mesh, beams, axes (and the handles) from the model.  The status and figures go first: the
        browser handles messages in order, so the numbers a user waits for are not queued behind the scene's
        meshes (``benchmarks/studio_latency.py``)."""
        scene: Any = self.server.scene
        st = self.model.state
        self._show_status()
        self.server.flush()              # the figures go out now, before the scene is built: the
        time.sleep(SEND_PAUSE)           # event loop gets the GIL to send them
        v = st.placed.vertices / 1000.0
        corners = face_corners(v, st.placed.closed)
        m, n = corners.shape[:2]
        values = face_metric(st.placed, self.metric).reshape(-1)
        if self.metric == "type":
            rng = np.random.default_rng(7)
            palette = rng.integers(60, 230, size=(int(values.max()) + 1, 3)).astype(np.uint8)
            colours = palette[values.astype(int)]
        elif self.metric == "planarity":             # δ_f on a fixed scale: 0 (blue) … 1e-3 (yellow) and above
            colours = ramp(np.minimum(values, 1e-3), (0.0, 1e-3))
        else:
            colours = ramp(values)
        self.legend.content = legend_html(self.metric, values, bool(st.folded.any() or (
            self.model.refused_folds is not None and self.model.refused_folds.any())))
        colours[st.folded.reshape(-1)] = FOLD_RGB
        if self.model.refused_folds is not None:
            colours[self.model.refused_folds.reshape(-1)] = FOLD_RGB
        self._draw_panels(corners.reshape(-1, 4, 3), colours)
        depth = float(self.model.doc.get("beams", {}).get("depth", 200.0)) / 1000.0
        axes = st.placed.axes
        if axes is not None and self.show_axes.value:
            seg = np.stack([v, v + 2.5 * depth * axes], axis=-2).reshape(-1, 2, 3)
            self._items["/axes"] = scene.add_line_segments("/axes", seg, (60, 60, 60), thickness=1.0,
                                                           thickness_units="screen")
        else:
            self._remove("/axes")
        if axes is not None and self.show_beams.value and st.families:
            strips = []
            for fam in st.families:
                lv = v if fam == "rows" else np.swapaxes(v, 0, 1)
                la = axes if fam == "rows" else np.swapaxes(axes, 0, 1)
                if st.placed.closed and fam == "rows":
                    lv, la = np.concatenate([lv, lv[:, :1]], 1), np.concatenate([la, la[:, :1]], 1)
                top, bot = lv, lv + depth * la
                q = np.stack([top[:, :-1], top[:, 1:], bot[:, 1:], bot[:, :-1]], axis=-2).reshape(-1, 4, 3)
                strips.append(q)
            q = np.concatenate(strips)
            b = 4 * np.arange(len(q))[:, None]
            t = np.concatenate([b + [0, 1, 2], b + [0, 2, 3]])
            self._items["/beams"] = scene.add_mesh_simple("/beams", q.reshape(-1, 3), t, color=(150, 150, 160), opacity=0.45,
                                  side="double")
        else:
            self._remove("/beams")
        if handles:
            self._draw_handles()
        self.redraws += 1

    def _draw_panels(self, quads: np.ndarray, colours: np.ndarray) -> None:
        """One flat-shaded mesh per distinct colour (the ramp is binned to 16 steps)."""
        scene: Any = self.server.scene
        for name in [k for k in self._items if k.startswith("/panels/")]:
            self._remove(name)
        binned = (colours.astype(int) // 16) * 16 + 8
        keys, inverse = np.unique(binned, axis=0, return_inverse=True)
        for k, rgb in enumerate(keys):
            q = quads[inverse.reshape(-1) == k]
            b = 4 * np.arange(len(q))[:, None]
            t = np.concatenate([b + [0, 1, 2], b + [0, 2, 3]])
            name = f"/panels/{k}"
            self._items[name] = scene.add_mesh_simple(name, q.reshape(-1, 3), t, color=tuple(int(x) for x in rgb),
                                                      flat_shading=True, side="double")

    def camera_view(self) -> tuple[np.ndarray, np.ndarray]:
        """``(position, look_at)`` of the camera that frames the mesh (display metres): from the −x −y side,
        above it."""
        v = self.model.state.placed.vertices.reshape(-1, 3) / 1000.0
        lo, hi = v.min(0), v.max(0)
        centre = 0.5 * (lo + hi)
        diag = float(np.linalg.norm(hi - lo))
        return centre + diag * np.array([-0.32, -0.55, 0.45]), centre

    def _frame_camera(self, client: Any) -> None:
        position, look_at = self.camera_view()
        client.camera.position = tuple(position)
        client.camera.look_at = tuple(look_at)

    def _remove(self, name: str) -> None:
        item = self._items.pop(name, None)
        if item is not None:
            item.remove()

    def _draw_handles(self) -> None:
        v = self.model.state.placed.vertices / 1000.0
        size = 0.08 * float(np.linalg.norm(v.reshape(-1, 3).max(0) - v.reshape(-1, 3).min(0)))
        wanted = self.model.handles()
        scene: Any = self.server.scene
        if move_handles(scene, self.model.method, self._handles, wanted, size, getattr(self, "handle_scale", None)):
            return
        for item in self._handles.values():
            item.remove()
        self.handle_scale = size
        self._handles = draw_handles(scene, self.model, wanted, size, self._gizmo_callback)

    def _gizmo_callback(self, key: str) -> Any:
        """The gizmo's callback: ``async`` so that the phases of one drag (start, update…, end) arrive in order."""
        async def on_gizmo(event: Any) -> None:
            phase = getattr(event, "phase", "update")
            if phase == "start":
                self._guard(self.model.begin_drag)
            elif phase == "end":
                self._guard(lambda: self._drag(key, event.target))
                self._guard(self._end_drag)
            else:
                self._guard(lambda: self._drag(key, event.target))
        return on_gizmo

    def _drag(self, key: str, target: Any) -> None:
        self.model.drag(key, np.asarray(target.position, dtype=float), quat_matrix(target.wxyz))
        self.redraw(handles=False)

    def _end_drag(self) -> None:
        self.model.end_drag()
        self._sync_controls()
        self.redraw(handles=True)

    # -- for tests and scripts ------------------------------------------------------------------------
    @property
    def url(self) -> str:
        """The page's address, with the session key (the only address the studio answers)."""
        from .guard import is_loopback

        host = self.server.get_host()
        name = "localhost" if is_loopback(host) or host in ("0.0.0.0", "::", "") else host
        name = f"[{name}]" if ":" in name else name
        return f"http://{name}:{self.server.get_port()}/{self.gate.key}/"

    def snapshot(self) -> dict:
        """What the scene shows now: vertices (mm), δ_P per planar family, the handles (display metres), the
        last error and the number of redraws."""
        with self.lock:
            st = self.model.state
            live: dict[str, Any] = self.live.snapshot() if self.live is not None else {"on": False}
            return {"vertices": st.placed.vertices.copy(), "delta_p": dict(st.delta_p), "error": self.model.error,
                    "handles": {**{h.key: h.position for h in self.model.handles()}, **live.get("anchors", {})},
                    "redraws": self.redraws, "params": self.model.params,
                    "figures": dataclasses.asdict(st.figures), "live": live}

    def stop(self) -> None:
        if self.live is not None:
            self.live.stop(join=True)
        self.server.stop()


def _no_share(verbose: bool = True) -> None:
    """Stands in for viser's ``request_share_url``: the studio is never shared through a public tunnel."""
    log.info("studio: a page asked for a share link; the studio is not shared")
    return None


def serve(model: StudioModel, host: str, port: int, open_browser: bool, design_path: str = "") -> int:
    """Run the studio until Ctrl-C."""
    import contextlib
    import io

    with contextlib.redirect_stdout(io.StringIO()):         # viser's banner names the address without the key
        studio = Studio(model, host, port, design_path)
    url = studio.url
    print(f"ppfab: studio at {url} (Ctrl-C to stop)", flush=True)
    if open_browser:
        import webbrowser

        webbrowser.open(url)
    try:
        while True:
            time.sleep(1.0)
    finally:
        studio.stop()
