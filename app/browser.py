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
# - frame(): the control panel is docked beside the canvas, but a user can drag it to float over
#   the canvas; then the camera's view is offset (three.js setViewOffset) by half the width the
#   panel covers, so the point the camera looks at is drawn in the middle of the free part of the
#   canvas, and orbiting still turns about it. Re-run on resize, on panel changes and every half
#   second (the panel can be folded).
# - a number typed into a slider's box: see the code below.
# - focusout on a text field inside a form submits the form: a typed value is taken on Enter or
#   when the field loses focus, never per keystroke.
# - a form's submit waits SUBMIT_AFTER_MS: viser 1.1 sends all of a panel's messages through one
#   throttled sender (50 ms, the latest message wins), so a value typed and submitted within 50 ms
#   (Enter right after the last key, or typing into a field just after leaving another, whose
#   submit opened the window) reached the server as the submit alone and the server took the
#   field's previous text. Held back longer than the throttle, the submit goes after the value;
#   and the value itself is sent once more, directly, just before it: a value pasted within 50 ms
#   of another message waited in the throttle and was replaced by the form's "changed" message.
#   (theoria's forms hold one text field each, named by their label's `for`.)
# - present(on, scale): presenter mode's large type (the docked panel's content zoomed by scale).
# - tracks(d), clock(c), the player: the page plays the scene by itself (app/scene.py `tracks()`).
#   Each frame it draws, after viser has applied the server's state (viser's nodes do that in a
#   render-loop callback of priority -1000; the player's runs at -999), it sets the poses, scales
#   and visibility of frame k, where k follows the clock the server last sent (extrapolated at
#   its rate while playing, exactly the server's frame while paused), and asks for the next frame
#   while playing. Chunks of a path: chunk j is shown from its start frame on. Per-frame props
#   change only while playing: a line's points are written into its geometry in the same frame as
#   the poses (`linePoints`); label text and arrow points go as the same node update the server
#   would send (a SceneNodeUpdateMessage in viser's own queue, under the node's owner), once each
#   time the frame it has them for changes. Paused, the server sets them, exactly; the next play
#   starts from whatever the server set. World matrices are brought up to date before viser's
#   labels read them, so a label on a moving frame is drawn where the frame is in this frame.
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
  // A scene is framed for the canvas beside the docked panel at 1280x800 (~1.1 wide for 1 high);
  // a narrower canvas (a small window, a phone held upright) would cut the sides of the scene off
  // (collinear's third body, the Moon's face seen from the Earth): there the camera zooms out
  // until the scene is as wide as in the canvas it was framed for. (The camera's zoom, not its
  // distance: a student's wheel moves the distance, and the link keeps it.)
  T.ASPECT = 1.1;
  T.frame = () => {
    const m = window.__viserMutable;
    if (!m || !m.camera || !m.canvas) return;
    const w = m.canvas.clientWidth, h = m.canvas.clientHeight;
    if (!w || !h) return;
    const dx = Math.round(T.covered() / 2), zoom = Math.min(1, w / h / T.ASPECT);
    const v = m.camera.view;
    const offset = dx === 0 ? !(v && v.enabled) : (v && v.enabled && v.offsetX === dx && v.fullWidth === w && v.fullHeight === h);
    if (offset && Math.abs(m.camera.zoom - zoom) < 1e-3) return;
    if (dx === 0) { if (v && v.enabled) m.camera.clearViewOffset(); }
    else m.camera.setViewOffset(w, h, dx, 0, w, h);
    if (m.cameraControl && m.cameraControl.zoomTo) m.cameraControl.zoomTo(zoom, false);  // it keeps the camera's zoom
    else m.camera.zoom = zoom;
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
  // an arrow key on a focused slider moves that slider only: viser's command hotkeys (← → step
  // the clock) listen on the document and skip only text fields, so one key did both
  document.body.addEventListener('keydown', (e) => {
    const t = e.target;
    if (t && t.getAttribute && t.getAttribute('role') === 'slider'
        && /^(Arrow(Left|Right|Up|Down)|Home|End|Page(Up|Down))$/.test(e.key)) e.stopPropagation();
  });
  // ← and → step the clock; viser's camera turns on them too (its keys listen on the document), so
  // one key stepped and turned the view: past the hotkeys (on the root element) they stop there
  const typing = (t) => t && t.closest && !!t.closest('input, textarea, select, [contenteditable=true]');
  document.documentElement.addEventListener('keydown', (e) => {
    if ((e.key === 'ArrowLeft' || e.key === 'ArrowRight') && !typing(e.target)) e.stopPropagation();
  });
  // A scene or a preset chosen from its list kept the focus in the list's search box, where the
  // keys (Space, 1–9, ← →) were typed as a search: the box lets go once a choice is made.
  const chosen = () => setTimeout(() => {
    const a = document.activeElement;
    if (a && a.closest && a.closest('.mantine-Select-root')) a.blur();
  }, 0);
  document.addEventListener('click', (e) => {
    if (e.target && e.target.closest && e.target.closest('.mantine-Select-option, [role=option]')) chosen();
  }, true);
  document.addEventListener('keydown', (e) => {
    if (e.key === 'Enter' && e.target && e.target.closest && e.target.closest('.mantine-Select-root')
        && e.target.getAttribute('aria-expanded') === 'true') chosen();
  }, true);
  // A number typed into a slider's box is the user's text until Enter or the box loses focus,
  // then sent as typed, once; the server parses it as a text field's value (exactly, or refused
  // with the allowed range; app/controls.py). The box is Mantine's NumberInput: it dropped an
  // exponent's "e" ("1e-2" became -12), clamped to the slider's range, sent every keystroke, and
  // playback rewrote the time's box between two keys. So none of the box's events reach React
  // (stopped at the window, before React's root sees them), and while it has the focus the page's
  // own re-renders do not rewrite its text (the last is kept, and shown when the edit ends).
  T.sliderOf = (t) => {
    if (!t || t.tagName !== 'INPUT' || !t.classList.contains('mantine-NumberInput-input')) return null;
    const box = t.closest('.mantine-NumberInput-root'), s = box && box.previousElementSibling;
    return s && s.classList.contains('mantine-Slider-root') && s.id ? s : null;
  };
  const VALUE = Object.getOwnPropertyDescriptor(HTMLInputElement.prototype, 'value');
  // The box's blur is kept from React too, so the number field's caret keeper still thinks it has
  // the focus, and on the next value the server sends (the time, twice a second while playing; a
  // preset's values) it called focus() on the box: Space, ← and → then typed into the time's box
  // instead of playing and stepping. A box takes the focus from the user only.
  const FOCUS = HTMLInputElement.prototype.focus;
  T.held = (t) => {
    if (t.__theoria) return t.__theoria;
    const inner = Object.getOwnPropertyDescriptor(t, 'value') || VALUE;  // React's value tracker's
    const h = t.__theoria = {editing: false, shown: VALUE.get.call(t)};
    Object.defineProperty(t, 'value', {configurable: true,
      get() { return inner.get.call(this); },
      set(v) { h.shown = v; if (!h.editing) inner.set.call(this, v); }});
    t.focus = function (...a) { if (document.activeElement === this) return FOCUS.apply(this, a); };
    return h;
  };
  T.hold = (t) => { const h = T.held(t); if (!h.editing) { h.editing = true; h.typed = false; } };
  T.release = (t) => { const h = T.held(t); h.editing = false; t.value = h.shown; };
  T.commit = (t, s) => {
    const h = T.held(t), text = VALUE.get.call(t).trim(), typed = h.editing && h.typed;
    T.release(t);  // the value the server last sent, until it sends the one typed
    const m = window.__viserMutable;
    if (typed && text !== '' && m && m.sendMessage)
      m.sendMessage({type: 'GuiUpdateMessage', uuid: s.id, updates: {value: text}});
  };
  for (const type of ['beforeinput', 'input', 'keypress', 'keyup', 'paste', 'cut', 'change',
                      'compositionstart', 'compositionupdate', 'compositionend'])
    window.addEventListener(type, (e) => {
      if (!T.sliderOf(e.target)) return;
      e.stopImmediatePropagation();
      if (type === 'input') { T.hold(e.target); T.held(e.target).typed = true; }
    }, true);
  // held from focus (a click to select the text, then a key) or from the first key after Enter
  window.addEventListener('focusin', (e) => { if (T.sliderOf(e.target)) T.hold(e.target); }, true);
  window.addEventListener('keydown', (e) => {
    const t = e.target, s = T.sliderOf(t);
    if (!s) return;
    e.stopImmediatePropagation();
    if (e.key === 'Enter') { e.preventDefault(); T.commit(t, s); }
    else if (e.key === 'Escape') { e.preventDefault(); T.release(t); }
    else T.hold(t);
  }, true);
  window.addEventListener('focusout', (e) => {  // Mantine would clamp the box to the range here
    const s = T.sliderOf(e.target);
    if (s) { e.stopImmediatePropagation(); T.commit(e.target, s); }
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
      try {
        if (!f.isConnected) return;
        const m = window.__viserMutable, label = f.querySelector('label[for]');
        const field = f.querySelector('input:not([type=hidden]):not([type=checkbox])');
        if (m && m.sendMessage && label && field)  // the value again, past the throttle
          m.sendMessage({type: 'GuiUpdateMessage', uuid: label.htmlFor, updates: {value: field.value}});
        f.requestSubmit();
      } finally { f.__theoriaNow = false; }
    }, T.SUBMIT_AFTER_MS);
  }, true);
  T.P = {d: null, clock: 0, k: 0, rate: 0, playing: false, at: 0, hooked: false};
  const b64 = (s, C) => {
    const bin = atob(s), u = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) u[i] = bin.charCodeAt(i);
    return new C(u.buffer);
  };
  const half = (h) => {  // an IEEE 754 half-precision number
    const e = (h >> 10) & 31, f = h & 1023, s = h & 32768 ? -1 : 1;
    if (e === 0) return s * f * 5.960464477539063e-8;
    return e === 31 ? (f ? NaN : s * Infinity) : s * (1 + f / 1024) * Math.pow(2, e - 15);
  };
  T.pointsOf = (o) => {  // the geometry of a point cloud node's own points
    if (o.__theoriaPoints && o.__theoriaPoints.parent) return o.__theoriaPoints.geometry;
    let p = null;
    o.traverse((c) => { if (!p && c.isPoints) p = c; });
    o.__theoriaPoints = p;
    return p && p.geometry;
  };
  T.tracks = (d) => {
    d.t = d.times ? b64(d.times, Float32Array) : new Float32Array([0]);
    for (const c of d.chunks || []) c.grow = (c.grow || []).map((s) => b64(s, Uint16Array));
    for (const tr of d.tracks) {
      tr.dim = tr.attr === 'wxyz' ? 4 : tr.attr === 'position' ? 3 : 1;
      tr.v = b64(tr.data, tr.attr === 'wxyz' ? Int16Array : tr.attr === 'visible' ? Uint8Array : Float32Array);
      delete tr.data;
    }
    for (const pr of d.props || []) {
      if (pr.prop === 'text') pr.v = b64(pr.data, Uint32Array);
      else if (pr.dtype === 'f4') pr.v = b64(pr.data, Float32Array);
      else pr.v = Float32Array.from(b64(pr.data, Uint16Array), half);
      pr.last = -1;
      delete pr.data;
    }
    T.P.d = d;
    T.hook();
  };
  T.clock = (c) => {
    Object.assign(T.P, c); T.P.at = performance.now();
    if (T.P.d) for (const pr of T.P.d.props || []) pr.last = -1;  // the server may have set them meanwhile
    T.hook(); T.redraw();
  };
  T.redraw = () => { const m = window.__viserMutable; if (m && m.requestRender) m.requestRender(); };
  T.frameAt = (c) => {  // the first frame whose time is not before c (the server's searchsorted)
    const t = T.P.d.t; let lo = 0, hi = t.length;
    while (lo < hi) { const mid = (lo + hi) >> 1; if (t[mid] < c) lo = mid + 1; else hi = mid; }
    return Math.min(lo, T.P.d.n - 1);
  };
  T.shown = () => {  // the frame on screen now
    const P = T.P;
    if (!P.playing) return Math.min(P.k, P.d.n - 1);
    const c = P.clock + P.rate * (performance.now() - P.at) / 1000;
    return T.frameAt(c - Math.floor(c));
  };
  T.apply = (state) => {
    const P = T.P, d = P.d, m = window.__viserMutable;
    if (!d || !m || !d.n) return;
    const k = T.shown(), R = m.nodeRefFromName, on = (g) => g == null || d.groups[g] !== false;
    P.frame = k;
    for (const tr of d.tracks) {
      const o = R[tr.node], v = tr.v, i = k * tr.dim;
      if (!o) {
        // a label has no object of its own: viser's label renderer reads its place from the pose
        // data each frame (the letter at the tip of a turning ω stayed where it was first put)
        const pose = tr.attr === 'position' && m.nodePoseData && m.nodePoseData[tr.node];
        if (pose) pose.position = [v[i], v[i + 1], v[i + 2]];
        continue;
      }
      if (tr.attr === 'wxyz') o.quaternion.set(v[i + 1], v[i + 2], v[i + 3], v[i]).normalize();
      else if (tr.attr === 'position') o.position.set(v[i], v[i + 1], v[i + 2]);
      else if (tr.attr === 'scale') o.scale.setScalar(v[i]);
      else if (tr.attr === 'visible') o.visible = on(tr.group) && v[i] > 0;
      if (!o.matrixAutoUpdate) o.updateMatrix();
    }
    if (d.props && m.messageQueue) {
      for (const pr of d.props) {
        if (!on(pr.group)) continue;
        const j = P.playing ? Math.floor(k / pr.stride) : -1;
        if (pr.prop === 'points' && T.linePoints(pr, R[pr.node], j)) continue;
        if (j < 0 || j === pr.last) continue;
        pr.last = j;
        const value = pr.prop === 'text' ? pr.strings[pr.v[j]] : pr.v.subarray(j * pr.per, (j + 1) * pr.per);
        m.messageQueue.push({type: 'SceneNodeUpdateMessage', name: pr.node, owner: d.owner,
                             updates: {[pr.prop]: value}});
      }
    }
    for (const c of d.chunks) {
      if (!on(c.group)) continue;
      let n = 0;
      while (n < c.starts.length && c.starts[n] <= k) n++;
      for (let j = 0; j < c.nodes.length; j++) {
        const o = R[c.nodes[j]];
        if (!o) continue;
        o.visible = j < n;
        // the chunk being drawn shows its points up to this frame: the trail ends at the body
        const g = c.grow && c.grow[j] && T.pointsOf(o);
        if (!g) continue;
        const count = j < n - 1 ? Infinity : j === n - 1 ? c.grow[j][Math.min(k - c.starts[j], c.grow[j].length - 1)] : 0;
        if (g.drawRange.count !== count) g.setDrawRange(0, count);
      }
    }
    // viser's labels take their place from their parent's world matrix, which three.js brings up to
    // date only as it renders: without this, a label on a turning body was drawn where the body had
    // been the frame before (on a fast spin, far from its axis)
    if (state && state.scene) state.scene.updateMatrixWorld();
    if (P.playing && state && state.invalidate) state.invalidate();
  };
  // A line's points of frame j (of its stride), written into the line's own geometry in this frame,
  // where viser's node update took effect a frame or more later (a new geometry made by React): the
  // line to F pointed away from F while playing. Paused (j < 0), the line is given back the points
  // the server last set (it sets the paused frame's, exactly). False: not a line (arrows).
  T.linePoints = (pr, o, j) => {
    if (!o) return true;  // not made yet: the server's first points come with it
    let line = null;  // the node's own line, below viser's group(s) for it
    o.traverse((c) => { if (!line && c.isLineSegments2) line = c; });
    const g = line && line.geometry, a = g && g.attributes && g.attributes.instanceStart;
    if (!a || a.data.array.length !== pr.per) return false;
    if (j < 0) {
      if (g.__theoriaServer) { a.data.array.set(g.__theoriaServer); g.__theoriaServer = null; }
      else return true;
    } else {
      if (j === pr.last && g === pr.geometry) return true;
      if (!g.__theoriaServer) g.__theoriaServer = a.data.array.slice();
      a.data.array.set(pr.v.subarray(j * pr.per, (j + 1) * pr.per));
      pr.last = j; pr.geometry = g;
    }
    a.data.needsUpdate = true;
    g.computeBoundingSphere();
    return true;
  };
  T.hook = () => {
    if (T.P.hooked) return;
    const m = window.__viserMutable, root = m && m.scene && m.scene.__r3f && m.scene.__r3f.root;
    if (!root || !root.getState().internal) { setTimeout(T.hook, 100); return; }
    T.P.hooked = true;
    root.getState().internal.subscribe({current: (s) => { T.lighten(s); T.apply(s); }}, -999, root);
    T.redraw();
  };
  // What each frame need not draw. viser's background-image quad covers the canvas and, with no
  // image set, discards every pixel it covers: it is skipped while it has no image. No theoria
  // scene casts a shadow (every light is made without), so the renderer keeps no shadow maps.
  // In software WebGL (no GPU) each costs frames: with app/page.py's canvas without multisampling,
  // playback at 1280x800 went from 22.7 to 33.2 poses a second (SwiftShader; docs/app.md).
  T.lighten = (st) => {
    if (st.gl && st.gl.shadowMap && st.gl.shadowMap.enabled) st.gl.shadowMap.enabled = false;
    const bg = T.P.bg || (T.P.bg = st.scene.children.find(o => o.isMesh && o.material && o.material.uniforms &&
                                                           o.material.uniforms.colorMap && o.material.uniforms.enabled));
    if (bg) bg.visible = !!bg.material.uniforms.enabled.value;
  };
  T.title = (text) => { document.title = text; };
  T.url = (query) => {
    const q = query ? '?' + query : '';
    if (window.location.search !== q) history.replaceState(null, '', window.location.pathname + q);
  };
  T.present = (on, scale) => {
    let s = document.getElementById('theoria-present');
    if (on && !s) {
      s = document.createElement('style');
      s.id = 'theoria-present';
      // the docked panel is widened by the server by the same factor; zoom lays it out again in it
      s.textContent = T.PANEL + '{zoom:' + scale + '}';
      document.head.appendChild(s);
    } else if (!on && s) s.remove();
    setTimeout(T.frame, 50);
  };
  T.frame();
  T.hook();
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


def call_json(client, name: str, arg: str) -> bool:
    """`call` with its one argument already JSON."""
    return run_js(client, f"window.theoria && window.theoria.{name}({arg});")


def read_address(client, timeout: float = 10.0) -> str | None:
    """The address the browser opened (with its query), or None (no answer, or a fake client). A
    page answers within milliseconds; the generous timeout is for a loaded machine, where a link
    answered late would otherwise be ignored."""
    try:
        ls = client.local_storage
        ls.set_item(ADDRESS_KEY + "-probe", "1")
        if not run_js(client, WRITE_ADDRESS):
            return None
        address = ls.get_item(ADDRESS_KEY, timeout=timeout)
    except Exception:
        return None
    # a page writes text; anything else came from a hand-made message, and opens the default view
    return address if isinstance(address, str) else None
