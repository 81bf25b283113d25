"""The replay page: one self-contained HTML file (meshcat's three.js viewer, the scene and its animation, and a
small overlay), written atomically.

The page needs no network and no server: meshcat's ``main.min.js`` (three.js, its controls and loaders, msgpack)
is inlined as meshcat's own static export inlines it, and the scene is a list of base64 meshcat commands replayed
synchronously on load. The overlay (plain DOM, about 100 lines of JavaScript) adds what meshcat's player lacks: a
play/pause button and a time slider under the view, the time, the move and the suction state at each moment, the
halt and its message on a fault (a red mark on the slider), and the address ``replay.html#t=12.5``: opening it
shows 12.5 s of the run, paused; pausing writes the current moment into the address, so it can be shared.
"""

from __future__ import annotations

import base64
import html
import json
from importlib import resources
from pathlib import Path
from typing import Any

from ur3hanoi.errors import OutputError
from ur3hanoi.io.atomic import atomic_write
from ur3hanoi.replay.timeline import Timeline


def meshcat_js() -> str:
    """meshcat's bundled viewer (three.js included), as its static export inlines it."""
    try:
        return (resources.files("meshcat") / "viewer" / "dist" / "main.min.js").read_text(encoding="utf-8")
    except (ModuleNotFoundError, FileNotFoundError) as exc:
        raise OutputError(f"cannot write the replay page: meshcat's viewer is not installed ({exc})") from None


OVERLAY_CSS = """
body { margin: 0; font: 14px/1.35 system-ui, sans-serif; }
#meshcat-pane { width: 100vw; height: 100vh; overflow: hidden; }
#ur3-info { position: fixed; left: 10px; top: 10px; background: rgba(255,255,255,0.88); padding: 8px 12px;
  border-radius: 6px; max-width: 55vw; box-shadow: 0 1px 4px rgba(0,0,0,0.25); }
#ur3-info h1 { font-size: 15px; margin: 0 0 4px 0; }
#ur3-fault { color: #b00; font-weight: 600; margin-top: 4px; }
#ur3-fault.past { background: #fdd; }
#ur3-bar { position: fixed; left: 10px; right: 10px; bottom: 10px; display: flex; gap: 10px; align-items: center;
  background: rgba(255,255,255,0.88); padding: 6px 10px; border-radius: 6px; box-shadow: 0 1px 4px rgba(0,0,0,0.25); }
#ur3-slider-box { position: relative; flex: 1; }
#ur3-slider { width: 100%; }
#ur3-halt-mark { position: absolute; top: -4px; width: 3px; height: 26px; background: #d00; pointer-events: none; }
#ur3-time { font-variant-numeric: tabular-nums; min-width: 9em; text-align: right; }
#ur3-play { min-width: 5em; }
"""

OVERLAY_HTML = """
<div id="ur3-info"><h1 id="ur3-title"></h1><div id="ur3-move"></div><div id="ur3-suction"></div>
<div id="ur3-fault" hidden></div></div>
<div id="ur3-bar"><button id="ur3-play">Play</button>
<div id="ur3-slider-box"><input id="ur3-slider" type="range" min="0" step="0.01" value="0">
<div id="ur3-halt-mark" hidden></div></div><span id="ur3-time"></span></div>
"""

OVERLAY_JS = r"""
(function () {
  const T = UR3_TIMELINE, dur = T.duration, anim = viewer.animator;
  const $ = (id) => document.getElementById(id);
  const slider = $("ur3-slider"), play = $("ur3-play");
  slider.max = dur;
  $("ur3-title").textContent = T.title;
  if (viewer.gui && viewer.gui.close) viewer.gui.close();
  // meshcat's player: make every clip active, then drive its time from here (seek), meshcat's clock stopped.
  if (anim.actions.length) { anim.play(); anim.pause(); }
  if (T.fault) {
    const f = $("ur3-fault"), mark = $("ur3-halt-mark");
    f.hidden = false;
    f.textContent = "halted at " + T.fault.t.toFixed(2) + " s: " + T.fault.message;
    mark.hidden = false;
    mark.style.left = (100 * T.fault.t / Math.max(dur, 1e-9)) + "%";
  }
  let t = 0, playing = false, last = null;
  function index(x) {  // last frame at or before x
    let lo = 0, hi = T.t.length - 1;
    while (lo < hi) { const mid = (lo + hi + 1) >> 1; if (T.t[mid] <= x + 1e-6) lo = mid; else hi = mid - 1; }
    return lo;
  }
  function show() {
    const i = index(t), m = T.move[i];
    $("ur3-time").textContent = t.toFixed(2) + " s / " + dur.toFixed(2) + " s";
    slider.value = t;
    let what;
    if (T.fault && t >= T.fault.t) {
      what = "halted" + (T.fault.move ? " in move " + T.fault.move + "/" + T.moves.length : "") +
          ": the arm stops, the suction goes off, the arm returns home";
    }
    else if (m >= 0) what = "move " + (m + 1) + "/" + T.moves.length + ": " + T.moves[m];
    else if (T.t[i] < 1e-9 || T.move.slice(0, i).every((v) => v < 0)) what = "at the start";
    else what = "returning home";
    $("ur3-move").textContent = what;
    $("ur3-suction").textContent = "suction " + (T.suction[i] ? "ON" : "off") +
        (T.held[i] ? ", block held (DIGIN 1)" : ", nothing held (DIGIN 0)");
    if (T.fault) $("ur3-fault").classList.toggle("past", t >= T.fault.t);
  }
  function seek(x) {
    t = Math.max(0, Math.min(dur, x));
    if (anim.actions.length) { anim.seek(t); anim.display_progress(t); }
    viewer.set_dirty();
    show();
  }
  function setPlaying(p, byUser) {
    playing = p; last = null;
    play.textContent = p ? "Pause" : "Play";
    // Paused by the user: the address names this moment, to share it (not while the page loads).
    if (!p && byUser) history.replaceState(null, "", "#t=" + t.toFixed(2));
  }
  function fromHash() {
    const m = /(?:^#|&)t=([0-9]*\.?[0-9]+)/.exec(location.hash);
    if (!m) return false;
    setPlaying(false);
    seek(parseFloat(m[1]));
    return true;
  }
  play.onclick = () => { if (!playing && t >= dur) seek(0); setPlaying(!playing, true); };
  slider.oninput = () => { playing = false; play.textContent = "Play"; seek(parseFloat(slider.value)); };
  slider.onchange = () => setPlaying(false, true);
  window.addEventListener("hashchange", fromHash);
  function tick(now) {
    if (playing) {
      if (last !== null) seek(t + (now - last) / 1000);
      last = now;
      if (t >= dur) setPlaying(false);
    }
    requestAnimationFrame(tick);
  }
  window.ur3replay = { seek: seek, time: () => t, play: () => setPlaying(true), pause: () => setPlaying(false) };
  if (!fromHash()) { seek(0); setPlaying(true); }
  requestAnimationFrame(tick);
})();
"""


def page_html(commands: list[bytes], timeline: Timeline, title: str) -> str:
    """The whole page as text."""
    blobs = ",\n".join(json.dumps(base64.b64encode(c).decode("ascii")) for c in commands)
    data: dict[str, Any] = timeline.to_json()
    # "</" in a JSON string must not close the script element.
    timeline_js = json.dumps(data).replace("</", "<\\/")
    js = meshcat_js().replace("</script", "<\\/script")
    return f"""<!DOCTYPE html>
<html lang="en">
<head><meta charset="utf-8"><title>{html.escape(title)}</title>
<meta name="generator" content="ur3hanoi (meshcat {_meshcat_version()} three.js viewer)">
<style>{OVERLAY_CSS}</style></head>
<body>
<div id="meshcat-pane"></div>
{OVERLAY_HTML}
<script>{js}</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
(function () {{
  const blobs = [
{blobs}
  ];
  for (const b of blobs) {{
    const s = atob(b), a = new Uint8Array(s.length);
    for (let i = 0; i < s.length; i++) a[i] = s.charCodeAt(i);
    viewer.handle_command_bytearray(a);
  }}
}})();
var UR3_TIMELINE = {timeline_js};
</script>
<script>{OVERLAY_JS}</script>
</body>
</html>
"""


def _meshcat_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("meshcat")
    except PackageNotFoundError:
        return "?"


def write_page(path: str | Path, commands: list[bytes], timeline: Timeline, title: str,
               inputs: tuple[Path, ...] = ()) -> int:
    """Write the page to ``path`` atomically (see :mod:`ur3hanoi.io.atomic`); returns its size [bytes]."""
    text = page_html(commands, timeline, title)
    atomic_write(path, text, inputs=inputs)
    return len(text.encode("utf-8"))
