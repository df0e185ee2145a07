"""Experiment: a first sight's walk read off the columns of the last few images, or of the last one's centre.

Run: ``python benchmarks/exp_moving_evidence.py [--profile full] [--worlds 1000] [--skip 0] [--seed 1]
[--planners discs,tracking]`` (the disc planner needs its network: ``python -m husky_course train discs``).

A cylinder seen for the first time has no track. The arrivals rule
(:class:`~husky_course.planners.arrivals.Arrivals`) rules standing out when the previous image's
column through its centre saw through it. :meth:`~husky_course.planners.arrivals.Arrivals.read`
also weighs every column of the last ``images`` images: each hypothesised walk puts the circle
somewhere in each of them, a column that saw through it rules the walk out, and one that saw its
front where the walk puts it supports it. Variants, on the same worlds of the tuning set
(evaluation set 1 by default; ``--skip`` passes over its first worlds, for another slice):

* the disc planner (its learned discs) with ``images`` 0 (the centre column only), 1 and 3 (its
  setting, :class:`~husky_course.config.ArrivalsConfig`);
* the classical tracker (circles fitted to its pieces, of the course's mean radius) with 0 (its
  setting) and 3: the same rule offered to it.

Each line gives the success rate with its exact 95% interval and the paired count of worlds won
only with the variant / only without, against the same planner with ``images`` 0.

Measured (full profile), the disc planner, images 0 / 1 / 3: worlds 0-999 0.780 / 0.794 / 0.798
(25 / 7 for 3 against 0); 1,000-1,999 0.776 / 0.788 / 0.793 (23 / 6); 2,000-2,999 0.795 / 0.802 /
0.811 (26 / 10). The tracker, 0 / 3: 0.735 / 0.744 (24 / 15) and 0.756 / 0.756 (16 / 16) on the
first two slices: what the evidence gives follows the learned discs' accuracy (their centres'
median lateral error is about 1 cm within 3 m, the fitted circles' 3 cm).
"""

from __future__ import annotations

import numpy as np
from exp_moving_start import paired_line  # benchmarks/, the script's own folder
from exp_moving_walls import run, slice_setup

from husky_course.planners.registry import make_planner

IMAGES = {"discs": (0, 1, 3), "tracking": (0, 3)}


def main() -> None:
    names, profile, sim, limit, seeds = slice_setup(__doc__)
    for name in names:
        base = None
        for images in IMAGES[name]:
            learned = {"profile": profile} if name == "discs" else {}
            planner = make_planner(name, config=profile.sim, **learned)
            planner.map.arrivals.images = images  # type: ignore[attr-defined]
            won = np.array([run(planner, sim, s, limit, "bouncing, faces read") for s in seeds])  # as it is
            print(paired_line(f"{name:9s} images {images}", won, base), flush=True)
            base = won if base is None else base


if __name__ == "__main__":
    main()
