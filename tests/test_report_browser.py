"""report.html as a browser shows it: headless Chromium (Debian package ``chromium``, which
.ci/run installs when missing) renders it with the network cut off, takes a screenshot,
and reports whether every image decoded and what the page tried to fetch.

Page requests are read from Chromium's NetLog (``--log-net-log``): a request the page
makes carries the page's origin as its initiator ('null' for a file:// page), while the
browser's own background traffic (update checks) carries 'not an origin'. Two control
pages, one with an external image and one with a corrupt embedded one, show that both
checks can fail. Skipped, with the reason, where no Chromium can be found.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from beadrod.workflows.report.document import render_report

_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
CHROMIUM = next((p for p in map(shutil.which, _NAMES) if p), None)

pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="no Chromium on PATH (Debian: apt-get install chromium; "
                             ".ci/run installs it): the browser checks of report.html need one")

_PROBE = """<script>window.addEventListener("load", () => {
  const s = [...document.images].map(i => (i.complete && i.naturalWidth > 0) ? 1 : 0);
  document.body.setAttribute("data-images-ok", s.join(","));
});</script>"""

# a 1x1 PNG, and the same bytes cut short
_PNG = ("iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQGAhKmMIQAAAABJ"
        "RU5ErkJggg==")


def _chromium(page: Path, tmp: Path, *extra: str) -> tuple[str, list[str]]:
    """(stdout, URLs the page itself requested) of headless Chromium on ``page``."""
    netlog = tmp / f"{page.stem}.netlog.json"
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
           f"--user-data-dir={tmp / 'profile'}", "--disable-background-networking",
           "--disable-component-update", "--disable-sync", "--disable-default-apps",
           # no network: every host name fails to resolve
           "--host-resolver-rules=MAP * ~NOTFOUND",
           f"--log-net-log={netlog}", "--virtual-time-budget=5000", *extra, page.as_uri()]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=180, check=False)
    assert res.returncode == 0, res.stderr[-2000:]
    return res.stdout, _page_requests(netlog)


def _page_requests(netlog: Path) -> list[str]:
    log = json.loads(netlog.read_text())
    start = log["constants"]["logEventTypes"]["URL_REQUEST_START_JOB"]
    urls = []
    for e in log["events"]:
        p = e.get("params") or {}
        if e["type"] == start and "url" in p and p.get("initiator") != "not an origin":
            url = str(p["url"])
            if not url.startswith(("data:", "file:")):
                urls.append(url)
    return urls


def _images_ok(dom: str) -> list[int]:
    class P(HTMLParser):
        flags: list[int] | None = None

        def handle_starttag(self, tag, attrs):
            a = dict(attrs)
            if tag == "body" and "data-images-ok" in a:
                P.flags = [int(v) for v in a["data-images-ok"].split(",") if v]

    P().feed(dom)
    assert P.flags is not None, "the probe did not run: no load event seen"
    return P.flags


def _probe(page: Path, out: Path) -> Path:
    out.write_text(page.read_text().replace("</body>", _PROBE + "</body>"))
    return out


def _report(tmp_path: Path) -> Path:
    from test_report import _flagged  # the report inputs of the unit tests, with warnings

    return render_report(_flagged(tmp_path), tmp_path)[1]


def _tinted(img: np.ndarray, rgb: tuple[int, int, int]) -> int:
    """Pixels of exactly the colour ``rgb`` (the CSS tint of a warnings-table cell)."""
    return int((np.abs(img[..., :3] - np.array(rgb) / 255).max(axis=-1) < 1.5 / 255).sum())


def test_report_renders_offline_with_every_image(tmp_path):
    page = _report(tmp_path)
    text = page.read_text()
    assert "http://" not in text and "https://" not in text  # nothing external referenced
    dom, requests = _chromium(_probe(page, tmp_path / "probe.html"), tmp_path, "--dump-dom")
    assert requests == []
    flags = _images_ok(dom)
    assert len(flags) == text.count("<img ") == 2 and all(flags), flags

    shot = tmp_path / "first_screen.png"
    _chromium(page, tmp_path, f"--screenshot={shot}", "--window-size=1280,900",
              "--hide-scrollbars")
    import matplotlib.image as mpimg

    img = mpimg.imread(shot)
    assert img.shape[:2] == (900, 1280)
    # not blank: text and the warning banner's colour are on the first screen
    assert float(np.std(img[..., :3])) > 0.05
    red = (img[..., 0] > 0.7) & (img[..., 1] < 0.3) & (img[..., 2] < 0.3)
    assert red.sum() > 100  # the red frame of the FAILED banner
    # the warnings table, below the evidence table, is on the first screen too: its
    # amber (warning) and green (passed) cells show without scrolling
    assert _tinted(img, (0xFF, 0xF3, 0xD6)) > 2000 and _tinted(img, (0xEE, 0xF8, 0xEE)) > 2000


def test_the_checks_can_fail(tmp_path):
    bad = tmp_path / "control.html"
    bad.write_text("<!DOCTYPE html><html><body><p>control</p>"
                   '<img src="http://example.invalid/x.png">'
                   f'<img src="data:image/png;base64,{_PNG}">'
                   f'<img src="data:image/png;base64,{_PNG[:40]}">' + _PROBE + "</body></html>")
    dom, requests = _chromium(bad, tmp_path, "--dump-dom")
    assert requests == ["http://example.invalid/x.png"]
    assert _images_ok(dom) == [0, 1, 0]
