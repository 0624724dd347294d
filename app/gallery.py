"""The gallery: every scenario in one list, grouped by source (Euler's ch. 15, ch. 16, the three
papers on three bodies) and, within a group, in the order of Euler's § (issue 7, item 1); the
curated camera of each scenario; Euler's formula as panel markdown.

Cameras are data for the app (the physics modules know nothing of views): `CAMERAS[name]` is
(position, look_at) in scene units (a rotation scene is scaled so that the body's largest
semi-axis is 1, the celestial sphere has radius 2.4, orbit scenes fit in radius 2; +z is up).
"""
from __future__ import annotations

import re

GROUP_ORDER = ("ch. 15", "ch. 16", "three bodies")
CUSTOM = "(your own values)"  # the Presets dropdown once a parameter has been changed by hand

Vec = tuple[float, float, float]

# name → (camera position, look-at point)
CAMERAS: dict[str, tuple[Vec, Vec]] = {
    # ch. 15: close to the body, oblique, so that polhode, herpolhode and the invariable plane show
    "free-tumble": ((3.0, 2.3, 1.8), (0.0, 0.0, 0.0)),
    "middle-axis-flip": ((3.4, 1.2, 1.6), (0.0, 0.0, 0.0)),  # B (green) axis across the view: the flip is seen
    "initial-axis": ((2.6, 2.6, 1.9), (0.0, 0.0, 0.0)),
    # ch. 16: farther out, the direction of F (radius 2) and the celestial sphere (radius 2.4) in view
    # across F's default direction (0.6, 0.5, 0.3), F on the left: its label runs toward the body, not under the panel
    "gravity-gradient-accuracy": ((-2.0, 3.8, 2.2), (0.0, 0.0, 0.0)),
    "gravity-start": ((1.2, -4.4, 2.4), (0.0, 0.0, 0.0)),  # across F (default direction (1, 0.6, 0.4)), not along it
    "libration-circular": ((0.8, -2.0, 5.2), (0.0, 0.0, 0.0)),  # from above F's orbit plane (body xy)
    "libration-eccentric": ((0.8, -2.0, 5.2), (0.0, 0.0, 0.0)),
    "hyperion": ((0.8, -2.0, 5.2), (0.0, 0.0, 0.0)),
    "moon": ((4.2, -3.6, 2.4), (0.0, 0.0, 0.0)),
    "pole-near-axis": ((4.6, 1.6, 1.4), (0.8, 0.0, 0.0)),  # nearly down the spin axis A (body x): the pole path beyond it face-on
    "precession-circular": ((4.6, -4.0, 3.0), (0.0, 0.0, 0.4)),
    "earth": ((4.6, -4.0, 3.0), (0.0, 0.0, 0.4)),
    "earth-long-view": ((3.6, -3.2, 4.4), (0.0, 0.0, 0.6)),  # the pole's circle near the top of the sphere
    # three bodies: from above the plane of motion, a little tilted
    "collinear": ((0.0, -0.9, 3.4), (0.0, 0.0, 0.0)),  # from above: L1–L5, zero-velocity curves
    "syzygy": ((0.4, -0.8, 3.1), (0.4, 0.0, 0.0)),  # co-rotating: Sun on +x, both syzygy points in view
    "lunar-perturbation": ((0.9, -3.1, 2.1), (0.0, 0.0, 0.35)),  # oblique: orbit plane, node line, normal
}

# name → overlays switched on/off against the group's default (app/scene.py OVERLAYS): drawings
# that say nothing in that scene are off, so what the scenario shows is not hidden in a tangle
OVERLAY_DEFAULTS: dict[str, dict[str, bool]] = {
    # the pole's own magnified path says it all; over several turns under a strong pull the
    # rotation-axis trail and the axis paths on the celestial sphere wind into a ball of string
    "pole-near-axis": {"celestial": False, "axis_trail": False, "polhode": False},
    # no motion: the run is a sweep of the distance of F (t is size/distance)
    "gravity-gradient-accuracy": {"celestial": False, "axis_trail": False, "polhode": False, "vectors": False},
}


def default_camera(spec) -> tuple[Vec, Vec]:
    """A scenario without a curated camera: oblique for rotation scenes, from above for orbits."""
    if spec.kind != "rotation":
        return (0.0, -2.6, 4.2), (0.0, 0.0, 0.0)
    if spec.group == "ch. 15":
        return (3.0, 2.3, 1.8), (0.0, 0.0, 0.0)
    return (4.8, 3.7, 2.9), (0.0, 0.0, 0.0)


def camera_for(spec) -> tuple[Vec, Vec]:
    return CAMERAS.get(spec.name) or default_camera(spec)


_ROMAN = {"I": 1, "V": 5, "X": 10, "L": 50, "C": 100}


def _roman(s: str) -> int:
    total = 0
    for a, b in zip(s, s[1:] + " "):
        v = _ROMAN[a]
        total += -v if _ROMAN.get(b, 0) > v else v
    return total


def section_key(section: str) -> tuple:
    """Sort key of a § string: (year of the paper, first §, 1 if the scene goes beyond Euler)."""
    year = re.search(r"\b(1[78]\d\d)\b", section)
    m = re.search(r"§\s*(\d+|[IVXLC]+)", section)
    first = 0
    if m:
        first = int(m.group(1)) if m.group(1).isdigit() else _roman(m.group(1))
    beyond = 1 if "(" in section else 0  # "(modern values)", "(beyond Euler)" after Euler's own
    return (int(year.group(1)) if year else 0, first, beyond)


def ordered(scenarios) -> list:
    """Scenarios in gallery order: groups as GROUP_ORDER, then § order, then name."""
    def key(s):
        g = GROUP_ORDER.index(s.group) if s.group in GROUP_ORDER else len(GROUP_ORDER)
        return (g, s.group, section_key(s.section), s.name)

    return sorted(scenarios, key=key)


def first_section(section: str) -> str:
    m = re.search(r"§\s*[\dIVXLC]+(?:\s*[–-]\s*§?\s*[\dIVXLC]+)?", section)
    return m.group(0).replace(" ", "") if m else section


def label(spec) -> str:
    """The scenario's line in the dropdown: group, (paper's year,) §, title."""
    sec = first_section(spec.section)
    year = re.search(r"\b(1[78]\d\d)\b", spec.section)
    if year:
        sec = f"{year.group(1)} {sec}"
    return f"{spec.group} · {sec} · {spec.title}"


def preset_names(spec) -> list[str]:
    return [n for n, _ in spec.presets]


def formula_markdown(formula: str) -> str:
    """Euler's formula(s), one per line, as markdown (plain Unicode: viser's markdown has no TeX)."""
    lines = [ln.strip() for ln in formula.split("\n") if ln.strip()]
    if not lines:
        return ""
    esc = [ln.replace("*", "\\*").replace("_", "\\_") for ln in lines]
    return "**Euler:**\n\n" + "\n".join(f"> {ln}  " for ln in esc)
