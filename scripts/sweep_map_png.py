"""Draw a sweep result's map as a PNG for the docs (no plotting library: numpy and Pillow).

    python scripts/sweep_map_png.py result.zarr METRIC out.png [--x NAME] [--y NAME|--profile]
        [--reduce mean|fraction|…] [--vmin V] [--vmax V] [--title TEXT]

Uses theoria.app.sweep.open_map, the function the app's map calls: the same axes, units and
reduction. A 2-D map is coloured with a perceptual ramp (dark: low); a profile (--profile) is
drawn as a curve, with a second metric beside it if --also NAME is given (e.g. Goldreich &
Peale's probability next to the measured capture fraction).
"""
from __future__ import annotations

import argparse

import numpy as np
from PIL import Image, ImageDraw

from theoria.app.sweep import open_map

# a dark-to-bright ramp (approximately viridis), interpolated
RAMP = np.array([[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]], float)


def ramp(v):
    v = np.clip(v, 0, 1) * (len(RAMP) - 1)
    i = np.minimum(np.floor(v).astype(int), len(RAMP) - 2)
    f = (v - i)[..., None]
    return (RAMP[i] * (1 - f) + RAMP[i + 1] * f).astype(np.uint8)


def axis_label(name, unit):
    return f"{name} [{unit}]" if unit and unit not in ("1", "see name") else name


def draw_map(m, out, vmin=None, vmax=None, title=""):
    v = np.asarray(m.values, float)
    lo = np.nanmin(v) if vmin is None else vmin
    hi = np.nanmax(v) if vmax is None else vmax
    img = ramp((v - lo) / (hi - lo if hi > lo else 1.0))
    img[~np.isfinite(v)] = (200, 200, 200)
    W, H = 640, 420
    plot = Image.fromarray(img[::-1]).resize((W, H), Image.NEAREST)  # first row (lowest y) at the bottom
    L, T, R, B = 80, 40, 110, 60
    canvas = Image.new("RGB", (L + W + R, T + H + B), "white")
    canvas.paste(plot, (L, T))
    d = ImageDraw.Draw(canvas)
    d.rectangle([L - 1, T - 1, L + W, T + H], outline="black")
    for k in range(5):
        fx = k / 4
        xv = m.x_values[0] + fx * (m.x_values[-1] - m.x_values[0])
        d.line([L + fx * W, T + H, L + fx * W, T + H + 5], fill="black")
        d.text((L + fx * W - 12, T + H + 8), f"{xv:.3g}", fill="black")
        yv = m.y_values[0] + fx * (m.y_values[-1] - m.y_values[0])
        d.line([L - 5, T + H - fx * H, L, T + H - fx * H], fill="black")
        d.text((L - 45, T + H - fx * H - 6), f"{yv:.3g}", fill="black")
    d.text((L + W / 2 - 60, T + H + 30), axis_label(m.x, m.x_unit), fill="black")
    d.text((8, T - 25), axis_label(m.y, m.y_unit) + "  (vertical)", fill="black")
    d.text((L, 8), title or f"{m.scenario}: {m.metric}" + (f" ({m.reduced})" if m.reduced else ""), fill="black")
    # legend
    bar = ramp(np.linspace(1, 0, H)[:, None].repeat(20, 1))
    canvas.paste(Image.fromarray(bar), (L + W + 20, T))
    d.rectangle([L + W + 19, T - 1, L + W + 40, T + H], outline="black")
    for k in range(5):
        fy = k / 4
        d.text((L + W + 45, T + H - fy * H - 6), f"{lo + fy * (hi - lo):.3g}", fill="black")
    d.text((L + W + 15, T + H + 8), axis_label(m.metric, m.metric_unit)[:22], fill="black")
    canvas.save(out)


def draw_profile(m, out, also=None, title=""):
    W, H, L, T, R, B = 640, 360, 80, 40, 40, 60
    canvas = Image.new("RGB", (L + W + R, T + H + B), "white")
    d = ImageDraw.Draw(canvas)
    x = np.asarray(m.x_values, float)
    ys = [(np.asarray(m.values[0], float), (33, 100, 180), m.metric + (f" ({m.reduced})" if m.reduced else ""))]
    if also is not None:
        ys.append((np.asarray(also.values[0], float), (220, 80, 40), also.metric))
    hi = max(np.nanmax(y) for y, _, _ in ys) * 1.1 or 1.0
    d.rectangle([L, T, L + W, T + H], outline="black")

    def px(xv, yv):
        return L + (xv - x[0]) / (x[-1] - x[0]) * W, T + H - yv / hi * H

    for y, col, lab in ys:
        pts = [px(a, b) for a, b in zip(x, y) if np.isfinite(b)]
        d.line(pts, fill=col, width=2)
        for p in pts:
            d.ellipse([p[0] - 3, p[1] - 3, p[0] + 3, p[1] + 3], fill=col)
    for k, (_, col, lab) in enumerate(ys):
        d.text((L + 10, T + 10 + 16 * k), lab, fill=col)
    for k in range(5):
        f = k / 4
        d.text((L + f * W - 12, T + H + 8), f"{x[0] + f * (x[-1] - x[0]):.3g}", fill="black")
        d.text((L - 45, T + H - f * H - 6), f"{f * hi:.3g}", fill="black")
    d.text((L + W / 2 - 40, T + H + 30), axis_label(m.x, m.x_unit), fill="black")
    d.text((L, 8), title or m.scenario, fill="black")
    canvas.save(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("path")
    ap.add_argument("metric")
    ap.add_argument("out")
    ap.add_argument("--x")
    ap.add_argument("--y")
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--also")
    ap.add_argument("--reduce", default="mean")
    ap.add_argument("--vmin", type=float)
    ap.add_argument("--vmax", type=float)
    ap.add_argument("--title", default="")
    ap.add_argument("--xmax", type=float, help="leave out the columns beyond this x")
    a = ap.parse_args()
    if a.profile:
        m = open_map(a.path, a.metric, x=a.x, y=False, reduce=a.reduce)
        also = open_map(a.path, a.also, x=a.x, y=False, reduce="mean") if a.also else None
        if a.xmax is not None:
            for mm in (m, also):
                if mm is not None:
                    keep = mm.x_values <= a.xmax + 1e-12
                    mm.x_values, mm.values = mm.x_values[keep], mm.values[:, keep]
        draw_profile(m, a.out, also, a.title)
    else:
        draw_map(open_map(a.path, a.metric, x=a.x, y=a.y, reduce=a.reduce), a.out, a.vmin, a.vmax, a.title)


if __name__ == "__main__":
    main()
