"""The unit of every number a run returns.

A metric's name carries its unit where the unit is a common one: `energy_J`, `polhode_period_s`,
`precession_rate_arcsec_per_yr`. The scenario declares the rest (`Scenario.metric_units`): numbers in
the scenario's own units (orbits, the mean motion n, 1/δ) and pure numbers (a ratio, a cosine, a
count, a relative error), whose unit is "". Units are written as parameters write theirs
(`Param.unit`: "rad/s", "deg", "n"); `physics.params.pretty_unit` prints them for a person.
"""
from __future__ import annotations

import re
from collections.abc import Mapping

# a name's last words → its unit; longest first, so that "rad_per_s" wins over "s"
NAME_SUFFIXES = (
    ("arcsec_per_century", "arcsec/century"), ("arcsec_per_yr", "arcsec/yr"), ("deg_per_yr", "deg/yr"),
    ("kg_m2_per_s", "kg m^2/s"), ("rad_per_s2", "rad/s^2"), ("rad_per_s", "rad/s"), ("rad_per_day", "rad/day"),
    ("per_orbit", "1/orbit"), ("per_s", "1/s"), ("per_yr", "1/yr"), ("per_day", "1/day"),
    ("arcsec", "arcsec"), ("mas", "mas"), ("deg", "deg"), ("rad", "rad"), ("years", "yr"), ("yr", "yr"),
    ("days", "d"), ("day", "d"), ("d", "d"), ("s", "s"), ("km", "km"), ("au", "au"), ("m", "m"), ("J", "J"),
    ("pct", "%"), ("percent", "%"), ("hz", "Hz"),
    ("orbits", "orbits"), ("lunar_units", "b"), ("n", "n"),  # the Moon's distance b; the mean motion n
)


def unit_in_name(key: str) -> tuple[str, str] | None:
    """(the name without its unit, the unit) when the name ends in one, else None:
    "flip_interval_s" → ("flip_interval", "s")."""
    for suffix, unit in NAME_SUFFIXES:
        if key.endswith("_" + suffix) and len(key) > len(suffix) + 1:
            return key[: -len(suffix) - 1], unit
    return None


# a plot's label ends in its unit in brackets: "obliquity of date (deg)", "node longitude (deg, simulated)"
_LABEL_UNIT = re.compile(r"\(([^(),]+)(?:,[^()]*)?\)$")
LABEL_UNITS = {unit for _, unit in NAME_SUFFIXES} | {"arcmin", "rad/s"}


def unit_in_label(label: str) -> str | None:
    """The unit a plot's label ends in, in brackets ("obliquity, Vondrák 2011 (deg)" → "deg"), if
    it is one (not "BC/AB (simulated)")."""
    m = _LABEL_UNIT.search(label)
    return m.group(1).strip() if m and m.group(1).strip() in LABEL_UNITS else None


def metric_unit(key: str, declared: Mapping[str, str]) -> str | None:
    """The unit of metric `key`: the scenario's declaration (a name, or a pattern matching whole
    names such as r"gp_half_width_[\\d.]+") first, then the unit in the name; None if neither says."""
    if key in declared:
        return declared[key]
    for pattern, unit in declared.items():
        if re.fullmatch(pattern, key):
            return unit
    found = unit_in_name(key)
    return found[1] if found else None


# a trajectory's time unit → the unit of a rate in it: its own unit where the scenario measures time
# in a rate's inverse (the mean motion n, Euler's δ), else radians per time unit
RATE_OF_TIME_UNIT = {"1/n·rad": "n", "1/δ": "δ"}
TIME_UNITS = {"s", "day", "yr", "unit"}  # "unit": a scenario's own unit of time


def rotation_units(time_unit: str, moment_unit: str) -> dict[str, str]:
    """The units of a rotating body's ω, L = Iω and kinetic energy ½ω·L, with the time of its
    trajectory in `time_unit` and its principal moments in `moment_unit` ("kg m^2", or "C" where
    the largest moment is the unit). Radians are left out of L and E, as SI leaves them out of the
    joule. Empty where the trajectory's variable is not a time (a sweep of sizes)."""
    rate = RATE_OF_TIME_UNIT.get(time_unit)
    if rate is None and time_unit not in TIME_UNITS:  # the run's "time" is not one (a sweep of sizes)
        return {}
    if rate is None:
        if moment_unit == "kg m^2" and time_unit == "s":
            return {"omega": "rad/s", "L": "kg m^2/s", "energy": "J"}
        return {"omega": f"rad/{time_unit}", "L": f"{moment_unit}/{time_unit}",
                "energy": f"{moment_unit}/{time_unit}^2"}
    return {"omega": rate, "L": f"{moment_unit} {rate}", "energy": f"{moment_unit} {rate}^2"}
