"""The page a browser loads, and what the server sets on it.

viser serves one self-contained `index.html` (its client inlined). theoria serves a copy with:

- the tab titled "theoria" from the first byte (the session then names the scenario);
- a visible line ("theoria — connecting…") from the first bytes parsed until the first scene is
  drawn, so the page is never blank while the client starts and the first scene is prepared;
- CSS that hides viser's own chrome a class has no use for from the first frame.

The copy is written once per viser version into theoria's cache directory (a temporary
directory when that is not writable) and used as viser's HTTP root while a server is built
(`themed_client`).
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import tempfile
import threading
from pathlib import Path

import viser
from viser import infra

from .browser import run_js
from .worker import cache_root

TITLE = "theoria"
LOADING = "theoria — connecting…"
# The loading line is shown over the page from its first frame until the first scene is drawn
# (`set_loading(client, None)`). While it is there, viser's panel is hidden, its header too: before
# the app's controls arrive, viser fills it with its developer tools (the websocket address, "Save
# Canvas", "Dev Settings", the scene tree), which a class has no use for.
# The box beside a slider is 3rem wide in viser: "0.00002" (a tidal rate) showed as "0.0000" and a
# value with ten digits as its first five. It grows with its text (up to 8rem) instead.
CSS = """
#theoria-loading{position:fixed;left:50%;top:45%;transform:translate(-50%,-50%);z-index:10000;
  font:17px/1.4 system-ui,sans-serif;color:#222;background:rgba(255,255,255,.94);padding:10px 18px;
  border-radius:8px;box-shadow:0 1px 6px rgba(0,0,0,.15);pointer-events:none;max-width:70vw;text-align:center}
body:has(#theoria-loading) .mantine-ScrollArea-root{visibility:hidden}
body:has(#theoria-loading) .mantine-Paper-root:has(.mantine-ScrollArea-root){visibility:hidden}
.mantine-NumberInput-root{width:auto!important;min-width:3rem;max-width:8rem}
.mantine-NumberInput-input{field-sizing:content;min-width:3rem;max-width:8rem}
"""
# A page that has not reached the server after CONNECT_HINT_S still says only "connecting…": a
# student's eleventh tab (the server takes ten from one address, or a class's whole room behind one
# address), a full server, a server stopped. The server cannot tell the page why (it refuses the
# socket viser's client keeps retrying), so the line says what to try; it connects, and the line
# goes, as soon as the server takes it.
CONNECT_HINT_S = 10
CONNECT_HINT = ("theoria — still connecting… The server may be busy or full, or this computer may already have "
                "as many theoria tabs open as the server takes from one address: close one, and this tab connects.")
CONNECT_HINT_JS = (f"setTimeout(function(){{var e=document.getElementById('theoria-loading');"
                   f"if(e&&e.textContent=={json.dumps(LOADING)}){{e.textContent={json.dumps(CONNECT_HINT)};}}}},"
                   f"{CONNECT_HINT_S * 1000});")
LOADING_HTML = f'<div id="theoria-loading">{LOADING}</div><script>{CONNECT_HINT_JS}</script>'
# Run before viser's client starts. In software WebGL (no GPU: SwiftShader, llvmpipe; the names
# viser's own check looks for) multisampled antialiasing is the dearest part of each frame, so
# the page asks for a canvas without it (with the savings of app/browser.py `lighten`,
# middle-axis-flip at 1280x800 played 22.7 -> 33.2 poses a second: docs/app.md). viser then shows
# a notice that rendering is in software ("Software WebGL rendering detected"), which would sit
# over a projected scene all lesson: it is taken down as it appears.
SOFTWARE_GL_JS = r"""
(() => {
  let name = '';
  try {
    const g = document.createElement('canvas').getContext('webgl2');
    const x = g && g.getExtension('WEBGL_debug_renderer_info');
    name = x ? String(g.getParameter(x.UNMASKED_RENDERER_WEBGL)) : '';
    const lose = g && g.getExtension('WEBGL_lose_context');
    if (lose) lose.loseContext();
  } catch (e) {}
  const soft = window.__theoriaSoftwareGL = /swiftshader|llvmpipe|softpipe|software/i.test(name);
  if (!soft) return;
  const get = HTMLCanvasElement.prototype.getContext;
  HTMLCanvasElement.prototype.getContext = function (type, attrs) {
    if (type === 'webgl2' || type === 'webgl') attrs = Object.assign({}, attrs || {}, {antialias: false});
    return get.call(this, type, attrs);
  };
  const seen = new MutationObserver(() => {
    for (const n of document.querySelectorAll('.mantine-Notification-root')) {
      if (n.textContent.includes('Software WebGL rendering')) { n.style.display = 'none'; seen.disconnect(); }
    }
  });
  const watch = () => seen.observe(document.body, {childList: true, subtree: true});
  if (document.body) watch(); else document.addEventListener('DOMContentLoaded', watch);
  setTimeout(() => seen.disconnect(), 60000);
})();
"""

_lock = threading.Lock()
_root: Path | None = None


def _viser_index() -> Path:
    return Path(viser.__file__).resolve().parent / "client" / "build" / "index.html"


def themed_index(html: str) -> str:
    html = html.replace("<title>Viser</title>", f"<title>{TITLE}</title>", 1)
    html = html.replace('content="Viser client"', f'content="{TITLE}"', 1)
    html = html.replace("<head>", f"<head><script>{SOFTWARE_GL_JS}</script>", 1)
    # The line goes in before viser's inlined client (an 800 kB script in the head that the browser
    # runs before it reads on), so that it is in the page from the first bytes parsed. The parser
    # opens the body at the div; the client's script then runs from the body, as it may.
    html = html.replace("</title>", f"</title><style>{CSS}</style>{LOADING_HTML}", 1)
    return html


def client_root() -> Path:
    """A directory holding theoria's copy of viser's index.html."""
    global _root
    with _lock:
        if _root is not None and (_root / "index.html").exists():
            return _root
        src = _viser_index()
        html = themed_index(src.read_text(encoding="utf-8"))
        digest = hashlib.blake2b(html.encode(), digest_size=8).hexdigest()
        for base in (cache_root() / "client", Path(tempfile.gettempdir()) / "theoria-client"):
            d = base / f"{viser.__version__}-{digest}"
            try:
                if not (d / "index.html").exists():
                    d.mkdir(parents=True, exist_ok=True)
                    tmp = d / "index.html.tmp"
                    tmp.write_text(html, encoding="utf-8")
                    tmp.replace(d / "index.html")
                _root = d
                return d
            except OSError:
                continue
        return src.parent


class _Served(type(Path())):
    """The page's directory as viser's HTTP server reads it. viser asks `is_file()` of the path a
    request names; a name longer than the filesystem holds (a 300-character URL path) raised
    ENAMETOOLONG there, which the server answered with 500 Internal Server Error. Here it is a
    file that is not there: 404, as for any other name."""

    def is_file(self) -> bool:
        try:
            return super().is_file()
        except OSError:
            return False


_build_lock = threading.Lock()


@contextlib.contextmanager
def themed_client():
    """While a ViserServer is built inside this block, its HTTP root is theoria's page."""
    root = client_root()
    cls = infra.WebsockServer
    with _build_lock:
        original = cls.__init__

        def init(self, *args, **kwargs):
            if kwargs.get("http_server_root") is not None:
                kwargs["http_server_root"] = _Served(root)
            original(self, *args, **kwargs)

        cls.__init__ = init
        try:
            yield
        finally:
            cls.__init__ = original


def set_loading(client, text: str | None) -> None:
    """The line over the page: `text`, or gone (None)."""
    if text is None:
        run_js(client, "var e=document.getElementById('theoria-loading'); if(e){e.remove();}")
    else:
        run_js(client, "var e=document.getElementById('theoria-loading'); if(!e){e=document.createElement('div');"
                       "e.id='theoria-loading';document.body.appendChild(e);} e.textContent=" + json.dumps(text) + ";")
