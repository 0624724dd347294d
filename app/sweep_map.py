"""A sweep result as a map a class can click (`theoria serve --sweep result.zarr`).

The map is one metric of a sweep over two swept parameters, coloured dark (low) to bright (high),
drawn in the panel's Sweep tab as HTML: the pixels are a small PNG (numpy → Pillow, one image
pixel per run, scaled up by the browser without smoothing) and everything a person reads — the
axes with the parameters' names and units, the tick values, the colour bar with the metric's name
in words and its unit — is HTML text beside it. Text drawn by the browser stays sharp at any size
(presenter mode scales the panel by 1.45) and shows ω₀, θ̇/n and ° in the page's font; text
burnt into a PNG would not.

A click on a pixel reaches the server as an ordinary control value (a hidden text field of the
panel, set by the page's script: "row,column,view,click"), so it passes the server's gate like
any typed value (rate-limited, coalesced, at most MAX_TEXT_CHARS) and needs no new message type.
The session then replays that run through the normal path (its worker and the simulation pool,
with their budgets), with `MapData.run_values(row, column)` as its parameters.

Opening the Zarr store and rendering a view happen once per (metric, summary) and are cached
(`SweepMaps.picture`); the panel's callbacks only choose what to show and post the rendering to
a background thread.
"""
from __future__ import annotations

import base64
import html
import io
import os
import re
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from theoria.physics.errors import ParameterError
from theoria.physics.params import pretty_unit

from .format import capitalised, human_number
from .panel import metric_label
from .sweep import SAMPLE, SWEEP_PRESETS, MapData, open_map

# a dark-to-bright perceptual ramp: matplotlib's viridis sampled at 9 points (its published table)
RAMP = np.array([[68, 1, 84], [71, 44, 122], [59, 81, 139], [44, 113, 142], [33, 144, 141],
                 [39, 173, 129], [92, 200, 99], [170, 220, 50], [253, 231, 37]], float)
NAN_RGB = (190, 190, 190)  # a run with no value (refused, failed, not run, undecided)
MARK_RGB = (255, 40, 40)
MAP_WIDTH_PX = 280  # the map's width in the panel (CSS px); the height follows the grid's shape

_REDUCE_WORDS = {"mean": "mean", "median": "median", "max": "largest", "min": "smallest",
                 "fraction": "fraction nonzero"}


def ramp(v: np.ndarray) -> np.ndarray:
    """Colours (uint8 RGB) for values in [0, 1]."""
    v = np.clip(np.nan_to_num(v, nan=0.0), 0, 1) * (len(RAMP) - 1)
    i = np.minimum(np.floor(v).astype(int), len(RAMP) - 2)
    f = (v - i)[..., None]
    return (RAMP[i] * (1 - f) + RAMP[i + 1] * f).round().astype(np.uint8)


def ramp_css() -> str:
    stops = ", ".join(f"rgb({r:.0f},{g:.0f},{b:.0f}) {100 * k / (len(RAMP) - 1):.1f}%" for k, (r, g, b) in enumerate(RAMP))
    return f"linear-gradient(to top, {stops})"


# ------------------------------------------------------------------------------ words for a map

# names in words; the unit is the store's (the scenario's `metric_units`) unless given here
_METRIC_WORDS = [
    (r"lyapunov_probe_per_orbit", "Largest Lyapunov exponent of the drawn body", None),
    (r"lyapunov_probe_per_unit_time", "Largest Lyapunov exponent of the drawn body", None),
    (r"captured_(\d+)_(\d+)", r"Captured into the \1:\2 resonance", "1 yes, 0 no"),
    (r"captured_resonance", "Resonance it ends in (θ̇/n; 0: none)", ""),
    (r"gp_capture_probability_(\d+)_(\d+)", r"Goldreich & Peale's probability of capture into \1:\2", None),
    (r"gp_series_half_width_([\d.]+)", r"Half-width of the \1 resonance (series in e)", None),
    (r"gp_half_width_([\d.]+)", r"Half-width of the \1 resonance", None),
    (r"final_spin_rate_n", "Final spin θ̇/n", ""),
]


def metric_words(key: str, unit: str = "") -> tuple[str, str]:
    """A metric's name in words and its unit as printed: ("Largest Lyapunov exponent …", "per orbit")."""
    unit = pretty_unit(unit) if unit not in ("see name",) else ""  # "see name": stores written before units
    for pat, name, u in _METRIC_WORDS:
        m = re.fullmatch(pat, key)
        if m:
            return m.expand(name), unit if u is None else u
    text = re.sub(r" \(.*\)$", "", metric_label(key))
    text = re.sub(r"\b(\d+) (\d+)\b", r"\1:\2", text)  # a resonance p:q written as a key p_q
    return text, unit


def is_capture(metric: str) -> bool:
    return metric.startswith("captured_") and metric != "captured_resonance"


@dataclass(frozen=True)
class View:
    """What the map shows of a metric: its columns (x), rows (y, or None for a profile along x)
    and how the remaining swept dimensions are summarised."""

    x: str
    y: str | None
    reduce: str | None  # None: every run is its own pixel
    over: tuple[str, ...]  # the dimensions summarised

    @property
    def key(self) -> str:
        return f"{self.x}|{self.y or ''}|{self.reduce or ''}"


@dataclass
class Picture:
    """One rendered view: the map's numbers and the PNG of its pixels."""

    map: MapData
    view: View
    metric: str
    png: bytes
    lo: float
    hi: float
    key: str
    ref: np.ndarray | None = None  # a profile's theory beside it (Goldreich & Peale's probability)
    ref_metric: str = ""

    @property
    def rows(self) -> int:
        return int(self.map.values.shape[0])

    @property
    def cols(self) -> int:
        return int(self.map.values.shape[1])


class SweepMaps:
    """A sweep result opened for the app: its scenario, metrics and views, and a cache of rendered
    pictures shared by every browser of the server."""

    def __init__(self, path):
        import xarray as xr

        self.path = os.fspath(path)
        what = "a Zarr store written by theoria sweep (theoria sweep SCENARIO … --out F.zarr)"
        if not os.path.isdir(self.path):
            if os.path.isfile(self.path) and self.path.endswith(".parquet"):  # a sweep's flat table
                raise ParameterError("--sweep", self.path, what + "; a Parquet sweep is a flat table with no grid "
                                     "to draw: sweep again with --out F.zarr")
            raise ParameterError("--sweep", self.path, what + ("; this is a file" if os.path.exists(self.path)
                                                               else "; no such folder"))
        try:
            ds = xr.open_zarr(self.path, consolidated=False)
        except Exception as e:  # noqa: BLE001 — not Zarr at all, or damaged: one line
            raise ParameterError("--sweep", self.path, f"{what}; it cannot be read as Zarr ({type(e).__name__})") from None
        if "theoria_sweep" not in ds.attrs or "status" not in ds.data_vars:
            raise ParameterError("--sweep", self.path, what + "; this Zarr store has no theoria sweep in it")
        from theoria.scenarios import get

        # The map shows the sweep as it was opened: read into memory now (the metrics are read whole
        # below in any case). Read lazily from the folder, a sweep written there again while the
        # server ran (`--force` renames a new store over the old) mixed the new numbers into the
        # panel made for the old: maps of another size, a click that replayed a run not shown.
        try:
            ds = ds.load()
        except Exception as e:  # noqa: BLE001 — a damaged chunk: one line
            raise ParameterError("--sweep", self.path, f"{what}; a part of it cannot be read ({type(e).__name__})") from None
        self.ds = ds
        self.scenario = get(ds.attrs.get("scenario") or ds.attrs["theoria_sweep"]["scenario"])
        spec = ds.attrs["theoria_sweep"]
        self.dims = list(spec["dims"])
        self.grid_dims = [d for d in self.dims if d != SAMPLE]
        st = np.asarray(ds["status"].values)
        if not np.any(st != 0):
            raise ParameterError("--sweep", self.path, "a sweep with at least one finished run (none is written yet)")
        self.metrics = [v for v in ds.data_vars if v != "status" and np.any(np.isfinite(np.asarray(ds[v].values, float)))]
        if not self.metrics:
            raise ParameterError("--sweep", self.path, "a sweep whose runs gave metrics (every value is missing)")
        # the named sweep this is (its description is shown), when its fixed values and swept names match
        fixed = spec.get("fixed", {})
        self.preset = next((p for p in SWEEP_PRESETS.values()
                            if p.scenario == self.scenario.name and p.metric in self.metrics
                            and all(fixed.get(k) == v for k, v in p.fixed.items())
                            and {g.split("=", 1)[0] for g in p.grid} == set(self.grid_dims)), None)
        usual = next((p.metric for p in SWEEP_PRESETS.values()
                      if p.scenario == self.scenario.name and p.metric in self.metrics), None)
        first = usual or self.metrics[0]
        self.metrics.remove(first)
        self.metrics.insert(0, first)
        self._cache: dict[tuple[str, str], Picture] = {}
        self._lock = threading.Lock()
        self._pool = ThreadPoolExecutor(1, thread_name_prefix="theoria-map")

    # ---- words -----------------------------------------------------------------------------
    def param_words(self, name: str) -> tuple[str, str]:
        """(the swept parameter's name in words, its unit as printed)."""
        if name == SAMPLE:
            return "random draw", ""
        try:
            p = self.scenario.param(name)
            return capitalised(p.title()), p.unit_text()
        except KeyError:
            return name.replace("_", " "), pretty_unit(self.ds[name].attrs.get("units", ""))

    def axis_text(self, name: str) -> str:
        words, unit = self.param_words(name)
        return f"{words} ({unit})" if unit else words

    def metric_text(self, metric: str) -> str:
        words, unit = metric_words(metric, self.ds[metric].attrs.get("units", ""))
        return f"{words} ({unit})" if unit else words

    def title(self) -> str:
        return self.scenario.title

    # ---- views -----------------------------------------------------------------------------
    def views(self, metric: str) -> list[tuple[str, View]]:
        """The summaries a map of `metric` offers, in words, the first the default."""
        dims = [d for d in self.ds[metric].dims]
        grid = [d for d in dims if d != SAMPLE]
        cap = is_capture(metric)
        reductions = ["mean", "fraction"] if cap else ["mean", "median", "max", "min", "fraction"]

        def rword(r, over):
            if cap:
                return "fraction captured over the " + " and ".join(self.param_words(d)[0].lower() for d in over)
            what = "random draws" if over == (SAMPLE,) else " and ".join(self.param_words(d)[0].lower() for d in over)
            return f"{_REDUCE_WORDS[r]} over the {what}"

        out: list[tuple[str, View]] = []
        if len(grid) >= 2:
            x, y = grid[-1], grid[-2]
            other = tuple(d for d in dims if d not in (x, y))
            if other:
                seen = set()
                for r in reductions:
                    label = rword(r, other)
                    if label not in seen:
                        seen.add(label)
                        out.append((label, View(x, y, r, other)))
            else:
                out.append(("each run", View(x, y, None, ())))
            for keep, drop in ((y, x), (x, y)):  # a profile: one swept parameter summarised too
                over = (drop,) + other
                seen = {lab for lab, _ in out}
                for r in reductions[:1]:
                    label = rword(r, over) + f" (against the {self.param_words(keep)[0].lower()})"
                    if label not in seen:
                        seen.add(label)
                        out.append((label, View(keep, None, r, over)))
        else:
            x = grid[0] if grid else dims[0]
            other = tuple(d for d in dims if d != x)
            if other:
                for r in reductions:
                    out.append((rword(r, other), View(x, None, r, other)))
            else:
                out.append(("each run", View(x, None, None, ())))
        return out

    def default_view(self, metric: str) -> str:
        """Every run as its own pixel; for a capture metric the fraction captured against the first
        swept parameter (the probability a theory predicts, e.g. against e)."""
        views = self.views(metric)
        if is_capture(metric):
            for label, v in views:
                if v.y is None and v.x == self.grid_dims[0]:
                    return label
        return views[0][0]

    # ---- pictures --------------------------------------------------------------------------
    def picture(self, metric: str, view_label: str) -> Picture:
        """The rendered view (cached; call from a background thread the first time)."""
        key = (metric, view_label)
        with self._lock:
            pic = self._cache.get(key)
        if pic is not None:
            return pic
        views = dict(self.views(metric))
        if metric not in self.metrics:
            raise ParameterError("metric", metric, "one of " + ", ".join(self.metrics))
        if view_label not in views:
            raise ParameterError("summary", view_label, "one of " + ", ".join(views))
        v = views[view_label]
        m = open_map(self.ds, metric, x=v.x, y=v.y if v.y is not None else False, reduce=v.reduce or "mean")
        vals = np.asarray(m.values, float)
        finite = vals[np.isfinite(vals)]
        if is_capture(metric) or v.reduce == "fraction" or metric.startswith("gp_capture_probability"):
            lo, hi = 0.0, 1.0
        elif finite.size:
            lo, hi = float(finite.min()), float(finite.max())
            if -0.05 * hi < lo < 0.25 * hi:
                lo = 0.0  # a nonnegative quantity (an exponent, an amplitude; round-off below 0) from zero
        else:
            lo, hi = 0.0, 1.0
        png = render_png(vals, lo, hi) if v.y is not None else render_bars(vals[0], lo, hi)
        pic = Picture(m, v, metric, png, lo, hi, f"{metric}|{v.key}")
        ref = self.reference(metric)
        if v.y is None and ref is not None:  # the theory's probability at the same points, as dots
            pic.ref = np.asarray(open_map(self.ds, ref, x=v.x, y=False, reduce="mean").values[0], float)
            pic.ref_metric = ref
        with self._lock:
            self._cache[key] = pic
        return pic

    def reference(self, metric: str) -> str | None:
        """The metric that predicts `metric` (captured_p_q: Goldreich & Peale's probability), if in the sweep."""
        m = re.fullmatch(r"captured_(\d+_\d+)", metric)
        ref = f"gp_capture_probability_{m.group(1)}" if m else None
        return ref if ref in self.ds.data_vars else None

    def picture_async(self, metric: str, view_label: str) -> Future:
        return self._pool.submit(self.picture, metric, view_label)

    def close(self) -> None:
        self._pool.shutdown(wait=False)

    # ---- a pixel -----------------------------------------------------------------------------
    def pixel_words(self, pic: Picture, i: int, j: int) -> str:
        """Which run a pixel is, in words: its swept values (and the value the map shows there)."""
        values = pic.map.run_values(i, j)
        parts = []
        for d in self.grid_dims:
            words, unit = self.param_words(d)
            v = values[d]
            num = human_number(v) if isinstance(v, (int, float)) else str(v)
            note = ""
            if d in pic.view.over:
                note = f" (the first of {self.ds.sizes[d]}; the pixel summarises them all)"
            parts.append(f"{words} = {num}{(' ' + unit) if unit and unit != '°' else unit}{note}")
        val = pic.map.values[i, j]
        shown = "no value" if not np.isfinite(val) else human_number(float(val))
        return "; ".join(parts) + f" — on the map: {shown}"


def render_png(vals: np.ndarray, lo: float, hi: float) -> bytes:
    """One image pixel per run, row 0 (the lowest y) at the bottom; missing values grey."""
    from PIL import Image

    v = np.asarray(vals, float)
    img = ramp((v - lo) / (hi - lo if hi > lo else 1.0))
    img[~np.isfinite(v)] = NAN_RGB
    buf = io.BytesIO()
    Image.fromarray(img[::-1]).save(buf, format="PNG", optimize=False)
    return buf.getvalue()


def render_bars(vals: np.ndarray, lo: float, hi: float, height: int = 120) -> bytes:
    """A profile as bars: column j filled from the bottom up to its value, in its colour (one
    image column per run of the profile; a missing value is a thin grey bar)."""
    from PIL import Image

    v = np.asarray(vals, float)
    f = (v - lo) / (hi - lo if hi > lo else 1.0)
    cols = ramp(f)
    img = np.full((height, len(v), 3), 255, np.uint8)
    for j, x in enumerate(f):
        if not np.isfinite(x):
            img[-3:, j] = NAN_RGB
            continue
        h = int(round(np.clip(x, 0, 1) * height))
        if h:
            img[height - h:, j] = cols[j]
    img[:, :, :][np.all(img == 255, axis=-1) & (np.arange(height)[:, None] % 30 == 29)] = (225, 225, 225)  # gridlines
    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG")
    return buf.getvalue()


def nice_ticks(lo: float, hi: float, n: int = 5) -> list[float]:
    """About n round values (1, 2, 2.5 or 5 × 10^k apart) from lo to hi."""
    if not (np.isfinite(lo) and np.isfinite(hi)) or hi <= lo:
        return [lo]
    raw = (hi - lo) / max(n - 1, 1)
    mag = 10 ** np.floor(np.log10(raw))
    step = next(m * mag for m in (1, 2, 2.5, 5, 10) if m * mag >= raw * 0.999)
    first = np.ceil(lo / step - 1e-9) * step
    out = [float(round(x, 12)) for x in np.arange(first, hi + step * 1e-6, step)]
    return [0.0 if abs(x) < step * 1e-9 else x for x in out]


def _ticks(values: np.ndarray, n: int = 5) -> list[tuple[float, str]]:
    """(fraction along the axis, text) for round values of a swept parameter, placed between the
    pixel centres of its grid (the first value at the middle of the first pixel)."""
    k = len(values)
    try:
        v = np.asarray(values, float)
    except (TypeError, ValueError):  # a choice parameter: every value by name
        return [((i + 0.5) / k, str(values[i])) for i in range(k)]
    if k == 1:
        return [(0.5, human_number(float(v[0])))]
    if not np.all(np.diff(v) > 0):
        idx = sorted(set(np.linspace(0, k - 1, min(n, k)).round().astype(int)))
        return [((i + 0.5) / k, human_number(float(v[i]))) for i in idx]
    return [((0.5 + float(np.interp(t, v, np.arange(k)))) / k, human_number(t)) for t in nice_ticks(v[0], v[-1], n)]


def _range_ticks(lo: float, hi: float) -> list[tuple[float, str]]:
    """(fraction of the colour bar or of a bar's height, text) for round values of the metric."""
    span = (hi - lo) or 1.0
    return [((t - lo) / span, human_number(t)) for t in nice_ticks(lo, hi)]


def _e(text) -> str:
    return html.escape(str(text), quote=True)


def map_html(maps: SweepMaps, pic: Picture, field_uuid: str | None, mark: tuple[int, int] | None = None) -> str:
    """The map as HTML: pixels (a PNG scaled without smoothing), axes and colour bar in words.
    `field_uuid`: the hidden control a click sets (the page's script reads it from the image)."""
    m = pic.map
    rows, cols = pic.rows, pic.cols
    W = MAP_WIDTH_PX
    profile = pic.view.y is None
    H = int(round(W * 0.75)) if not profile else int(round(W * 0.6))
    src = "data:image/png;base64," + base64.b64encode(pic.png).decode("ascii")
    xlabel = maps.axis_text(m.x)
    summary = next(lab for lab, v in maps.views(pic.metric) if v == pic.view)
    if pic.view.reduce and is_capture(pic.metric):  # a fraction of runs, not a yes/no any more
        quantity = "Fraction " + metric_words(pic.metric)[0][:1].lower() + metric_words(pic.metric)[0][1:]
        metric = quantity + ", over the " + summary.split(" over the ", 1)[1].split(" (against")[0]
    else:
        quantity = maps.metric_text(pic.metric)
        metric = quantity + (" — " + summary if pic.view.reduce else "")
    ylabel = maps.axis_text(m.y) if m.y else quantity
    font = "font:11px/1.2 system-ui,sans-serif;color:#222"
    parts = [f"<div class='theoria-map' style='{font};user-select:none;margin:0 10px'>",
             f"<div style='font-weight:600;margin-bottom:4px'>{_e(metric)}</div>",
             "<div style='display:flex;align-items:stretch'>"]
    # the y axis: its name written upward, tick values beside the map
    parts.append(f"<div style='writing-mode:vertical-rl;transform:rotate(180deg);text-align:center;"
                 f"height:{H}px;width:16px;font-weight:500'>{_e(ylabel)}</div>")
    parts.append(f"<div style='position:relative;width:40px;height:{H}px;margin-left:2px'>")
    if m.y:
        for f, t in _ticks(m.y_values):
            parts.append(f"<span style='position:absolute;right:3px;bottom:{f * H - 6:.1f}px'>{_e(t)}</span>")
    else:  # a profile: the bars' heights are the metric
        for f, t in _range_ticks(pic.lo, pic.hi):
            parts.append(f"<span style='position:absolute;right:3px;bottom:{f * H - 6:.1f}px'>{_e(t)}</span>")
    parts.append("</div>")
    data = (f" data-theoria-map='1' data-uuid='{_e(field_uuid)}' data-rows='{rows}' data-cols='{cols}' "
            f"data-key='{_e(pic.key)}'") if field_uuid else ""
    parts.append(f"<div style='position:relative;width:{W}px;height:{H}px;outline:1px solid #444'>"
                 f"<img alt='{_e(metric)} over {_e(xlabel)}' src='{src}'{data} draggable='false' "
                 f"style='display:block;width:{W}px;height:{H}px;image-rendering:pixelated;cursor:crosshair'>")
    if mark is not None:
        i, j = mark
        pw, ph = W / cols, H / rows
        parts.append(f"<div title='the run shown in the scene' style='position:absolute;pointer-events:none;"
                     f"left:{j * pw - 2:.1f}px;bottom:{i * ph - 2:.1f}px;width:{max(pw, 4):.1f}px;height:{max(ph, 4):.1f}px;"
                     f"border:2px solid rgb{MARK_RGB};box-shadow:0 0 0 1px #fff'></div>")
    if pic.ref is not None:
        for j, r in enumerate(pic.ref):
            if np.isfinite(r):
                y = (r - pic.lo) / ((pic.hi - pic.lo) or 1.0) * H
                parts.append(f"<div style='position:absolute;pointer-events:none;left:{(j + 0.5) * W / cols - 4:.1f}px;"
                             f"bottom:{y - 4:.1f}px;width:8px;height:8px;border-radius:50%;background:#e8590c;"
                             "border:1px solid #fff'></div>")
    parts.append("</div>")
    # the colour bar: the metric's range, bottom to top
    parts.append(f"<div style='width:12px;height:{H}px;margin-left:8px;background:{ramp_css()};outline:1px solid #444'></div>")
    parts.append(f"<div style='position:relative;width:40px;height:{H}px'>")
    for f, t in _range_ticks(pic.lo, pic.hi):
        parts.append(f"<span style='position:absolute;left:3px;bottom:{f * H - 6:.1f}px'>{_e(t)}</span>")
    parts.append("</div></div>")
    # the x axis
    parts.append(f"<div style='position:relative;margin-left:58px;width:{W}px;height:14px'>")
    for f, t in _ticks(m.x_values):
        parts.append(f"<span style='position:absolute;left:{f * W:.1f}px;transform:translateX(-50%)'>{_e(t)}</span>")
    parts.append("</div>")
    parts.append(f"<div style='margin-left:58px;width:{W}px;text-align:center;font-weight:500'>{_e(xlabel)}</div>")
    legend = "Grey: no value (refused, failed or undecided runs). " if np.any(~np.isfinite(m.values)) else ""
    if pic.ref is not None:
        legend += f"<span style='color:#e8590c'>●</span> {_e(metric_words(pic.ref_metric)[0])}. "
    parts.append(f"<div style='margin-top:4px;color:#555'>{legend}Colour bar: {_e(quantity)}. "
                 "Click a pixel to replay that run in the scene.</div></div>")
    return "".join(parts)


def parse_click(text: str, pic: Picture) -> tuple[int, int] | None:
    """A click's value "row,column,view,count" → (row, column) when it is for this picture and in
    range; None otherwise (a stale view, a malformed value)."""
    parts = str(text).split(",")
    if len(parts) < 3:
        return None
    try:
        i, j = int(parts[0]), int(parts[1])
    except ValueError:
        return None
    if parts[2] != pic.key or not (0 <= i < pic.rows and 0 <= j < pic.cols):
        return None
    return i, j
