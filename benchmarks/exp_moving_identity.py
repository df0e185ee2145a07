"""Experiment: ghosts that know which new disc is their own cylinder's from the camera alone (its track).

Run: ``python benchmarks/exp_moving_identity.py [--profile full] [--worlds 1000] [--start 7000]
[--agreement 1000] [--variants ghosts track track-end track-make] [--check] [--workers 2] [--base B.npz]``
(the disc planner needs its networks: ``python -m husky_course train discs`` and ``train cuts``; ``--base``:
the planner's own episodes kept for the next run, as ``exp_moving_variants.py`` keeps them).

Why: ``exp_moving_drift.py`` found that ``exp_moving_doubt_memory.py``'s ghosts (a dropped disc kept as one
hypothesis per walk of the course's motion model, its walks an image sees through ruled out) lacked
*identity*, not place: told which new disc is its own cylinder's (privileged), a ghost that ends only when its
own cylinder is seen again, and is made for every dropped disc whose cylinder the new image shows no disc
of, gives all of ``exp_moving_memory.py``'s rule ``S`` (12 / 2 on tuning worlds 7,000-7,999, ``S`` 14 / 4).
The camera's own answer to "which new disc is which cylinder" is the tracks
(:class:`~husky_course.planners.motion.Tracks`): a piece of surface joins the track whose line predicts it,
so a new disc either *continues* a track that was there before this image, or is a first sight (a new
track), or lies on a piece too long to track (over 1 m: a wall, or several things read as one).

Every disc here carries the name of its piece's track (a name per track, kept while the track is
continued: this script's ``NamedTracks`` gave them from outside the library until ``track`` joined the
library, whose :class:`~husky_course.planners.motion.Tracks` now name their tracks, the same names). The
rules (:class:`IdentityMap`, on the ghosts of ``exp_moving_doubt_memory.py``, with their draws from the
course's prior: nothing privileged):

* ``track-end``: a ghost ends when a new disc continues its own track, or when a new disc that continues no
  earlier track (a first sight, or untracked) overlaps one of its open walks; a new disc continuing another
  track (another cylinder, as far as the camera can tell) leaves it. A ghost of an untracked disc ends as
  before, on any new disc over an open walk.
* ``track-make``: a ghost is made for every disc an image sees through or again (its centre column reaches
  its front) unless its own cylinder is found: a new disc continues its track, or a new disc that continues
  no other track lands on it (centres closer than the larger radius; any new disc, for an untracked disc).
  As before, a ghost is made only where its disc is at most ``GHOST_AGE`` steps old and some walk is still
  open.
* ``track``: both.

``ghosts`` is ``exp_moving_doubt_memory.py``'s ghosts as they are (a ghost ends on any new disc over an open
walk; made only where no new disc landed on the dropped one). Each variant runs as a planner on the same
tuning worlds as the planner as it is: success with its exact interval, the worlds won only with / only
without it, exact sign test. ``--check`` adds :data:`NEITHER` (the identity map with neither rule, on the
named tracks), which must win exactly the worlds ``ghosts`` wins, or the script fails. ``--agreement N``
counts, along the ``track`` planner's runs on ``N`` tuning worlds (privileged: :class:`CheckedMap`), which
rule says each dropped disc's cylinder was found again, against what became of it; then the ghosts the
``track`` and the ``ghosts`` planners keep, by the truth of the disc each was made from.

The rule for choosing, written down after the first slice ran and before the second: the variant is chosen
on tuning worlds 7,000-8,999 (both slices, by worlds won only with it less worlds won only without), and the
chosen one is tested on tuning worlds 9,000-12,999, four slices of 1,000 no choice here has seen, only if it
wins more worlds than it loses on 7,000-8,999; the test's pooled sign test is the result.

Measured (full profile): see :data:`MEASURED`. ``track`` has since joined the library as the disc planner's
ghosts (:mod:`husky_course.planners.ghosts`, ``ArrivalsConfig.ghosts``; the planner took the same action as
this script's ``track`` in all 300 episodes of full-profile tuning worlds 7,000-7,299). The variants here run
with the library's ghosts off (they are ghosts of their own), and the planner as it is they pair with now
has them: the figures below were measured against the planner before it had them.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import exp_moving_doubt_memory as doubt
import exp_moving_variants as variants
import numpy as np
from exp_moving_memory import belonging

from husky_course.config import Profile, get_profile, with_world
from husky_course.engines import map_tasks
from husky_course.evaluation.episodes import eval_world_seeds, run_episode
from husky_course.sim.fast import FastSimulator

MEASURED = """
Full profile, library fingerprint ``199de8c9e356d225``. Which rule says a dropped disc's cylinder was found
again (``--agreement 1000``, about 2.5 minutes on 2 cores), tuning worlds 7,000-7,999 / 8,000-8,999:

=====================  =============  =============  =============  ===================================
truth                  discs          a disc landed  the tracks     of which own track / a disc lands
=====================  =============  =============  =============  ===================================
found again            25,234/25,595  0.843 / 0.839  0.979 / 0.976  24,541 / 152, 24,849 / 136
not found, standing    296 / 338      0.287 / 0.287  0.243 / 0.222  69 / 3, 72 / 3
not found, walking     511 / 518      0.153 / 0.185  0.147 / 0.133  72 / 3, 68 / 1
no cylinder            339 / 359      0.027 / 0.039  0.029 / 0.022  9 / 1, 7 / 1
=====================  =============  =============  =============  ===================================

The tracks find a cylinder seen again 98% of the time, a landing disc 84% (its new disc lies more than a
radius from the old one). But the cylinders no new disc belongs to are found, wrongly, about as often by the
tracks (13-15% of walkers, 22-24% of standing ones) as by a landing disc (15-19%, 29%), and almost all of the
tracks' errors are their own joins (140 of 144 walkers: another cylinder's piece continued the dropped one's
track; the last column's split was added to the script after the first slice's episodes ran).

The ghosts each planner keeps after an image (summed over images, along its own runs; counted on 7,000-7,999
after the slices' choice, with ``--agreement 1000``), by the truth of the disc each was made from: ``track``
1,050 of cylinders found again / 491 not found, standing / 859 not found, walking / 1,078 of no cylinder;
``ghosts`` 266 / 279 / 534 / 977. The tracks keep 61% more ghosts of the walkers really lost, and four times
as many of cylinders the same image found again (a cylinder counted twice, once as a ghost): the likely cost
in the worlds ``track`` loses, and what a better identity rule would remove. Of the 362 such ghosts ``track``
made (``ghosts`` 115), 343 (97) were made where the cylinder's new disc continued another cylinder's track,
19 (18) where it was a first sight lying on none of the ghost's open walks: the tracks' association (a piece
joining the wrong track), not the ghosts' rules, is what to mend next.

Episodes (``--worlds 1000``, about 3 minutes a variant), won only with / only without, against the planner
as it is (0.838 / 0.862):

==============  =====================  =====================  ==========
variant         7,000-7,999            8,000-8,999            together
==============  =====================  =====================  ==========
``ghosts``      0.838 (3 / 3)          0.865 (7 / 4)          10 / 7
``track-make``  0.838 (3 / 3)          0.865 (7 / 4)          10 / 7
``track-end``   0.840 (6 / 4)          0.867 (12 / 7)         18 / 11
``track``       0.844 (12 / 6)         0.870 (16 / 8)         28 / 14
==============  =====================  =====================  ==========

``track-make`` gives the ghosts' figures to the world: a ghost made where a new disc landed on its disc is, as
a rule, ended on the spot by that disc (it overlaps the walk that kept the disc's own speed) unless the ending
rule changes too. ``--check`` on 8,000-8,999: with neither rule the map won exactly the ghosts' worlds.
``track`` was chosen by the rule above (28 / 14) and tested: on tuning worlds 9,000-12,999 (``--start S
--variants track``, about 6 minutes a slice; the planner as it is 0.844 / 0.837 / 0.855 / 0.852, as
``exp_moving_doubt_memory.py`` measured them) it crossed 0.849 (11 / 6), 0.842 (14 / 9), 0.858 (12 / 9) and
0.867 (20 / 5): together 57 / 29, p = 0.003, 0.854 against 0.847. With the slices it was chosen on, 85 / 43.
Rule ``S`` (privileged) held 26 / 8 on 7,000-8,999 and the ghosts told their own cylinder 26 / 7; the
camera's identity wins as many worlds (28) but loses more (14).
"""
TRUTHS = ("found again", "not found, standing", "not found, walking", "no cylinder")  #: :class:`CheckedMap`
RULES = ("ghosts", "track", "track-end", "track-make")  #: the variants (module docstring)
#: :class:`IdentityMap` with neither rule (``--check``): it must win exactly the worlds ``ghosts`` wins
NEITHER = "neither"


class IdentityMap(doubt.DoubtingMap):
    """``exp_moving_doubt_memory.py``'s ghosts, ended and made by the tracks' identity as :attr:`rule`
    names (module docstring). ``names``: per disc, its piece's track's name when it was made (-1: none)."""

    rule: frozenset[str]

    def new_names(self, new: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(names, strange)`` per disc of ``new``: its piece's track's name (-1: none), and whether it
        continues no earlier track (a first sight, or a piece too long to track)."""
        tracks = self.motion.tracks
        if not len(new):
            return np.zeros(0, int), np.zeros(0, bool)
        return tracks.piece_names[self._cylinder], ~tracks.continued[self._cylinder]

    def found(self, new: np.ndarray, names: np.ndarray, strange: np.ndarray) -> np.ndarray:
        """Per remembered disc, whether the tracks say the new image found its cylinder again, and how: 1, a
        new disc of ``new`` (track names ``names``) continues its track; 2, a new disc that continues no
        earlier track (``strange``: a first sight, or untracked) lands on it (any new disc lands, for a
        disc with no track); 0, neither."""
        if not len(new):
            return np.zeros(len(self.discs), int)
        gap = np.hypot(self.discs[:, None, 0] - new[None, :, 0], self.discs[:, None, 1] - new[None, :, 1])
        lands = gap < np.maximum(self.discs[:, None, 2], new[None, :, 2])
        mine = self.names[:, None] >= 0
        track = (mine & (self.names[:, None] == names[None])).any(1)
        return np.where(track, 1, np.where((lands & (strange[None] | ~mine)).any(1), 2, 0))

    def _merge(self, obs: np.ndarray, d: np.ndarray, new: np.ndarray, other: np.ndarray) -> np.ndarray:
        names, strange = self.new_names(new)
        end, make = "end" in self.rule, "make" in self.rule

        def ended(g: dict) -> bool:
            if not g["open"].any():
                return True
            if end and g["name"] >= 0:
                return bool((names == g["name"]).any()) or doubt.found(g, new[strange])
            return doubt.found(g, new)

        for g in self.ghosts:
            g["open"] &= ~self.seen_through(g, d)
        self.ghosts = [g for g in self.ghosts if not ended(g)]
        seen, landed = self.forgotten(d, new)
        made = seen & ~(self.found(new, names, strange) > 0 if make else landed)
        for k in np.flatnonzero(made):  # as DoubtingMap makes its ghosts, each with its disc's track's name
            g = self.ghost(k, d) | {"name": int(self.names[k]), "from": int(k)}
            if g["life"] <= doubt.GHOST_AGE and not ended(g):
                self.ghosts.append(g)
        return super(doubt.DoubtingMap, self)._merge(obs, d, new, other)  # the library's names kept there


class CheckedMap(IdentityMap):
    """:class:`IdentityMap` that also counts (privileged: the eyes of ``exp_moving_doubt_memory.py``'s
    ``ToldPlanner``) every disc an image sees through or again, by what became of its cylinder (found again:
    a new disc belongs to it; not found, standing or walking; no cylinder under the disc) and which rule says
    it was found: a new disc landed on it (``ghosts``), the tracks (:meth:`IdentityMap.found`, and how):
    ``counts[truth, landed, how]``; and the ghosts its own rules keep after each image, by the truth of the
    disc each was made from: ``alive[truth]``; and the ghosts made of a cylinder found again, by the new disc
    that found it (untracked, a first sight, continuing another track): ``double``. All kept across
    episodes."""

    ids: np.ndarray
    counts: np.ndarray
    alive: np.ndarray
    double: np.ndarray

    def reset(self) -> None:
        super().reset()
        self.ids = np.zeros(0, int)
        if not hasattr(self, "counts"):
            self.counts, self.alive = np.zeros((len(TRUTHS), 2, 3), int), np.zeros(len(TRUTHS), int)
            self.double = np.zeros(3, int)

    def move(self, dx: float, dy: float) -> np.ndarray:
        kept = super().move(dx, dy)
        self.ids = self.ids[kept]
        return kept

    def _merge(self, obs: np.ndarray, d: np.ndarray, new: np.ndarray, other: np.ndarray) -> np.ndarray:
        cyl, vy = self.truth
        own = belonging(new, cyl) if len(new) else np.zeros(0, int)
        seen, landed = self.forgotten(d, new)
        found = self.found(new, *self.new_names(new))
        truths = np.full(len(self.discs), -1)
        for k in np.flatnonzero(seen):
            i = int(self.ids[k])
            truths[k] = 3 if i < 0 else 0 if i in own else 2 if vy[i] != 0 else 1
            self.counts[truths[k], int(landed[k]), int(found[k])] += 1
        held = list(self.ghosts)  # held, so that no new ghost takes the id of one dropped here
        before = {id(g) for g in held}
        names, strange = self.new_names(new)
        kept = super()._merge(obs, d, new, other)
        for g in self.ghosts:
            if id(g) not in before:
                g["truth"] = int(truths[g["from"]])
                if g["truth"] == 0:  # its cylinder's new disc: untracked, a first sight, another track's
                    j = int(np.flatnonzero(own == self.ids[g["from"]])[0])
                    self.double[0 if names[j] < 0 else 1 if strange[j] else 2] += 1
            self.alive[g["truth"]] += 1
        self.ids = np.r_[own, self.ids[kept]]
        return kept


def agreement(args: tuple[Profile, list[int], str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:class:`CheckedMap`'s counts along the runs on ``seeds`` of the planner ``variant`` names."""
    profile, seeds, variant = args
    planner = identity_planner(profile, variant)
    planner.__class__ = doubt.ToldPlanner  # eyes for the counts only: the ghosts' draws are not told
    planner.map.__class__ = CheckedMap
    planner.map.reset()
    sim = FastSimulator(profile.sim)
    for seed in seeds:
        run_episode(planner, sim, seed, profile.sim.max_primitives)
    return planner.map.counts, planner.map.alive, planner.map.double


def identity_planner(profile: Profile, variant: str):
    """The disc planner with ``exp_moving_doubt_memory.py``'s ghosts, ended and made as ``variant`` says
    (:data:`RULES`)."""
    if variant not in (*RULES, NEITHER):
        raise SystemExit(f"a variant is one of {', '.join(RULES)}; got {variant!r}")
    planner = doubt.doubting_planner(profile, "ghosts")
    if variant != "ghosts":
        planner.map.__class__ = IdentityMap
        rules = {"track": {"end", "make"}, NEITHER: set()}.get(variant, {variant[6:]})
        planner.map.rule = frozenset(rules)
        planner.map.reset()
    return planner


def report(counts: np.ndarray, alive: dict[str, np.ndarray], double: dict[str, np.ndarray], first: int,
           n: int, profile: str) -> None:
    """Print :func:`agreement`'s counts: per truth, how often each rule says the cylinder was found, and
    the ghosts each planner keeps after an image."""
    print(f"discs an image saw through or again along the track planner's runs, moving tuning worlds "
          f"{first}-{first + n - 1} ({profile} profile), and which rule said their cylinder was found:")
    print(f"  {'truth':22s} {'discs':>7s} {'a disc landed':>14s} {'the tracks':>11s} {'by its track':>13s} "
          f"{'a new lands':>12s} {'only landed':>12s} {'only tracks':>12s}")
    for name, c in zip(TRUTHS, counts, strict=True):
        total = int(c.sum())
        if total:
            tracks = c[:, 1:].sum()
            print(f"  {name:22s} {total:7d} {c[1].sum() / total:14.3f} {tracks / total:11.3f} "
                  f"{c[:, 1].sum():13d} {c[:, 2].sum():12d} {c[1, 0]:12d} {c[0, 1:].sum():12d}")
    print("ghosts kept after an image (summed over images), by what became of the cylinder of the disc each "
          "was made from, along each planner's own runs:")
    print(f"  {'planner':10s} " + " ".join(f"{t:>20s}" for t in TRUTHS))
    for variant, a in alive.items():
        print(f"  {variant:10s} " + " ".join(f"{int(x):20d}" for x in a))
    for variant, (untracked, first_sight, other) in double.items():
        print(f"ghosts {variant} made of a cylinder the same image found again, by the new disc that found "
              f"it: untracked {untracked}, a first sight {first_sight}, continuing another track {other}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=1000)
    parser.add_argument("--start", type=int, default=7000, help="the first tuning world (evaluation set 1)")
    parser.add_argument("--variants", nargs="*", default=list(RULES), help=f"of {', '.join(RULES)}")
    parser.add_argument("--agreement", type=int, default=0,
                        help="tuning worlds on which to count whose cylinder each rule finds (0: none)")
    parser.add_argument("--check", action="store_true",
                        help=f"add the variant {NEITHER!r}, which must win exactly the worlds ghosts wins")
    parser.add_argument("--base", type=Path, help=variants.BASE_HELP)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    if args.worlds < 1:
        raise SystemExit(f"--worlds must be positive; got {args.worlds}")
    profile = with_world(get_profile(args.profile), "moving")
    for name in args.variants:
        identity_planner(profile, name)  # a bad name fails before any world runs
    if args.agreement:
        seeds = [int(s) for s in eval_world_seeds(args.start + args.agreement, 1)[args.start:]]
        counts, alive, double = None, {}, {}
        for variant in ("track", "ghosts"):  # ghosts: the map with neither rule, as ``--check`` shows
            parts = map_tasks(agreement, [(profile, seeds[i : i + 10], "track" if variant == "track" else
                                           NEITHER) for i in range(0, len(seeds), 10)],
                              workers=args.workers, desc=f"agreement ({variant})", unit="10 worlds")
            counts = sum(p[0] for p in parts) if counts is None else counts
            alive[variant], double[variant] = sum(p[1] for p in parts), sum(p[2] for p in parts)
        report(counts, alive, double, args.start, args.agreement, profile.name)
    names = [*args.variants, *(["ghosts", NEITHER] if args.check else [])]
    names = list(dict.fromkeys(names))
    if not names:
        return
    worlds = variants.tuning_worlds(args.start, args.worlds, profile.name)
    won = variants.paired_episodes(identity_planner, names, profile, worlds, args.workers, args.base)
    if args.check:
        same = bool(np.array_equal(won["ghosts"], won[NEITHER]))
        print(f"{NEITHER!r} won exactly the worlds ghosts won: {same}")
        if not same:
            raise SystemExit("the identity map with neither rule is not exp_moving_doubt_memory.py's ghosts")


if __name__ == "__main__":
    main()
