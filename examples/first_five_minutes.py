"""A student's first five minutes with theoria: Euler's flip about the middle axis (§808).

Run it as a script (`python examples/first_five_minutes.py [OUTDIR]`) or paste the steps into a
notebook cell by cell. It writes flip.html (a replay that plays in any browser, offline) and
flip.rrd (a recording for the rerun viewer) into OUTDIR (default: the current directory).
"""
import sys
from pathlib import Path

import theoria as th

out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")

# 1. What is there: every scenario, in the order of Euler's sections.
print("scenarios:", ", ".join(th.scenarios()))

# 2. One scenario: its parameters (unit, allowed range, default) and its presets.
sc = th.scenario("middle-axis-flip")
print(f"\n{sc.title} ({sc.section})\n{sc.summary}\n")
for name, p in sc.parameters.items():
    print(f"  {name:<14} default {p.default!s:<18} {p.allowed():<34} {p.help}")
print("presets:", "; ".join(sc.presets))

# 3. A run: spin a brick slowly about its middle axis with a 1 % nudge, for 200 seconds.
run = sc.simulate(spin=1, perturbation=0.01, duration=200)
units = run.metric_units  # every metric's unit ("" for a pure number such as a count)
print(f"\nflips seen: {run.metrics['flips_seen']:.0f}, "
      f"interval between flips: {run.metrics['flip_interval']:.4f} {units['flip_interval']}")
for c in run.comparisons:  # Euler says / simulated / modern
    print(f"  {c.label}: Euler {c.euler:.6f}, simulated {c.simulated:.6f}, modern {c.modern:.6f} {c.unit}")
print("warnings:", run.warnings or "none")

# 4. A smaller nudge waits longer between flips: a preset (named after what it shows) at the
#    same spin (keywords override the preset's values, and the preset spins six times faster).
tiny = sc.simulate(preset="tiny nudge", spin=1, duration=200)
print(f"with a nudge of {tiny.params['perturbation']:g}: {tiny.metrics['flip_interval_exact']:.2f} s between flips, "
      f"against {run.metrics['flip_interval_exact']:.2f} s with {run.params['perturbation']:g}")

# 5. A value out of range is refused with the parameter, the value and what is allowed.
try:
    sc.simulate(spin=1e9)
except th.ParameterError as e:
    print("refused:", e)

# 6. The numbers as a table (pandas), a replay to open in a browser, a recording for rerun.
try:
    df = run.to_dataframe()
    print(f"\n{len(df)} samples; columns: {', '.join(df.columns[:8])}, ...")
except ImportError as e:
    print(e)
print(run.export_html(out / "flip.html"))
print(run.record(out / "flip.rrd"))
# run.show()  # serves this run in the app at http://127.0.0.1:8080 (Ctrl-C to stop)
