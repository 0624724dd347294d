"""Reads the bright-star catalogue asset (assets/bright_stars.csv) for the celestial sphere.
Physics never reads files: the app loads the catalogue here and passes arrays on (e.g. to
physics.earth_precession.pole_star_passages or equatorial_to_ecliptic)."""
from __future__ import annotations

import csv
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

ASSET = "bright_stars.csv"  # package data of theoria.assets: present in a wheel as in a checkout


@dataclass(frozen=True)
class StarCatalogue:
    names: tuple
    bayer: tuple
    ra_deg: np.ndarray  # J2000
    dec_deg: np.ndarray  # J2000
    vmag: np.ndarray


def load_bright_stars(path: str | Path | None = None) -> StarCatalogue:
    if path is None:
        text = resources.files("theoria.assets").joinpath(ASSET).read_text(encoding="utf-8")
    else:
        text = Path(path).read_text(encoding="utf-8")
    rows = [r for r in csv.DictReader(line for line in text.splitlines()
                                       if line.strip() and not line.startswith("#"))]
    ra = np.array([15.0 * (float(r["ra_h"]) + float(r["ra_m"]) / 60 + float(r["ra_s"]) / 3600) for r in rows])
    dec = np.array([(-1.0 if r["dec_sign"] == "-" else 1.0)
                    * (float(r["dec_d"]) + float(r["dec_m"]) / 60 + float(r["dec_s"]) / 3600) for r in rows])
    return StarCatalogue(tuple(r["name"] for r in rows), tuple(r["bayer"] for r in rows), ra, dec,
                         np.array([float(r["vmag"]) for r in rows]))
