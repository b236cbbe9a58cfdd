"""What a studio user waits for: from a key press to the figures painted in the browser.

The bundled default (22 × 15 faces) is opened in headless Chromium (Debian's ``chromium`` and
``chromium-driver``, software WebGL).  The page gets a capture-phase ``keydown`` listener that stamps
``performance.now()`` and a ``MutationObserver`` on the figures' text; when the panel count shown changes, two
``requestAnimationFrame`` callbacks later (the frame with the new text painted) the time since the key press is
recorded.  The key presses are real keyboard events on the ``faces_u`` slider's thumb, alternately → and ←
(22 → 23 → 22 faces: every press is a new mesh, re-solved, measured and redrawn), one after the other with a
pause between.  Reported: median, min and max of ``repeat`` presses, and the studio's own re-solve time of the
same edits (``Solve.seconds``) for comparison: the rest is the redraw, the WebSocket and the browser.

    OMP_NUM_THREADS=1 python benchmarks/studio_latency.py [repeat]
"""

from __future__ import annotations

import shutil
import socket
import statistics
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from selenium import webdriver  # noqa: E402
from selenium.webdriver.chrome.options import Options  # noqa: E402
from selenium.webdriver.chrome.service import Service  # noqa: E402
from selenium.webdriver.common.action_chains import ActionChains  # noqa: E402
from selenium.webdriver.common.by import By  # noqa: E402
from selenium.webdriver.common.keys import Keys  # noqa: E402

from fabrication.studio.app import Studio  # noqa: E402
from fabrication.studio.model import StudioModel  # noqa: E402

WATCH = """
window.__lat = []; window.__dom = []; window.__t0 = null; window.__last = null;
const shown = () => [...document.querySelectorAll('li')].map(x => x.textContent).find(t => t.startsWith('panels:'));
window.__last = shown();
document.addEventListener('keydown', () => { window.__t0 = performance.now(); }, true);
new MutationObserver(() => {
  const text = shown();
  if (text && text !== window.__last && window.__t0 !== null) {
    window.__last = text; const t0 = window.__t0; window.__t0 = null; window.__dom.push(performance.now() - t0);
    requestAnimationFrame(() => requestAnimationFrame(() => window.__lat.push(performance.now() - t0)));
  }
}).observe(document.body, {subtree: true, childList: true, characterData: true});
"""


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _wait(cond, timeout: float = 30.0):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        value = cond()
        if value:
            return value
        time.sleep(0.02)
    raise TimeoutError("the figures did not change")


def main(repeat: int = 12) -> None:
    options = Options()
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1400,900", "--use-gl=swiftshader",
              "--enable-unsafe-swiftshader", "--disable-dev-shm-usage"):
        options.add_argument(a)
    options.binary_location = shutil.which("chromium") or shutil.which("chromium-browser") or "chromium"
    browser = webdriver.Chrome(service=Service(shutil.which("chromedriver") or "chromedriver"), options=options)
    studio = Studio(StudioModel.load(None), port=_port())
    try:
        browser.get(studio.url)
        _wait(lambda: studio.server.get_clients())
        _wait(lambda: browser.find_elements(By.XPATH, "//li[starts-with(normalize-space(.), 'panels:')]"))
        time.sleep(3.0)                                         # the first frames of the software renderer
        label = browser.find_element(By.XPATH, "//label[normalize-space(string(.))='faces_u']")
        thumb = browser.find_element(By.XPATH, f"//*[@id='{label.get_attribute('for')}']") if \
            browser.find_elements(By.ID, label.get_attribute("for")) else None
        if thumb is None or thumb.get_attribute("role") != "slider":
            thumb = label.find_element(By.XPATH, "./ancestor::div[contains(@class, 'mantine-Flex-root')][1]"
                                                 "//*[@role='slider']")
        browser.execute_script("arguments[0].scrollIntoView({block: 'center'});", thumb)
        ActionChains(browser).click(thumb).perform()
        time.sleep(2.0)                                         # a click may move the thumb: let it settle
        browser.execute_script(WATCH)
        solves = []
        for k in range(repeat):
            thumb.send_keys(Keys.ARROW_RIGHT if k % 2 == 0 else Keys.ARROW_LEFT)
            _wait(lambda: browser.execute_script("return window.__lat.length") > k)
            solves.append(studio.model.state.seconds)
            time.sleep(0.7)
        lat = browser.execute_script("return window.__lat")
        dom = browser.execute_script("return window.__dom")
        print(f"key press -> figures painted, default 22 x 15 faces, {repeat} presses: median {statistics.median(lat):.0f} "
              f"ms (min {min(lat):.0f}, max {max(lat):.0f}); the new text in the page (before painting): median "
              f"{statistics.median(dom):.0f} ms; the studio's re-solve of the same edits: median "
              f"{1000 * statistics.median(solves):.0f} ms")
    finally:
        studio.stop()
        browser.quit()


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 12)
