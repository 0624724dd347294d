"""Small pieces of JavaScript the app runs in a browser (viser's RunJavascript message), for what
viser's GUI API does not offer: the tab's title, the address bar holding the view's state, the
framing of the scene beside the control panel, a typed value taken when its field loses focus,
a click on a sweep's map, and presenter mode's large type.

Each helper is idempotent and cheap; they are installed once per page by `SETUP` and then called
as `window.theoria.<name>(...)`. The JavaScript reads only its own page (no network).
"""
from __future__ import annotations

import json

from viser import _messages

# Installed once per page.
#
# - frame(): the control panel floats over the right of the canvas; the camera's view is offset
#   (three.js setViewOffset) by half the width the panel covers, so the point the camera looks at
#   is drawn in the middle of the free part of the canvas, and orbiting still turns about it.
#   Re-run on resize, on panel changes and every half second (the panel can be folded).
# - focusout on a text field inside a form submits the form: a typed value is taken on Enter or
#   when the field loses focus, never per keystroke.
# - a form's submit waits SUBMIT_AFTER_MS: viser 1.1 sends all of a panel's messages through one
#   throttled sender (50 ms, the latest message wins), so a value typed and submitted within 50 ms
#   (Enter right after the last key, or typing into a field just after leaving another, whose
#   submit opened the window) reached the server as the submit alone and the server took the
#   field's previous text. Held back longer than the throttle, the submit goes after the value.
# - present(on): presenter mode's large type (the panel scaled about its top right corner).
SETUP = r"""
(() => {
  if (window.theoria) return;
  const T = window.theoria = {};
  // viser's control panel: the Mantine Paper that holds a scroll area (notifications are Papers too)
  T.PANEL = '.mantine-Paper-root:has(.mantine-ScrollArea-root)';
  T.panel = () => {
    const el = document.querySelector(T.PANEL);
    return el && el.getBoundingClientRect().width > 0 ? el : null;
  };
  T.covered = () => {
    const m = window.__viserMutable, p = T.panel();
    if (!m || !m.canvas || !p) return 0;
    const c = m.canvas.getBoundingClientRect(), r = p.getBoundingClientRect();
    if (r.left <= c.left + c.width / 2) return 0;  // not a panel on the right
    return Math.max(0, c.right - r.left);
  };
  T.frame = () => {
    const m = window.__viserMutable;
    if (!m || !m.camera || !m.canvas) return;
    const w = m.canvas.clientWidth, h = m.canvas.clientHeight;
    if (!w || !h) return;
    const dx = Math.round(T.covered() / 2);
    const v = m.camera.view;
    if (v && v.enabled && v.offsetX === dx && v.fullWidth === w && v.fullHeight === h) return;
    if (dx === 0) { if (v && v.enabled) m.camera.clearViewOffset(); }
    else m.camera.setViewOffset(w, h, dx, 0, w, h);
    m.camera.updateProjectionMatrix();
    if (m.requestRender) m.requestRender();
  };
  window.addEventListener('resize', () => setTimeout(T.frame, 50));
  setInterval(T.frame, 500);
  document.addEventListener('focusout', (e) => {
    const t = e.target;
    if (t && t.tagName === 'INPUT' && (t.type === 'text' || t.type === '') && t.form && t.form.requestSubmit)
      t.form.requestSubmit();
  }, true);
  // a sweep's map (app/sweep_map.py): a click sets the map's hidden field to "row,column,view,n"
  // (row 0 at the bottom), sent as an ordinary control value; n makes a second click on the same
  // pixel a new value
  T.clicks = 0;
  document.addEventListener('click', (e) => {
    const img = e.target && e.target.closest ? e.target.closest('img[data-theoria-map]') : null;
    const m = window.__viserMutable;
    if (!img || !m || !m.sendMessage) return;
    const r = img.getBoundingClientRect(), rows = +img.dataset.rows, cols = +img.dataset.cols;
    const j = Math.min(cols - 1, Math.max(0, Math.floor((e.clientX - r.left) / r.width * cols)));
    const i = Math.min(rows - 1, Math.max(0, Math.floor((r.bottom - e.clientY) / r.height * rows)));
    T.clicks += 1;
    m.sendMessage({type: 'GuiUpdateMessage', uuid: img.dataset.uuid,
                   updates: {value: i + ',' + j + ',' + img.dataset.key + ',' + T.clicks}});
  }, true);
  T.SUBMIT_AFTER_MS = 120;
  document.addEventListener('submit', (e) => {
    const f = e.target;
    if (!f || f.tagName !== 'FORM' || f.__theoriaNow) return;
    e.preventDefault();
    e.stopImmediatePropagation();  // viser's handler sees the submit when it is sent again below
    clearTimeout(f.__theoriaTimer);  // Enter then blur: one submit
    f.__theoriaTimer = setTimeout(() => {
      f.__theoriaNow = true;
      try { if (f.isConnected) f.requestSubmit(); } finally { f.__theoriaNow = false; }
    }, T.SUBMIT_AFTER_MS);
  }, true);
  T.title = (text) => { document.title = text; };
  T.url = (query) => {
    const q = query ? '?' + query : '';
    if (window.location.search !== q) history.replaceState(null, '', window.location.pathname + q);
  };
  T.present = (on) => {
    let s = document.getElementById('theoria-present');
    if (on && !s) {
      s = document.createElement('style');
      s.id = 'theoria-present';
      // scaled about its top right corner: the panel stays where it floats (zoom moved it off screen)
      s.textContent = T.PANEL + '{transform:scale(1.45);transform-origin:top right}';
      document.head.appendChild(s);
    } else if (!on && s) s.remove();
    setTimeout(T.frame, 50);
  };
  T.frame();
})();
"""

# The page's address (its query holds a shared view) handed to the server through viser's
# localStorage channel: written under the prefix viser uses for the key `probe`.
ADDRESS_KEY = "theoria-address"
WRITE_ADDRESS = r"""
(() => {
  const k = Object.keys(localStorage).find(k => k.endsWith('%s-probe'));
  if (k) localStorage.setItem(k.slice(0, -'-probe'.length), window.location.href);
})();
""" % ADDRESS_KEY


def run_js(client, source: str) -> bool:
    """Run `source` in the browser of `client` (False if the client cannot: a test's fake)."""
    try:
        client._websock_connection.queue_message(_messages.RunJavascriptMessage(source=source))
        return True
    except Exception:
        return False


def call(client, name: str, *args) -> bool:
    """`window.theoria.<name>(*args)` in the browser (the session sends SETUP first: messages
    arrive in order)."""
    return run_js(client, f"window.theoria && window.theoria.{name}({', '.join(json.dumps(a) for a in args)});")


def read_address(client, timeout: float = 10.0) -> str | None:
    """The address the browser opened (with its query), or None (no answer, or a fake client). A
    page answers within milliseconds; the generous timeout is for a loaded machine, where a link
    answered late would otherwise be ignored."""
    try:
        ls = client.local_storage
        ls.set_item(ADDRESS_KEY + "-probe", "1")
        if not run_js(client, WRITE_ADDRESS):
            return None
        return ls.get_item(ADDRESS_KEY, timeout=timeout)
    except Exception:
        return None
