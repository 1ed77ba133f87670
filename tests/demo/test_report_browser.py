"""The demo's HTML report opens in headless Chromium without errors and is not blank (slow).

Needs Debian's ``chromium`` package (``apt-get install chromium``); the README's slow-test
command says so. Chromium is started with the flags this closed-network machine needs.
"""

import base64
import re
import shutil
import subprocess

import numpy as np
import pytest

from fsrbayes.demo import QUICK, run_demo

CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--enable-logging=stderr",
    "--v=0",
    "--virtual-time-budget=10000",
]

# Appended to a copy of the report: after load, log how many images decoded (naturalWidth > 0).
IMAGE_PROBE = """<script>window.addEventListener("load", () => {
  const images = Array.from(document.images);
  const ok = images.filter(im => im.complete && im.naturalWidth > 0).length;
  console.log("IMAGES " + ok + "/" + images.length);
});</script>"""


def _chromium():
    path = shutil.which("chromium") or shutil.which("chromium-browser")
    assert path, (
        "headless Chromium is needed for this test: apt-get install chromium (Debian's package)"
    )
    return path


def _run_chromium(args, tmp_path):
    run = subprocess.run(
        [_chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'profile'}", *args],
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    return run


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    run_demo(out, QUICK, processes=2, echo=lambda line: None)
    return out / "report.html"


@pytest.mark.slow
def test_report_is_self_contained(report):
    html = report.read_text(encoding="utf-8")
    sources = re.findall(r'<img[^>]*\ssrc="([^"]+)"', html)
    assert len(sources) >= 6
    for src in sources:
        assert src.startswith("data:image/png;base64,"), src[:80]
        assert base64.b64decode(src.split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"
    assert not re.search(r'(?:src|href)="(?:file:|/|\.\.?/)', html)


@pytest.mark.slow
def test_report_opens_in_headless_chromium_and_is_not_blank(report, tmp_path):
    import matplotlib.image

    probed = tmp_path / "probed.html"
    probed.write_text(
        report.read_text(encoding="utf-8").replace("</body>", IMAGE_PROBE + "</body>"),
        encoding="utf-8",
    )
    run = _run_chromium(["--dump-dom", probed.as_uri()], tmp_path)
    console = [line for line in run.stderr.splitlines() if ":CONSOLE" in line]
    counts = [re.search(r"IMAGES (\d+)/(\d+)", line) for line in console]
    counts = [m for m in counts if m]
    assert counts, f"the page's load handler never ran; console: {console}"
    loaded, total = map(int, counts[-1].groups())
    assert total >= 6 and loaded == total, f"{loaded} of {total} images decoded"
    assert not [line for line in console if "IMAGES" not in line], console
    assert "fsrbayes demo" in run.stdout

    shot = tmp_path / "report.png"
    _run_chromium(
        ["--window-size=1280,2400", "--hide-scrollbars", f"--screenshot={shot}", report.as_uri()],
        tmp_path,
    )
    pixels = matplotlib.image.imread(shot)[..., :3]
    non_white = np.mean(pixels.min(axis=-1) < 0.95)
    colours = len(np.unique((pixels * 255).astype(np.uint8).reshape(-1, 3), axis=0))
    assert non_white > 0.05, f"screenshot is nearly blank: {non_white:.3f} of pixels not white"
    assert colours > 50, f"screenshot has only {colours} colours: text but no figures?"
