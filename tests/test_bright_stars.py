"""assets/bright_stars.csv was typed by hand (no network at build time). Checked here against an
independent source: PyEphem's built-in star list (Hipparcos J2000 positions, XEphem database),
for every star the two have in common."""
from __future__ import annotations

import numpy as np
import pytest

from theoria.app.bright_stars import load_bright_stars

ephem = pytest.importorskip("ephem")
import ephem.stars  # noqa: E402

# Known differences in V with their reason (not typing errors): the catalogue gives the combined
# light of α Cen A+B (−0.27), PyEphem α Cen A alone (−0.01); Canopus −0.74 (V, BSC) against PyEphem's
# −0.62; Antares is a variable (0.6–1.6).
MAG_REASON = {"Rigil Kentaurus": 0.3, "Canopus": 0.15, "Antares": 0.15}


def test_positions_and_magnitudes_match_pyephem():
    cat = load_bright_stars()
    common = [k for k, n in enumerate(cat.names) if n in ephem.stars.stars]
    assert len(common) >= 60
    seps, dmag = [], []
    for k in common:
        s = ephem.star(cat.names[k])
        s.compute("2000/1/1 12:00", epoch="2000")  # J2000 position at epoch J2000 (no proper motion)
        ra, dec = float(s.a_ra), float(s.a_dec)
        r1, d1 = np.radians(cat.ra_deg[k]), np.radians(cat.dec_deg[k])
        c = np.sin(d1) * np.sin(dec) + np.cos(d1) * np.cos(dec) * np.cos(r1 - ra)
        seps.append(np.degrees(np.arccos(np.clip(c, -1, 1))) * 3600)
        dmag.append(abs(cat.vmag[k] - s.mag) - MAG_REASON.get(cat.names[k], 0.0))
    seps = np.array(seps)
    # the file rounds to 0.1 s in RA (1.5″ at the equator) and 1″ in Dec
    assert seps.max() < 3.0, (cat.names[common[int(np.argmax(seps))]], seps.max())
    assert max(dmag) <= 0.07
