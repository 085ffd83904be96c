"""The replay page: one self-contained HTML file, meshcat's viewer and the scene inlined.

The viewer bundle shipped by the ``meshcat`` Python package (``viewer/dist/main.min.js``: three.js,
the orbit controls, the dat.GUI panel with the animation's play, pause, reset and time slider)
is inlined in a ``<script>``; the scene is a list of meshcat commands, each msgpack-packed and
base64-encoded on one line of a ``<script type="text/plain" id="urpc-commands">``, which the page
feeds to ``viewer.handle_command_bytearray`` exactly as a meshcat server would over its websocket.
No server, no network: the file opens from disk (``file://``).
"""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path
from typing import Any

#: Where the camera looks from, relative to the scene's center (world axes, z up): this
#: direction, at this many times the scene's radius.
CAMERA_DIRECTION, CAMERA_DISTANCE = (1.0, -3.0, 1.5), 1.8

_STYLE = """
body { margin: 0; overflow: hidden; font-family: sans-serif; }
#meshcat-pane { width: 100vw; height: 100vh; overflow: hidden; }
#urpc-label { position: absolute; left: 12px; top: 10px; padding: 4px 8px; font-size: 14px;
  background: rgba(255, 255, 255, 0.8); border-radius: 4px; pointer-events: none;
  max-width: calc(100vw - 300px); }
"""

_BOOT = """
(function () {
  var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
  var lines = document.getElementById("urpc-commands").textContent.split("\\n");
  lines.forEach(function (line) {
    line = line.trim();
    if (!line) return;
    var raw = atob(line), bytes = new Uint8Array(raw.length);
    for (var i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
    viewer.handle_command_bytearray(bytes);
  });
  var info = JSON.parse(document.getElementById("urpc-info").textContent);
  // Look at the scene's center (world axes, z up) from info.camera; the camera sits in
  // three.js' y-up world, where meshcat's (x, y, z) is (x, z, -y).
  var c = info.center, p = [c[0] + info.camera[0], c[1] + info.camera[1], c[2] + info.camera[2]];
  viewer.camera.position.set(p[0], p[2], -p[1]);
  viewer.controls.target.set(c[0], c[2], -c[1]);
  viewer.controls.update();
  // The panel shows the animation's play, pause, reset and time slider; the scene tree folded.
  viewer.gui.open();
  if (viewer.gui.__folders.Scene) viewer.gui.__folders.Scene.close();
  var label = document.getElementById("urpc-label");
  function show() {
    var t = viewer.animator.time || 0, text = info.title;
    info.segments.forEach(function (segment) {
      if (t >= segment.start - 1e-9 && segment.label) text = info.title + ": " + segment.label;
    });
    label.textContent = text + "   t = " + t.toFixed(2) + " / " + info.duration.toFixed(2) + " s";
  }
  (function loop() { show(); requestAnimationFrame(loop); })();
  window.urpcViewer = viewer;
})();
"""


def viewer_script() -> str:
    """meshcat's viewer bundle (``main.min.js``) from the installed ``meshcat`` package."""
    import meshcat

    return (Path(meshcat.viewer_assets_path()) / "dist" / "main.min.js").read_text(encoding="utf-8")


def pack(command: Any) -> str:
    """One meshcat command, msgpack-packed (as meshcat's own server sends it), in base64."""
    import umsgpack

    return base64.b64encode(umsgpack.packb(command.lower())).decode("ascii")


def unpack(line: str) -> dict[str, Any]:
    """The lowered command behind one line of the page (for tests and inspection)."""
    import umsgpack

    return umsgpack.unpackb(base64.b64decode(line))


def page_commands(text: str) -> list[dict[str, Any]]:
    """The lowered commands of a replay page."""
    start = text.index('<script type="text/plain" id="urpc-commands">')
    body = text[text.index(">", start) + 1 : text.index("</script>", start)]
    return [unpack(line) for line in body.split() if line]


def page_info(text: str) -> dict[str, Any]:
    """The page's metadata (title, duration [s], segments, fps)."""
    start = text.index('<script type="application/json" id="urpc-info">')
    return json.loads(text[text.index(">", start) + 1 : text.index("</script>", start)])


def render_page(title: str, commands: list[Any], info: dict[str, Any]) -> str:
    """The HTML document."""
    lines = "\n".join(pack(command) for command in commands)
    norm = sum(c * c for c in CAMERA_DIRECTION) ** 0.5
    camera = [CAMERA_DISTANCE * info["radius"] * c / norm for c in CAMERA_DIRECTION]
    metadata = json.dumps({"title": title, **info, "camera": camera}).replace("</", "<\\/")
    return (
        '<!DOCTYPE html>\n<html>\n<head>\n<meta charset="utf-8">\n'
        f"<title>{html.escape(title)}</title>\n<style>{_STYLE}</style>\n</head>\n<body>\n"
        '<div id="meshcat-pane"></div>\n<div id="urpc-label"></div>\n'
        f"<script>\n{viewer_script()}\n</script>\n"
        f'<script type="text/plain" id="urpc-commands">\n{lines}\n</script>\n'
        f'<script type="application/json" id="urpc-info">{metadata}</script>\n'
        f"<script>{_BOOT}</script>\n</body>\n</html>\n"
    )
