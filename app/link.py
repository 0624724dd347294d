"""The state of a view as a link: scenario, parameters, time, camera, the scene's options and
overlays, presenter mode. The app keeps the browser's address bar on this link; opening it
(another tab, another browser, a student's phone) shows the same view.

    ?s=middle-axis-flip&p.spin=6&p.perturbation=0.001&t=12.5&play=0&cam=3,2.3,1.8,0,0,0

A link typed by hand may name the scene as `?scenario=earth`, `?scene=earth` or just `?earth`.

Parameters are written with their keys and exact values (what `Param.parse` reads back), only
those that differ from the scene's defaults (the session leaves the others out; opening the link
fills them in); time in the run's own unit. When the server listens on a network address,
`class_link` gives the address students can open and `qr_svg_uri` its QR code (segno).
"""
from __future__ import annotations

import ipaddress
import math
import socket
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import parse_qsl, urlencode, urlsplit

from theoria.physics.errors import ParameterError
from .format import exact


@dataclass
class LinkState:
    scenario: str | None = None
    params: dict[str, str] = field(default_factory=dict)  # key → text as in the link (parsed by resolve)
    time: float | None = None  # in the run's time unit
    playing: bool = True
    camera: tuple[float, ...] | None = None  # position (3), look-at (3)[, up (3)]
    options: dict[str, bool] = field(default_factory=dict)
    overlays: dict[str, bool] = field(default_factory=dict)
    present: bool = False
    speed: float | None = None
    exaggerate: float | None = None  # the body's shape exaggerated (the panel's "Exaggerate the shape")
    dropped: list = field(default_factory=list)  # (key, value, what it takes) of values not taken
    unread: int = 0  # parts of a link beyond MAX_LINK_PARTS, not read


def _finite(text: str) -> float:
    """A number of the link, or ValueError: "nan" and "inf" are words float() reads, not numbers a
    view can be at (a clock at NaN would never move again)."""
    x = float(text)
    if not math.isfinite(x):
        raise ValueError(text)
    return x


def _apart(a, b) -> bool:
    return math.dist(a, b) > 1e-9


def _num(x: float, digits: int = 6) -> str:
    text = f"{float(x):.{digits}g}"
    return text


def param_text(p, v: Any) -> str:
    """A parameter's value as the link writes it (exact: read back by Param.parse)."""
    if p.kind == "vec3":
        return ",".join(exact(x) for x in v)
    if p.kind == "choice":
        return str(v)
    if p.kind == "int":
        return str(int(v))
    return exact(v)


def to_query(state: LinkState, spec=None) -> str:
    """The query string (without "?") of `state`; `spec` orders the parameters as the scenario does."""
    q: list[tuple[str, str]] = []
    if state.scenario:
        q.append(("s", state.scenario))
    names = [p.name for p in spec.params] if spec is not None else list(state.params)
    for n in names:
        if n in state.params:
            q.append((f"p.{n}", state.params[n]))
    if state.time is not None:
        q.append(("t", _num(state.time, 8)))
    if not state.playing:
        q.append(("play", "0"))
    if state.speed is not None and state.speed != 1.0:
        q.append(("speed", _num(state.speed, 4)))
    if state.exaggerate is not None and state.exaggerate != 1.0:
        q.append(("exag", _num(state.exaggerate, 4)))
    if state.camera is not None:
        q.append(("cam", ",".join(_num(x, 5) for x in state.camera)))
    for k, on in sorted(state.options.items()):
        q.append((f"o.{k}", "1" if on else "0"))
    for k, on in sorted(state.overlays.items()):
        q.append((f"v.{k}", "1" if on else "0"))
    if state.present:
        q.append(("present", "1"))
    return urlencode(q, safe=",.")


def from_address(address: str | None) -> LinkState:
    """The state a link holds (fields it does not hold stay None / empty). Bad numbers are
    dropped; the parameters are checked later, by the scenario."""
    st = LinkState()
    if not address or not isinstance(address, str):
        return st
    query = urlsplit(address).query if ("?" in address or "://" in address) else address
    parts = query.split("&", MAX_LINK_PARTS)
    if len(parts) > MAX_LINK_PARTS:  # the rest is counted, not read (see MAX_LINK_PARTS)
        st.unread = parts.pop().count("&") + 1
    for k, v in parse_qsl("&".join(parts), keep_blank_values=True):
        if len(v) > 400:  # nothing in a link of ours is this long
            st.dropped.append((k, v, "a value of at most 400 characters"))
            continue
        try:
            if k in SCENARIO_KEYS:
                st.scenario = v
            elif k.startswith("p."):
                st.params[k[2:]] = v
            elif k == "t":
                st.time = _finite(v)
            elif k == "play":
                st.playing = v not in ("0", "false", "no")
            elif k == "speed":
                st.speed = _finite(v)
            elif k == "exag":
                st.exaggerate = _finite(v)
            elif k == "cam":
                c = tuple(_finite(x) for x in v.split(","))
                # a camera the view can take: apart from where it looks, and an up that is a direction
                if len(c) in (6, 9) and all(abs(x) < 1e9 for x in c) and _apart(c[0:3], c[3:6]) \
                        and (len(c) == 6 or _apart(c[6:9], (0.0, 0.0, 0.0))):
                    st.camera = c
                else:
                    raise ValueError(v)
            elif k.startswith("o."):
                st.options[k[2:]] = v not in ("0", "false", "no")
            elif k.startswith("v."):
                st.overlays[k[2:]] = v not in ("0", "false", "no")
            elif k == "present":
                st.present = v not in ("0", "false", "no")
            elif v == "" and st.scenario is None and _looks_like_a_name(k):  # `?earth`: the scene by its name
                st.scenario = k
            elif k in VISER_KEYS:  # the page's own settings, read by viser's client
                pass
            else:  # a key of no link of ours (a typo, `?scene=` from another app): said, not silently ignored
                st.dropped.append((k, v, "not a key of a theoria link (" + KEYS_TAKEN + ")"))
        except ValueError:
            st.dropped.append((k, v, _TAKES.get(k, "a finite number")))
    return st


# A link of ours has a part per parameter, option and overlay and a few more (under a hundred).
# A hand-made one of 90,000 unknown keys cost the server 1.7 s of CPU each time a page opened it
# (a refusal made for every key, three of them shown): five tabs reopening it held the class's
# redraws at 1-4 s. Parts beyond these are counted, not read.
MAX_LINK_PARTS = 200
# the scene: "s" as the app writes it; "scenario" and "scene" as a teacher writing a link by hand would
SCENARIO_KEYS = ("s", "scenario", "scene")
# keys viser's client reads from the address itself (its SearchParamsUtils and App): not ours to name
VISER_KEYS = frozenset({"websocket", "fixedDpr", "darkMode", "showStats", "logCamera", "hideViserLogo",
                        "playbackPath", "forceOrbitOriginTool", "dummyWindowDimensions", "dummyWindowTitle"})
KEYS_TAKEN = "s=SCENE, p.PARAMETER=VALUE, t, play, speed, exag, cam, o.OPTION, v.OVERLAY, present"


def _looks_like_a_name(k: str) -> bool:
    return 0 < len(k) <= 64 and all(c.isalnum() or c == "-" for c in k)


_TAKES = {"cam": "six numbers: where the camera is and where it looks (two different points), and "
                 "optionally three more for its up direction"}


def link_values(spec, st: LinkState) -> tuple[dict[str, Any], list[ParameterError]]:
    """The scenario's values with the link's parameters applied, one at a time: a parameter the
    scenario does not have, or a value it refuses, is left at its default and reported."""
    params = {p.name: p for p in spec.params}
    given: dict[str, Any] = {}
    errors: list[ParameterError] = []
    for k, text in st.params.items():
        if k not in params:
            errors.append(ParameterError(k, text, "not a parameter of this scene"))
            continue
        try:
            given[k] = params[k].parse(text)
        except ParameterError as e:
            errors.append(e)
    try:
        return spec.resolve(given), errors
    except ParameterError as e:  # a combination the scenario refuses (e.g. moments out of triangle)
        return spec.resolve(None), errors + [e]


# ---- the class's address ---------------------------------------------------------------------

def _is_loopback(host: str) -> bool:
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return host in ("localhost",)


def network_addresses() -> list[str]:
    """This machine's IPv4 addresses other than loopback, read locally (no packet is sent)."""
    found: list[str] = []
    try:
        import psutil  # optional: the most complete answer

        for addrs in psutil.net_if_addrs().values():
            for a in addrs:
                if a.family == socket.AF_INET and not _is_loopback(a.address):
                    found.append(a.address)
    except Exception:
        pass
    if not found:
        try:
            for a in socket.gethostbyname_ex(socket.gethostname())[2]:
                if not _is_loopback(a):
                    found.append(a)
        except OSError:
            pass
    # private (classroom Wi-Fi) addresses first
    return sorted(dict.fromkeys(found), key=lambda a: (not ipaddress.ip_address(a).is_private, a))


def class_link(bind_host: str, port: int, page_address: str | None = None) -> str | None:
    """The address students open, or None when the server listens only on this machine. The host
    is the one the teacher's browser used if that is a network address, else the bound address,
    else (bound to every interface) this machine's first private address."""
    if _is_loopback(bind_host):
        return None
    host = None
    if page_address:
        h = urlsplit(page_address).hostname
        if h and not _is_loopback(h):
            host = h
    if host is None and bind_host not in ("0.0.0.0", "::", ""):
        host = bind_host
    if host is None:
        addrs = network_addresses()
        host = addrs[0] if addrs else None
    if host is None:
        return None
    if ":" in host:
        host = f"[{host}]"
    return f"http://{host}:{port}/"


def qr_svg_uri(text: str, scale: int = 4) -> str:
    """A QR code of `text` as an SVG data URI (segno)."""
    import segno

    return segno.make(text, error="m").svg_data_uri(scale=scale, border=2)
