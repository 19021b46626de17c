"""The site report in a real headless browser: no horizontal overflow at 1400 px, every
figure loaded.

Uses a Chromium found on the PATH (``chromium``, ``chromium-browser``, ``google-chrome``,
``chromium-headless-shell``, ``chrome-headless-shell``) through ``--dump-dom`` with a probe
script added to a copy of the page, else Playwright's own Chromium when the ``playwright``
package and its browser are installed; skipped when neither is.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from datetime import datetime, timedelta

import numpy as np
import pytest

from bwim.accuracy import ReferenceRow
from bwim.report import TrafficSummary, render_html, site_sections
from bwim.report.runs import CalibrationRun, CalibrationRuns
from bwim.summary import SummaryRow

BROWSERS = ("chromium", "chromium-browser", "google-chrome", "chromium-headless-shell",
            "chrome-headless-shell")
WIDTH = 1400

#: Measures the page once it has loaded and writes the numbers into a <pre id="probe">.
PROBE = """<script>
window.addEventListener("load", function () {
  var imgs = Array.prototype.slice.call(document.images);
  var root = document.scrollingElement;
  var out = {scrollWidth: root.scrollWidth, clientWidth: root.clientWidth,
             images: imgs.length,
             loaded: imgs.filter(function (i) { return i.complete && i.naturalWidth > 0; })
                         .length};
  var pre = document.createElement("pre");
  pre.id = "probe";
  pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
});
</script>"""


def _browser() -> str | None:
    for name in BROWSERS:
        path = shutil.which(name)
        if path:
            return path
    return None


def _measure_playwright(url: str) -> dict:
    """The probe's numbers from Playwright's Chromium (skip when it is not installed)."""
    try:
        from playwright.sync_api import Error, sync_playwright
    except ImportError:
        pytest.skip("no headless Chromium installed (" + ", ".join(BROWSERS)
                    + ") and no playwright")
    with sync_playwright() as pw:
        try:
            browser = pw.chromium.launch()
        except Error as exc:
            pytest.skip(f"playwright has no browser: {str(exc).splitlines()[0]}")
        try:
            view = browser.new_page(viewport={"width": WIDTH, "height": 1000})
            view.goto(url, wait_until="load")
            return json.loads(view.locator("#probe").text_content(timeout=30_000))
        finally:
            browser.close()


def _measure(page: str, tmp_path) -> dict:
    """Render ``page`` in headless Chromium at WIDTH px and return the probe's numbers."""
    html_file = tmp_path / "page.html"
    html_file.write_text(page.replace("</body>", PROBE + "</body>"), encoding="utf-8")
    exe = _browser()
    if exe is None:
        return _measure_playwright(html_file.as_uri())
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
           f"--window-size={WIDTH},1000", "--virtual-time-budget=10000",
           f"--user-data-dir={tmp_path / 'profile'}", "--dump-dom", html_file.as_uri()]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=90)
    except subprocess.TimeoutExpired:
        pytest.fail("the headless browser did not finish within 90 s")
    m = re.search(r'<pre id="probe">(.*?)</pre>', done.stdout, re.S)
    assert m is not None, f"no probe in the dumped page; stderr: {done.stderr[-500:]}"
    return json.loads(m.group(1))


def _site_page() -> str:
    """A day with long flags and reasons: a per-vehicle table far wider than the page."""
    rng = np.random.default_rng(11)
    t0 = datetime(2015, 10, 1, 6, 0)
    rows, refs = [], []
    for k in range(60):
        sp = (3.6, 6.0, 1.3, 1.3) if k % 2 else (4.5,)
        common = dict(record=f"site_A_logger_event_{k:05d}.csv",
                      time=t0 + timedelta(minutes=11 * k), lane=1 + k % 3,
                      vehicle_class="113" if k % 2 else "11", n_axles=len(sp) + 1,
                      speed=18.0 + k % 7, axle_spacings=sp, lateral=1.0 + 0.05 * k,
                      lateral_unit="m")
        if k % 6 == 5:
            rows.append(SummaryRow(**common, flags=("multiple_presence", "speed_varies",
                                                    "unexplained_strain"),
                                   reason="multiple presence: 2 vehicles on the span at once "
                                          "(lanes 1 and 2), the event is not weighed"))
            continue
        w = rng.uniform(30e3, 110e3, len(sp) + 1)
        rows.append(SummaryRow(**common, axle_weights=w, gvw=float(w.sum()),
                               flags=("outside_calibration_time", "lateral_extrapolated"),
                               quality="warning"))
        if k % 4 == 0:
            refs.append(ReferenceRow(record=common["record"], gvw=float(w.sum()) * 1.02))
    runs = CalibrationRuns(name="calibration_runs.csv", runs=tuple(
        CalibrationRun(name=f"calibration_run_{k:03d}.csv", scale=1 + 0.002 * k,
                       residual=0.03, time=t0 + timedelta(minutes=20 * k)) for k in range(20)))
    sections = site_sections(TrafficSummary(name="summary.csv", rows=rows), reference=refs,
                             runs=runs)
    return render_html("site report", sections)


def test_site_report_fits_1400_px_and_every_figure_loads(tmp_path):
    """At 1400 px the page does not scroll sideways (the wide per-vehicle table scrolls in
    its own box) and the browser decoded all ten figures."""
    page = _site_page()
    n_figures = page.count("<img ")
    assert n_figures == 10
    got = _measure(page, tmp_path)
    assert got["images"] == n_figures and got["loaded"] == n_figures
    assert got["scrollWidth"] <= WIDTH, got
