"""How each way of making the pose fit's σ describes the errors, from `trajdrift validate` grades.

Reproduces the figures of docs/evidence.md, "Two estimates of σ, pooled" and "The lever's share
of σ":

    for s in 1 1000 2000 3000; do
        trajdrift validate --missions 50 --seed $s --json g$s.json
    done
    python3 tests/python/sigma_parts.py g1.json g1000.json g2000.json g3000.json

Each grade carries the report's `sigma_parts` (the final fit's jackknife and formal σ, the profile
windows' σ for the same parameter, the lever's share, the cuts' part, the hidden drift) beside the error against the truth. For the
constant clocks and for the declared drifts it prints, per rule, the median |error|/σ, the share
2σ covers, and how many errors lie beyond 2.5σ once σ is scaled to a Gaussian's median (how well
the rule tells the missions apart, whatever its overall size); then how often 30 constant clocks
drawn at random hold 2σ coverage in 85–98 % and median |error|/σ in 0.4–1.2 together. Standard
library only.
"""

import json
import math
import random
import statistics
import sys
from collections import Counter

FLOOR_S = 1e-4  # the pose fit's least σ (POSE_SIGMA_FLOOR_S)
GAUSSIAN_MEDIAN = 0.6745


def with_hidden(p, s):
    return math.hypot(s, p["hidden_drift_s"], p.get("valley_s", 0.0), p.get("basins_s", 0.0))


def pooled(p, lever_s):
    """The mean of the jackknife's and the windows' variances (the windows' with `lever_s` in
    quadrature), at least the formal σ."""
    windows_var = (p["windows_s"] or 0.0) ** 2 + lever_s**2
    return max(math.sqrt((p["jackknife_s"] ** 2 + windows_var) / 2), p["formal_s"], FLOOR_S)


def less_cuts(p, s):
    cuts = p.get("cuts_s", 0.0)
    return min(s, max(math.sqrt(max(s * s - cuts * cuts, 0.0)), p["formal_s"], FLOOR_S))


RULES = {
    "reported": lambda p, g: g["sigma_s"],
    "jackknife alone": lambda p, g: max(p["jackknife_s"], FLOOR_S),
    "formal alone": lambda p, g: max(p["formal_s"], FLOOR_S),
    "windows alone": lambda p, g: max(p["windows_s"] or 0.0, FLOOR_S),
    "jackknife, at least formal": lambda p, g: with_hidden(
        p, max(p["jackknife_s"], p["formal_s"], FLOOR_S)
    ),
    "larger of the three": lambda p, g: with_hidden(
        p, max(p["jackknife_s"], p["formal_s"], p["windows_s"] or 0.0, FLOOR_S)
    ),
    "pooled, lever held": lambda p, g: with_hidden(p, pooled(p, 0.0)),
    # The constant's rule as it pools (every constant clock of the validation has three windows or
    # more and a jackknife that saw a spread; `combined` in each grade says which rule applied):
    # the windows' part with the share of σ the fitted lever adds, which the windows hold.
    "pooled, the lever's share": lambda p, g: with_hidden(p, pooled(p, p.get("lever_s", 0.0))),
    # The constant's Δt is the mean over tilings of the windows: what the cuts chose (their spread)
    # taken away in quadrature, at least the formal σ.
    "the lever's share, less the cuts": lambda p, g: with_hidden(
        p, less_cuts(p, pooled(p, p.get("lever_s", 0.0)))
    ),
}


def table(name, grades):
    print(f"{name}: {len(grades)} missions")
    print(f"  {'rule':28} {'median |e|/σ':>12} {'2σ covers':>10} {'beyond 2.5σ at equal median':>28}")
    for rule, sigma in RULES.items():
        z = [abs(g["error_s"]) / sigma(g["sigma_parts"], g) for g in grades]
        med = statistics.median(z)
        covered = sum(a <= 2 for a in z) / len(z)
        beyond = sum(a * GAUSSIAN_MEDIAN / med > 2.5 for a in z)
        print(f"  {rule:28} {med:12.3f} {100 * covered:9.1f}% {beyond:28d}")


def main(paths):
    grades = [g for path in paths for g in json.load(open(path))]
    usable = [g for g in grades if g.get("error_s") is not None and g.get("sigma_parts")]
    constant = [
        g
        for g in usable
        if g["drift_true_ppm"] == 0 and g["kind"] != "step" and g["model"] == "constant"
    ]
    linear = [g for g in usable if g["model"] == "linear"]
    table("constant clocks", constant)
    largest = Counter(
        max(("jackknife", "formal", "windows"), key=lambda k: g["sigma_parts"][f"{k}_s"] or 0.0)
        for g in constant
    )
    print(f"  the largest piece: {dict(largest)}")
    table("declared drifts (linear)", linear)
    z = [abs(g["error_s"]) / g["sigma_s"] for g in constant]
    rng = random.Random(1)
    draws = 20000
    held = 0
    for _ in range(draws):
        s = rng.sample(z, 30)
        held += 0.85 <= sum(a <= 2 for a in s) / 30 <= 0.98 and 0.4 <= statistics.median(s) <= 1.2
    print(f"30 constant clocks at random ({draws} draws): coverage and median both held on {100 * held / draws:.0f} %")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit("usage: sigma_parts.py GRADES.json... (from `trajdrift validate --json`)")
    main(sys.argv[1:])
