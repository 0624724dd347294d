"""The gallery as the app shows it: the scenarios' dropdown labels, the default camera of a
scenario that declares none, Euler's formula as panel markdown. The order (Euler's ch. 15, ch. 16,
the three papers, each in § order) and each scenario's camera live with the scenarios.

Cameras are in scene units (a rotation scene is scaled so that the body's largest semi-axis is 1,
the celestial sphere has radius 2.4, orbit scenes fit in radius 2; +z is up).
"""
from __future__ import annotations

import re

from theoria.physics.params import pretty_unit  # noqa: F401  (units as the panel prints them)
from theoria.scenarios.base import GROUP_ORDER, section_key

CUSTOM = "(your own values)"  # the Presets dropdown once a parameter has been changed by hand

Vec = tuple[float, float, float]


def default_camera(spec) -> tuple[Vec, Vec]:
    """A scenario without a curated camera: oblique for rotation scenes, from above for orbits."""
    if spec.kind != "rotation":
        return (0.0, -2.6, 4.2), (0.0, 0.0, 0.0)
    if spec.group == "ch. 15":
        return (3.0, 2.3, 1.8), (0.0, 0.0, 0.0)
    return (4.8, 3.7, 2.9), (0.0, 0.0, 0.0)


def camera_for(spec) -> tuple[Vec, Vec]:
    """(position, look_at) of the scenario's own camera, or the default for its kind of scene."""
    if spec.camera is not None:
        return tuple(spec.camera.position), tuple(spec.camera.look_at)
    return default_camera(spec)


def ordered(scenarios) -> list:
    """Scenarios in gallery order (as theoria.scenarios.all_scenarios: group, then § order)."""
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
    return [n for n in spec.presets]


def formula_markdown(formula: str) -> str:
    """Euler's formula(s), one per line, as markdown (plain Unicode: viser's markdown has no TeX)."""
    lines = [ln.strip() for ln in formula.split("\n") if ln.strip()]
    if not lines:
        return ""
    esc = [ln.replace("*", "\\*").replace("_", "\\_") for ln in lines]
    return "**Euler:**\n\n" + "\n".join(f"> {ln}  " for ln in esc)
