"""``ppfab studio`` in a real headless Chromium (Debian's ``chromium`` and ``chromium-driver``; CI installs them).

The studio runs in this process on a free loopback port; the browser loads its page and a person's input is
sent as real events: arrow keys on the ``faces_u`` slider, a mouse drag on a handle's gizmo, typing a file
name and clicking Save.  The state is read back through :meth:`fabrication.studio.app.Studio.snapshot`.

Locating the gizmo: the test puts the camera where it wants (position, look-at, up, vertical field of view,
all reported back by the client), projects the handle's centre and a point 60 % up its z arrow (the arrow's
length is the gizmo's scale in world units) to canvas pixels with the pinhole model, presses the mouse there
and drags upwards along the arrow's screen direction.

Screenshots of the default design and of a conical design go to ``docs/images/`` when ``PPFAB_SCREENSHOTS=1``
(the README shows them), else into the test's temporary folder.
"""

from __future__ import annotations

import os
import shutil
import socket
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest

from conftest import REPO
from conftest import wait_for as _wait

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
DRIVER = shutil.which("chromedriver")
pytestmark = pytest.mark.skipif(not (CHROMIUM and DRIVER),
                                reason="needs Debian's chromium and chromium-driver (apt-get install chromium "
                                       "chromium-driver; .ci/run installs them)")
viser = pytest.importorskip("viser", reason="the studio extra is not installed (pip install '.[studio]')")
selenium = pytest.importorskip("selenium")

from selenium import webdriver  # noqa: E402
from selenium.webdriver.chrome.options import Options  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402

from fabrication.studio.app import Studio  # noqa: E402
from fabrication.studio.model import StudioModel, solve  # noqa: E402

PP_TOL = 1e-9


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture
def browser():
    o = Options()
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1400,900",
              "--use-gl=swiftshader", "--enable-unsafe-swiftshader", "--disable-dev-shm-usage"):
        o.add_argument(a)
    o.binary_location = CHROMIUM
    d = webdriver.Chrome(service=Service(DRIVER), options=o)
    yield d
    d.quit()


def _open(browser, model: StudioModel, design_path: str = "") -> Studio:
    studio = Studio(model, port=_free_port(), design_path=design_path)
    browser.get(studio.url)                                    # the address with the session key
    _wait(lambda: studio.server.get_clients(), what="the page to connect")
    _wait(lambda: browser.find_elements(By.TAG_NAME, "canvas"), what="the 3D canvas")
    for close in browser.find_elements(By.CSS_SELECTOR, ".mantine-Notification-closeButton"):
        close.click()                                          # the software-rendering notice
    return studio


def _shot(browser, name: str, tmp_path: Path) -> Path:
    folder = REPO / "docs" / "images" if os.environ.get("PPFAB_SCREENSHOTS") == "1" else tmp_path
    folder.mkdir(parents=True, exist_ok=True)
    time.sleep(2.0)                                            # let the software renderer finish a frame
    path = folder / name
    browser.save_screenshot(str(path))
    assert path.stat().st_size > 10_000
    return path


def _delta_p(vertices: np.ndarray, families) -> float:
    """δ_P (§3.3) recomputed here from the vertices: largest distance from the least-squares plane (SVD) over
    the bounding-box diagonal, for every polyline of the planar families."""
    worst = 0.0
    for fam in families:
        lines = vertices if fam == "rows" else np.swapaxes(vertices, 0, 1)
        for line in lines:
            c = line - line.mean(0)
            normal = np.linalg.svd(c)[2][-1]
            diag = np.linalg.norm(line.max(0) - line.min(0))
            worst = max(worst, float(np.abs(c @ normal).max() / diag))
    return worst


def _project(camera, point: np.ndarray, width: int, height: int) -> np.ndarray:
    """Canvas pixel ``(x, y)`` of a world point under the client's pinhole camera: ``wxyz`` turns camera
    coordinates (x right, y down, z forward) into world ones, ``fov`` is the vertical field of view."""
    R = _rotation(camera.wxyz)
    d = R.T @ (np.asarray(point, dtype=float) - np.asarray(camera.position, dtype=float))
    focal = 0.5 * height / np.tan(0.5 * float(camera.fov))
    return np.array([0.5 * width + focal * d[0] / d[2], 0.5 * height + focal * d[1] / d[2]])


def _rotation(wxyz) -> np.ndarray:
    w, x, y, z = np.asarray(wxyz, dtype=float)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                  [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                  [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _control(browser, label: str):
    """The input element of the GUI control labelled ``label`` (a ``<label for=…>``; viser breaks long labels
    with ``<wbr>``, so the label's string value is compared)."""
    xpath = f"//label[normalize-space(string(.))='{label}']"
    found = browser.find_elements(By.ID, browser.find_element(By.XPATH, xpath).get_attribute("for"))
    if found:
        return found[0]
    return browser.find_element(By.XPATH, f"{xpath}/ancestor::div[contains(@class, 'mantine-Flex-root')][1]//input")


def _slider_keys(browser, label: str, key: str, times: int) -> int:
    """Focus the slider's thumb with a click, press ``key`` ``times`` times; returns the value the slider
    should show then (the value after the click, which may move the thumb by a step, plus ``times``)."""
    thumb = _control(browser, label).find_element(By.CSS_SELECTOR, "[role='slider']")
    browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", thumb)
    ActionChains(browser).click(thumb).perform()
    time.sleep(0.5)
    start = int(thumb.get_attribute("aria-valuenow"))
    for _ in range(times):
        thumb.send_keys(key)
        time.sleep(0.2)
    return start + times


def _drag_handle(browser, studio: Studio, key: str, pixels: float) -> None:
    """Drag handle ``key`` along its z arrow by ``pixels`` on the screen (positive: towards +z) with real
    mouse events."""
    client = next(iter(studio.server.get_clients().values()))
    centre = np.asarray(studio.snapshot()["handles"][key])
    eye = centre + np.array([-6.0, -22.0, 4.0])
    client.camera.position = tuple(eye)                       # position first: the client keeps it and turns
    client.camera.look_at = tuple(centre)                     # towards the look-at point set next
    view = (centre - eye) / np.linalg.norm(centre - eye)

    def settled() -> bool:                                     # the client reported the pose back
        forward = _rotation(client.camera.wxyz)[:, 2]
        return bool(np.allclose(client.camera.position, eye, atol=1e-6) and forward @ view > 1 - 1e-6)
    _wait(settled, what=f"the camera (set {eye} -> {centre}; reported {client.camera.position}, "
                        f"{client.camera.look_at})")
    time.sleep(1.0)
    canvas = max(browser.find_elements(By.TAG_NAME, "canvas"), key=lambda c: c.size["width"] * c.size["height"])
    w, h = canvas.size["width"], canvas.size["height"]
    a = _project(client.camera, centre, w, h)
    b = _project(client.camera, centre + 0.6 * studio.handle_scale * np.array([0.0, 0.0, 1.0]), w, h)
    direction = (b - a) / np.linalg.norm(b - a)
    chain = ActionChains(browser, duration=50)
    chain.move_to_element_with_offset(canvas, int(b[0] - w / 2), int(b[1] - h / 2)).click_and_hold()
    for _ in range(6):
        step = direction * pixels / 6
        chain.move_by_offset(int(round(step[0])), int(round(step[1])))
    chain.release().perform()


def test_studio_default_design_slider_drag_save(browser, tmp_path):
    model = StudioModel.load(None)
    studio = _open(browser, model)
    try:
        before = studio.snapshot()
        assert before["vertices"].shape == (23, 16, 3)
        _shot(browser, "studio_default.png", tmp_path)

        # a handle: the tangent plane of g at its second node, dragged up its z arrow
        undo_before = len(studio.model.history.undo)
        _drag_handle(browser, studio, "g1", 80.0)
        _wait(lambda: len(studio.model.history.undo) > undo_before, what="the drag to be recorded")
        dragged = studio.snapshot()
        assert dragged["handles"]["g1"][2] > before["handles"]["g1"][2]     # the tangent plane went up
        assert dragged["vertices"].shape == before["vertices"].shape
        moved = np.abs(dragged["vertices"] - before["vertices"]).max()
        assert moved > 10.0, f"the mesh moved only {moved} mm"
        assert dragged["params"]["g"] != before["params"]["g"]
        assert dragged["params"]["h"] == before["params"]["h"]
        assert max(dragged["delta_p"].values()) <= PP_TOL
        assert _delta_p(dragged["vertices"], ("rows", "cols")) <= PP_TOL
        assert dragged["error"] == ""

        # a slider: faces_u up by 3 with the arrow keys on its thumb
        want = _slider_keys(browser, "faces_u", Keys.ARROW_RIGHT, 3)
        assert want >= 24
        _wait(lambda: studio.snapshot()["params"]["faces_u"] == want, what=f"faces_u to reach {want}")
        after_slider = studio.snapshot()
        assert after_slider["vertices"].shape == (want + 1, 16, 3)
        assert max(after_slider["delta_p"].values()) <= PP_TOL
        assert _delta_p(after_slider["vertices"], ("rows", "cols")) <= PP_TOL

        assert after_slider["params"]["g"] == dragged["params"]["g"]              # the drag is kept
        # save through the GUI: type the file name, click Save; loading it gives the same geometry
        target = tmp_path / "edited.toml"
        field = _control(browser, "save as")
        browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", field)
        field.click()
        field.send_keys(Keys.CONTROL, "a")
        field.send_keys(str(target), Keys.ENTER)
        _wait(lambda: studio.server.gui is not None and str(target) in str(studio.save_path.value),
              what="the typed file name")
        button = browser.find_element(By.XPATH, "//span[text()='Save']/ancestor::button")
        browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", button)
        button.click()
        _wait(target.exists, what="the saved file")
        reloaded = StudioModel.load(target)
        assert np.abs(reloaded.state.placed.vertices - after_slider["vertices"]).max() <= 1e-9
        again = solve(tomllib.loads(target.read_text(encoding="utf-8")), target.parent)
        assert np.abs(again.placed.vertices - after_slider["vertices"]).max() <= 1e-9

        # undo (clicks) takes back the slider's steps (one edit each), then the drag
        undo = browser.find_element(By.XPATH, "//span[text()='Undo']/ancestor::button")
        browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", undo)
        steps = len(studio.model.history.undo) - undo_before - 1
        assert steps >= 1
        for k in range(steps):
            undo.click()
            _wait(lambda: len(studio.model.history.undo) == undo_before + steps - k, what="an undo")
        assert studio.snapshot()["params"]["faces_u"] == 22
        undo.click()
        _wait(lambda: studio.snapshot()["params"]["g"] == before["params"]["g"], what="undo of the drag")
        assert np.abs(studio.snapshot()["vertices"] - before["vertices"]).max() == 0.0
    finally:
        studio.stop()


def test_studio_conical_design_handle_and_screenshot(browser, tmp_path):
    path = REPO / "examples" / "conical_spheres.toml"
    studio = _open(browser, StudioModel.load(path), str(path))
    try:
        before = studio.snapshot()
        assert any(k.startswith("s") for k in before["handles"]) and any(k.startswith("p") for k in before["handles"])
        _shot(browser, "studio_conical.png", tmp_path)
        undo_before = len(studio.model.history.undo)
        _drag_handle(browser, studio, "s2", 60.0)
        _wait(lambda: len(studio.model.history.undo) > undo_before, what="the drag to be recorded")
        after = studio.snapshot()
        assert after["params"]["spheres"][2][2] > before["params"]["spheres"][2][2]      # moved up
        assert np.abs(after["vertices"] - before["vertices"]).max() > 1.0
        assert after["delta_p"]["rows"] <= PP_TOL                     # P: the cross-sections stay planar
        assert _delta_p(after["vertices"], ("rows",)) <= PP_TOL
    finally:
        studio.stop()


def test_a_refused_value_reverts_its_field_and_says_why_under_it_and_the_figures_say_what_they_count(browser):
    """Typed in Chromium: scale = -5 on the default.  The model keeps 1000, the field shows 1000 again and the
    reason appears right under the field (not only in the status at the top); the figures on the page name
    what they measure — the support the build makes, the panes as cut — with the studio's numbers."""
    studio = _open(browser, StudioModel.load(None))
    try:
        field = _control(browser, "scale")
        browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", field)
        field.click()
        field.send_keys(Keys.CONTROL, "a")
        field.send_keys("-5", Keys.ENTER)
        _wait(lambda: studio.model.error, what="the refusal")
        assert studio.model.geometry["scale"] == 1000.0
        _wait(lambda: field.get_attribute("value") in ("1000", "1,000"), what="the field to show 1000 again")
        below = _wait(lambda: [p for p in browser.find_elements(By.XPATH, "//p[starts-with(normalize-space(.), "
                                                                          "'not applied:')]")
                               if "scale stays 1000" in p.text], what="the reason under the field")
        gap = below[0].location["y"] - (field.location["y"] + field.size["height"])
        assert 0 <= gap < 60, f"the reason is {gap} px from the field"     # right under it, where one looks
        figures = {t.split(":", 1)[0]: t for t in (li.text for li in browser.find_elements(By.TAG_NAME, "li"))}
        figs = studio.snapshot()["figures"]
        assert figures["torsion"] == f"torsion: {figs['torsion_mm']:.2e} mm (the PP support the build makes)"
        assert figures["glass as cut"].startswith(f"glass as cut: {figs['glass_area_m2']:.1f} m² (faces inset by "
                                                  f"half the {figs['gap_mm']:g} mm gap)")
    finally:
        studio.stop()


def test_live_anchor_dragged_in_the_browser_moves_the_mesh_which_settles_pp(browser, tmp_path):
    """A mesh-file design (Fig. 23: the real ``DOS__enneper2.obj``, 31 × 31 vertices): the *live* checkbox
    clicked, the centre typed as an anchor, its gizmo dragged up with the mouse; the mesh follows while the
    drag goes on, settles planar (faces and both families, by SVD) with the anchor where the drag left it, and
    the drag is recorded in ``[optimize] anchors``."""
    path = REPO / "examples" / "fig23_enneper_pp_to_conical.toml"
    studio = _open(browser, StudioModel.load(path), "examples/" + path.name)   # relative: the screenshot's save-as
    try:
        before = studio.snapshot()
        field = _control(browser, "anchors [row, column]")
        browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", field)
        field.click()
        field.send_keys(Keys.CONTROL, "a")
        field.send_keys("[[0, 0], [0, 30], [30, 0], [30, 30], [15, 15]]", Keys.ENTER)
        _wait(lambda: "[15, 15]" in str(studio.live.cells.value), what="the typed anchors")
        box = _control(browser, "live: drag anchors")
        browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", box)
        browser.execute_script("arguments[0].click();", box)
        _wait(lambda: "a15_15" in studio.snapshot()["handles"], what="the live anchors")
        _wait(lambda: studio.snapshot()["live"]["settled"], 120, "the first relaxation")
        canvas = max(browser.find_elements(By.TAG_NAME, "canvas"), key=lambda c: c.size["width"] * c.size["height"])
        ActionChains(browser).move_to_element_with_offset(canvas, -canvas.size["width"] // 2 + 5, 0).perform()
        _shot(browser, "studio_live.png", tmp_path)                # the pointer off the panel: no tooltip
        undo_before = len(studio.model.history.undo)
        redraws = studio.redraws
        _drag_handle(browser, studio, "a15_15", 20.0)
        _wait(lambda: len(studio.model.history.undo) > undo_before, what="the drag to be recorded")
        _wait(lambda: studio.snapshot()["live"]["settled"], 120, "the mesh to settle")
        time.sleep(0.5)
        after = studio.snapshot()
        assert studio.redraws > redraws + 1                           # the mesh was redrawn as it relaxed
        v = after["vertices"]
        lift = v[15, 15, 2] - before["vertices"][15, 15, 2]
        assert lift > 50.0, f"the anchor rose only {lift} mm"
        assert np.allclose(after["handles"]["a15_15"], v[15, 15] / 1000.0, atol=1e-9)
        assert abs(v[16, 15, 2] - before["vertices"][16, 15, 2]) > 0.1 * lift     # its neighbours followed
        quads = np.stack([v[:-1, :-1], v[:-1, 1:], v[1:, 1:], v[1:, :-1]], axis=2).reshape(-1, 4, 3)
        assert _delta_p(quads, ("rows",)) <= 1e-6, (lift, after["live"])   # every face planar (SVD, 4 corners)
        assert _delta_p(v, ("rows", "cols")) <= 1e-6
        recorded = {int(a[0]): a[1:] for a in studio.model.doc["optimize"]["anchors"]}
        assert np.allclose(recorded[15 * 31 + 15], studio.live.session.relaxation.vertices[15 * 31 + 15], atol=0)
    finally:
        studio.stop()


def test_a_page_of_another_origin_cannot_reach_the_studio(browser, tmp_path):
    """A page served from another origin (another port on this machine) opens viser's WebSocket with the
    right subprotocol and even the session key: Chromium sends its Origin, the studio refuses the handshake
    and no client connects; the studio's own page (same key) connects."""
    import http.server
    import threading

    studio = Studio(StudioModel.load(REPO / "examples" / "smallest_roof.toml"), port=_free_port())
    (tmp_path / "evil.html").write_text("<html><body>evil</body></html>", encoding="utf-8")
    handler = lambda *a: http.server.SimpleHTTPRequestHandler(*a, directory=str(tmp_path))  # noqa: E731
    evil = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=evil.serve_forever, daemon=True).start()
    try:
        browser.get(f"http://127.0.0.1:{evil.server_address[1]}/evil.html")
        ws = f"ws://localhost:{studio.server.get_port()}/{studio.gate.key}"
        outcome = browser.execute_async_script(
            "const done = arguments[arguments.length - 1];"
            f"const s = new WebSocket('{ws}', ['viser-v{viser.__version__}']);"
            "s.onopen = () => done('open'); s.onerror = () => done('refused');")
        assert outcome == "refused"
        time.sleep(1.0)
        assert not studio.server.get_clients()
        browser.get(studio.url)
        _wait(lambda: studio.server.get_clients(), what="the studio's own page to connect")
    finally:
        evil.shutdown()
        studio.stop()


@pytest.mark.slow
def test_studio_build_button_writes_the_folder_and_shows_the_report(browser, tmp_path):
    model = StudioModel.load(None)
    for key, value in (("faces_u", 4), ("faces_v", 3), ("u_range", [-3.0, 3.0]), ("v_range", [-2.0, 2.0])):
        assert model.set_param(key, value), model.error
    studio = _open(browser, model)
    try:
        out = tmp_path / "build"
        field = _control(browser, "build folder")
        browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", field)
        field.click()
        field.send_keys(str(out), Keys.ENTER)
        _wait(lambda: str(out) in str(studio.out_path.value), what="the typed folder")
        button = browser.find_element(By.XPATH, "//span[text()='Build']/ancestor::button")
        browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", button)
        button.click()
        _wait(lambda: studio.job is not None, what="the build to start")
        studio.job.join(900)
        assert studio.job.status == "done", studio.job.message
        assert (out / "report.html").is_file() and (out / "manifest.json").is_file()
        report = str((out / "report.html").resolve())
        _wait(lambda: browser.find_elements(By.XPATH, f"//code[text()='{report}']"), 30, "the report's path")
        _wait(lambda: browser.find_elements(By.XPATH, "//span[text()='Open report']"), 30, "the Open report button")
    finally:
        studio.stop()
