"""Open an HTML report in headless Chromium (from ``file://``, network blocked) and
report what happened: JavaScript errors, the plot DOM that was built, a screenshot.

The page is opened as a copy with a small probe script first in ``<head>``: it records
uncaught errors, failed resource loads (capture-phase ``error`` events),
``console.error`` calls and unhandled promise rejections, and after the load writes a
JSON summary (errors, counts of plotly plots, SVG layers and WebGL canvases, each
plot's page rectangle) into a ``<pre>`` that ``--dump-dom`` returns.  Chromium's own
console log (``--enable-logging=stderr``) is returned too.  Also used by
docs/gen_report_images.py to take the guides' screenshots."""

from __future__ import annotations

import html.parser
import json
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
         "--disable-quic", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync", "--hide-scrollbars",
         "--host-resolver-rules=MAP * ~NOTFOUND", "--enable-logging=stderr", "--v=0"]

PROBE = """<script>
window.__gk = [];
addEventListener('error', function (e) {
  var t = e.target;
  __gk.push(t && t !== window ? 'resource failed: ' + (t.src || t.href || t.tagName)
                              : 'error: ' + e.message);
}, true);
addEventListener('unhandledrejection', function (e) { __gk.push('rejection: ' + e.reason); });
(function () { var ce = console.error; console.error = function () {
  __gk.push('console.error: ' + Array.prototype.join.call(arguments, ' '));
  return ce.apply(console, arguments); }; })();
addEventListener('load', function () { setTimeout(function () {
  var plots = document.querySelectorAll('.js-plotly-plot'), rects = [];
  plots.forEach(function (p) { var b = p.getBoundingClientRect();
    rects.push({x: b.left, y: b.top + scrollY, w: b.width, h: b.height,
                gl: !!p.querySelector('.gl-container canvas')}); });
  var pre = document.createElement('pre'); pre.id = 'geomkit-probe'; pre.style.display = 'none';
  pre.textContent = JSON.stringify({errors: __gk, plots: plots.length,
    svg: document.querySelectorAll('svg.main-svg').length,
    gl: document.querySelectorAll('.gl-container canvas').length, rects: rects,
    webgl: !!document.createElement('canvas').getContext('webgl')});
  document.body.appendChild(pre); }, 2000); });
</script>"""

ERROR_WORDS = re.compile(r"Uncaught|Error|ERR_|Failed|failed|not supported|deprecated")


def chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome", "chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


class _Refs(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.refs = []

    def handle_starttag(self, tag, attrs):
        for k, v in attrs:
            if k in ("src", "href", "data", "poster", "srcset", "action") and v:
                self.refs.append((tag, k, v))


def external_refs(text: str) -> list:
    """Attributes of HTML tags that load something from a URL (``http(s)://``, ``//``),
    and CSS ``url(http...)`` / ``@import``: what a page would fetch from the network."""
    p = _Refs()
    p.feed(text)
    bad = [r for r in p.refs if re.match(r"\s*(https?:)?//", r[2], re.I)
           and not (r[0] == "a" and r[1] == "href")]  # links are not loads
    bad += re.findall(r"url\(\s*['\"]?\s*(?:https?:)?//[^)]*\)", _styles(text), re.I)
    bad += re.findall(r"@import\s+[^;]*", _styles(text), re.I)
    return bad


def _styles(text):
    return " ".join(re.findall(r"<style[^>]*>(.*?)</style>", text, re.S | re.I))


def open_report(path, screenshot=None, size=(1280, 1600), budget_ms=15000, timeout=180):
    """Load ``path`` in headless Chromium; returns ``{"probe": {...} or None,
    "console": [chromium console lines], "returncode", "screenshot": Path or None}``."""
    exe = chromium()
    if exe is None:
        raise RuntimeError("no chromium")
    src = Path(path).read_text(encoding="utf-8")
    with tempfile.TemporaryDirectory(prefix="geomkit-browser-") as tmp:
        tmp = Path(tmp)
        page = tmp / "page.html"
        i = src.lower().index("<head>") + len("<head>")
        page.write_text(src[:i] + PROBE + src[i:], encoding="utf-8")
        (tmp / "profile").mkdir()
        shot = tmp / "shot.png"
        cmd = [exe, *FLAGS, f"--user-data-dir={tmp / 'profile'}",
               f"--window-size={size[0]},{size[1]}", f"--virtual-time-budget={budget_ms}",
               f"--screenshot={shot}", "--dump-dom", page.as_uri()]
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        m = re.search(r'<pre id="geomkit-probe"[^>]*>(.*?)</pre>', r.stdout, re.S)
        probe = json.loads(html.unescape(m.group(1))) if m else None
        console = [ln for ln in r.stderr.splitlines() if ":CONSOLE" in ln]
        out = None
        if screenshot is not None and shot.exists():
            out = Path(screenshot)
            shutil.copyfile(shot, out)
        return {"probe": probe, "console": console, "returncode": r.returncode,
                "screenshot": out, "stderr": r.stderr[-2000:]}


def console_errors(lines) -> list:
    """Chromium console lines that report an error (not performance notes such as
    "GPU stall due to ReadPixels" or canvas read-back hints)."""
    bad = []
    for ln in lines:
        msg = ln.split("] ", 1)[-1]
        if "GL Driver Message" in msg and "Performance" in msg:
            continue
        if "willReadFrequently" in msg:
            continue
        if ERROR_WORDS.search(msg):
            bad.append(msg)
    return bad
