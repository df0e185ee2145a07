"""Experiment: why the moving disc planner's map drops walkers half a metre off; what of ``S`` ghosts hold.

Run: ``python benchmarks/exp_moving_drift.py [--profile full] [--worlds 1000] [--start 1000] [--workers 2]
[--episodes 1000 --variants S:all S:first S:tracked S:hidden S:shown ghost:told ghost:exact
ghost:exact+own ghost:exact+own+all] [--base B.npz]`` (the disc planner needs its networks: ``python -m
husky_course train discs``; ``--base``: the planner's own episodes kept for the next run, as
``exp_moving_variants.py`` keeps them).

Why: ``exp_moving_lost.py`` found that most cylinders the disc planner's map drops are walkers whose
remembered disc, when the column through its centre saw through it, lay half a metre or more from the
cylinder, and that given back exactly (``exp_moving_memory.py``'s rule ``S``) they are worth about a point;
yet ``exp_moving_doubt_memory.py``'s ghosts of those discs were worth nothing, even told which of their walks
is nearest the truth (``told``). A disc is placed once, by the image that makes it, and then walks at the
speed read in that image, so its error when dropped is its error at birth plus its speed's error times the
steps since.

1. **Drift** (``--worlds``). Along the planner's runs (told nothing: it decides as the planner does) on
   ``--worlds`` tuning worlds from ``--start`` (evaluation set 1), every disc on a walking cylinder carries,
   from the image that made it (privileged: the simulator's truth then): its place's lateral error, its
   speed's error (the disc's speed less the cylinder's), and what its speed was read from: a *first sight*
   (the arrivals rule, or standing), or a track of 2, 3 or 4 looks read *standing* (speed 0), the *wrong
   way*, off by more than 0.1 m per step, or within 0.1; whether the cylinder turned at a side wall in the
   three steps before, and whether the piece had a nearer surface beside either end (*partly hidden*: a
   column over 0.1 m nearer). Printed: for every walker's disc a later image drops at its centre column
   (within 4 m, no new disc on its cylinder: ``exp_moving_lost.py``'s drops), by the speed's reading, how
   many, the median steps since birth, the median lateral error at the drop and at birth, the median of the
   speed's error times the steps, how many the image does not show (hidden or out of view), and the share
   of the remembered walkers' discs read so (each at least one step old, within 4 m, once per decision)
   that end in such a drop. Then the tracked discs' large speed errors by looks, turn and partly hidden view.
2. **Episodes** (``--episodes``), each beside the planner as it is on the same tuning worlds (success, the
   worlds won only with / only without, exact sign test): ``S:PART``, rule ``S`` given for only some drops
   (:data:`PARTS`: all; the drops of first sights' discs, or of tracked ones; the drops the image does not
   show, or does); ``ghost:VARIANT`` (:data:`GHOSTS`), ``told`` ghosts told more: each ghost of a cylinder
   put at its true place and speed in every draw (``exact``), ended only by a new disc on its own cylinder
   (``own``), and made for every drop rule ``S`` gives back, a new disc landing on the dropped one or not
   (``all``).

Measured (full profile): see :data:`MEASURED`.
"""

from __future__ import annotations

import argparse
from collections import defaultdict
from pathlib import Path

import exp_moving_doubt_memory as doubt
import exp_moving_lost as lost
import exp_moving_memory as memory
import exp_moving_variants as variants
import numpy as np

from husky_course.config import Profile, get_profile, with_world
from husky_course.engines import map_tasks
from husky_course.evaluation.episodes import eval_world_seeds, run_episode
from husky_course.planners.reference import truth_in_frame
from husky_course.sim.fast import FastSimulator

MEASURED = """
Full profile, library fingerprint ``199de8c9e356d225``; ``--worlds 1000`` from ``--start 1000`` and from
``--start 7000`` (about 5 minutes each on 2 cores). The walkers' drops, by the speed their disc was born with:

==============  ===================  ==============================  ====================
speed at birth  drops, 1,000-1,999   drops (not shown), 7,000-7,999  dropped per decision
==============  ===================  ==============================  ====================
first sight     328                  319 (241)                       0.027 / 0.026
read standing   16                   29 (19)                         0.011 / 0.021
wrong way       9                    12 (11)                         0.014 / 0.020
off by > 0.1    19                   17 (9)                          0.013 / 0.013
within 0.1      71                   60 (21)                         0.004 / 0.003
all             443 (311 not shown)  437 (301)                       0.013 / 0.013
==============  ===================  ==============================  ====================

Medians, all drops (both slices alike): dropped 1 step after the disc was made (339 of 437 by the very next
image), 0.48 / 0.45 m off, of which 0.05 / 0.04 m at birth and 0.47 / 0.44 m its speed's error times the
steps; first sights 0.54 / 0.50 m off, 0.05 / 0.04 m at birth. So three drops in four are first sights,
placed to a few centimetres by the image that saw them once, that walked out of sight before the next image
(which sees through where they stood): their half metre is one step of an unknown walk, not a track's wrong
speed. Discs whose track read the speed within 0.1 m per step are dropped about an eighth as often per
decision as first sights, and when they are they are where the cylinder is (0.03 m): the image shows it,
as a wall or joined to a neighbour (39 of 60). A turn at a wall while remembered: 43 / 35 drops.

Tracked walkers' discs at birth (12,739 / 12,457), the share off by more than 0.1 m per step (read standing,
wrong way): 2 looks 0.253 / 0.243 (0.122 / 0.116 standing), 3 looks 0.064 / 0.059, 4 looks 0.029 / 0.026;
turned at a wall in the last three steps 0.540 / 0.524, no turn 0.123 / 0.114; partly hidden 0.277 / 0.267,
in full view 0.115 / 0.109. Two-look tracks (47% of tracked walkers' discs) carry most large errors.

Episodes, tuning worlds 7,000-7,999 (the planner as it is 0.838), won only with / only without: rule ``S``
itself (``exp_moving_variants.py``'s ``memory:S``, the planner ``S:all`` builds) 0.848 (14 / 4, p = 0.031; on
8,000-8,999 0.870 against 0.862, 12 / 4: together 26 / 8, p = 0.003); ``S:first`` 0.841 (7 / 4);
``S:tracked`` 0.844 (6 / 0); ``S:hidden`` 0.842 (7 / 3); ``S:shown`` 0.844 (6 / 0). Rule ``S`` is a point
made of small parts, each half a point or less, none established alone by 1,000 worlds. A part meant to give
each cylinder back only while its dropped disc was at most four steps old (a ghost's life) crossed 0.848
(14 / 4) and was withdrawn: the disc rule ``S`` appends stays in the map until an image drops it, so the part
limited nothing. That the gain lies within a ghost's life shows instead in ``exact+own+all`` below (ghosts
live ``GHOST_AGE`` = 4 steps from their disc's birth).

Why ``exp_moving_doubt_memory.py``'s ``told`` ghosts held none of it, on the same worlds (``--variants
ghost:...``, about 4.5 minutes each): ``told`` 0.836 (1 / 3, as that script measured); ``real`` (no ghost of a
disc on no cylinder: 30 of 73 ghost-decisions on worlds 7,000-7,039 were of such phantoms) 0.837 (1 / 2);
``exact`` (every ghost of a cylinder at its true place and speed) 0.838 (2 / 2); ``exact+own`` (ended only by
a new disc on its own cylinder) 0.842 (6 / 2), with ``real`` too the same 0.842 (6 / 2); ``exact+own+all``
(made for every drop ``S`` gives back, a new disc landing on the dropped one or not) 0.848 (12 / 2): all of
``S``. On 8,000-8,999 (as it is 0.862, ``S`` 0.870): ``exact+own`` 0.870 (11 / 3), ``exact+own+all`` 0.871 (14
/ 5); the two slices together 17 / 5 and 26 / 7 (``S`` 26 / 8). So the ghosts' place was never what they
lacked (told ghosts already stood a median 5 cm from their cylinder on worlds 1,000-1,014), nor did their
phantoms cost: what they lacked was *identity*. A ghost ends when any new disc overlaps one of its walks, and
none is made where a new disc lands on the dropped one; told which new disc is its own cylinder's
(privileged), ending and making ghosts by that alone gives all of ``S``. Where the two rules part, the new
disc was another cylinder's (a neighbour, or a piece read as joined), and the dropped cylinder was forgotten
while still there. What rule ``S`` gives is which new disc is which cylinder: data association, not a sharper
belief over where it walked. ``own+all`` (identity as ``exact+own+all``, each ghost at ``told``'s open walk
nearest its cylinder rather than at its true place and speed, added afterwards): 0.844 (10 / 4) and 0.866
(9 / 5), together 19 / 9 against ``exact+own+all``'s 26 / 7: whether the place counts once identity is
known, these slices cannot tell. ``exp_moving_identity.py`` gives the ghosts identity from the camera
alone (the tracks).
"""
READINGS = ("first sight", "read standing", "wrong way", "off > 0.1", "within 0.1")  #: a speed at birth
#: per disc, from its birth: time, lateral error, speed error, reading, looks, turned, partly hidden, speed
BORN = ("time", "error", "speed_error", "reading", "looks", "turned", "partial", "speed")
OFF = 0.1  #: m per step: a large speed error
#: :func:`split`'s parts of rule ``S``: all; the drops the image does not show (hidden or out of view) or
#: does; of first sights' discs or of tracked ones
PARTS = ("all", "hidden", "shown", "first", "tracked")
#: :func:`ghost`'s variants
GHOSTS = ("told", "real", "exact", "exact+own", "exact+own+all", "exact+own+real", "exact+own+all+real",
          "own+all")


def reading(speed: float, true: float, first: bool) -> int:
    """The index in :data:`READINGS` of a walker's speed ``speed`` read at birth (its truth ``true``)."""
    if first:
        return 0
    if speed == 0.0:
        return 1
    if np.sign(speed) != np.sign(true):
        return 2
    return 3 if abs(speed - true) > OFF else 4


class DriftMap(lost.DropMap):
    """The disc planner's map, told nothing, that keeps each disc's birth (:data:`BORN`, privileged) and
    records every centre-column drop of a walker's disc (``drift``) and every remembered walker's disc
    (``remembered``, once per decision)."""

    born: np.ndarray  #: (discs, len(BORN)), aligned with ``ids``
    drift: list
    remembered: list
    births: list  #: every walker's disc's :data:`BORN` row

    def reset(self) -> None:
        super().reset()
        self.born = np.zeros((0, len(BORN)))
        for name in ("drift", "remembered", "births"):  # kept across episodes (:func:`runs`)
            if not hasattr(self, name):
                setattr(self, name, [])

    def decode(self, d: np.ndarray, cols: np.ndarray, pts: np.ndarray, pieces: list[np.ndarray]):
        out = super().decode(d, cols, pts, pieces)
        self._depth = (d, cols, pts)
        return out

    def _merge(self, obs: np.ndarray, d: np.ndarray, new: np.ndarray, other: np.ndarray) -> np.ndarray:
        seen, _ = self.forgotten(d, new)
        assert self.eyes.world is not None
        cyl, vy = truth_in_frame(self.eyes.world, self.pose, self.time)
        taken = set()
        if len(new):
            gap = np.hypot(new[:, :1] - cyl[:, 0], new[:, 1:2] - cyl[:, 1]) - cyl[:, 2]
            taken = set(gap.argmin(1)[gap.min(1) < lost.ON_CYLINDER].tolist())
        for k in np.flatnonzero(self.ids >= 0):
            i, b = int(self.ids[k]), self.born[k]
            if not np.isfinite(b[0]) or cyl[i, 0] - cyl[i, 2] >= lost.NEAR or self.time - b[0] < 1:
                continue
            drop = bool(seen[k]) and i not in taken
            self.remembered.append((int(b[3]), drop))
            if drop:
                turned = self._turned(i, b[0], self.time)
                self.drift.append((self._why(i, cyl)[0], int(b[3]), self.time - b[0],
                                   float(self.discs[k, 1] - cyl[i, 1]), float(b[1]), float(b[2]),
                                   turned != bool(np.sign(self.speeds[k]) != np.sign(b[7]))))
        return memory.RememberingMap._merge(self, obs, d, new, other)

    def _turned(self, i: int, start: float, end: float) -> bool:
        """Whether cylinder ``i``'s lateral walk changed direction between times ``start`` and ``end``."""
        assert self.eyes.world is not None
        y = [self.eyes.world.obstacles_at(float(t))[i, 1] for t in np.arange(start, end + 1.5)]
        v = np.sign(np.diff(y))
        return bool((v[v != 0][1:] != v[v != 0][:-1]).any())

    def add(self, obs: np.ndarray) -> None:
        old = self.born
        super().add(obs)
        cols, pieces, _, cylinder = self._image
        born = int(cylinder.sum())  # this image's discs come first; rule ``S`` appends its own after the kept
        given = len(self.discs) - born - int(self.kept.sum())
        new = np.full((born, len(BORN)), np.nan)
        assert self.eyes.world is not None
        cyl, vy = truth_in_frame(self.eyes.world, self.pose, self.time)
        d, _, pts = self._depth
        tracks = self.motion.tracks.tracks
        small = [k for k, idx in enumerate(pieces) if np.ptp(pts[idx], axis=0).max() <= 1.0]
        for j, p in enumerate(np.flatnonzero(cylinder)):
            i = int(self.ids[j])
            if i < 0 or vy[i] == 0:
                continue
            first = bool(self.fresh[j])
            looks = len(tracks[small.index(p)]) if p in small and not first else 1
            c = np.sort(np.unique(cols[pieces[p]]))
            lo, hi = int(c[0]), int(c[-1])
            partial = (lo > 0 and d[lo - 1] < d[lo] - 0.1) or (hi + 1 < len(d) and d[hi + 1] < d[hi] - 0.1)
            turned = self._turned(i, max(self.time - 3.0, 0.0), self.time)
            new[j] = (self.time, self.discs[j, 1] - cyl[i, 1], self.speeds[j] - vy[i],
                      reading(float(self.speeds[j]), float(vy[i]), first), looks, turned, partial,
                      self.speeds[j])
        self.born = np.r_[new, old[self.kept], np.full((given, len(BORN)), np.nan)]
        self.births.extend(new[np.isfinite(new[:, 0])].tolist())

    def move(self, dx: float, dy: float) -> np.ndarray:
        kept = super().move(dx, dy)
        self.born = self.born[kept]
        return kept


class PartMap(DriftMap):
    """Rule ``S`` of ``exp_moving_memory.py`` (privileged) for only the drops :attr:`part` names
    (:data:`PARTS`): every other drop is marked lost another way (``X``), so it is not given back."""

    part: str

    def _merge(self, obs: np.ndarray, d: np.ndarray, new: np.ndarray, other: np.ndarray) -> np.ndarray:
        seen, _ = self.forgotten(d, new)
        assert self.eyes.world is not None
        cyl = truth_in_frame(self.eyes.world, self.pose, self.time)[0]
        how = {}
        for k in np.flatnonzero(seen & (self.ids >= 0)):
            i = int(self.ids[k])
            unseen = self._why(i, cyl)[0] in ("hidden", "out of view")
            how[i] = {"hidden": unseen, "shown": not unseen, "first": bool(self.fresh[k]),
                      "tracked": not self.fresh[k]}[self.part]
        kept = super()._merge(obs, d, new, other)
        for i, given in how.items():
            if self.lost.get(i) == "S" and not given:
                self.lost[i] = "X"
        return kept


class ExactGhostMap(doubt.DoubtingMap):
    """``exp_moving_doubt_memory.py``'s ``told`` ghosts, told more (privileged, :data:`GHOSTS`): ``exact``
    puts each ghost of a cylinder, in every draw, at that cylinder's true place and speed (not its open walk
    nearest it); ``own`` ends such a ghost only when a new disc lands on its own cylinder (not on any of its
    walks, and not when an image has seen through every walk) or it ages out; ``all`` (with ``own``) makes
    a ghost of every disc an image sees through or again, a new disc landing on it or not, as rule ``S``
    gives back every cylinder so dropped that no disc holds; ``real`` makes no ghost of a disc that lay on
    no cylinder (rule ``S`` gives back only cylinders; ``real`` alone: ``told``'s ghosts, but those)."""

    exact: frozenset[str]

    def _slots(self) -> tuple[np.ndarray, np.ndarray]:
        points, v = super()._slots()
        if self.draw is not None and "exact" in self.exact:
            for n, g in enumerate(self.ghosts):
                if g["id"] >= 0:
                    points[n], v[n] = self.truth[0][g["id"]], self.truth[1][g["id"]] or doubt.TINY
        return points, v

    def _merge(self, obs: np.ndarray, d: np.ndarray, new: np.ndarray, other: np.ndarray) -> np.ndarray:
        if "own" not in self.exact:  # (``all`` comes with ``own``: :data:`GHOSTS`)
            out = super()._merge(obs, d, new, other)
            if "real" in self.exact:
                self.ghosts = [g for g in self.ghosts if g["id"] >= 0]
            return out
        own = memory.belonging(new, self.truth[0]) if len(new) else np.zeros(0, int)

        def kept(g: dict) -> bool:
            if g["id"] < 0 and "real" in self.exact:
                return False
            if g["id"] >= 0:
                g["open"] |= ~g["open"].any()  # its walks stay drawable (``exact`` places it anyway)
                return g["id"] not in own
            return bool(g["open"].any()) and not doubt.found(g, new)

        for g in self.ghosts:
            g["open"] &= ~self.seen_through(g, d)
        self.ghosts = [g for g in self.ghosts if kept(g)]
        seen, landed = self.forgotten(d, new)
        made = seen if "all" in self.exact else seen & ~landed  # ``all``: a new disc landed on it too
        for k in np.flatnonzero(made):
            g = self.ghost(k, d)
            if g["life"] <= doubt.GHOST_AGE and kept(g):
                self.ghosts.append(g)
        out = super(doubt.DoubtingMap, self)._merge(obs, d, new, other)
        self.ids = np.r_[own, self.ids[out]]
        return out


def ghost(profile: Profile, variant: str):
    """The disc planner with ``told`` ghosts (``exp_moving_doubt_memory.py``), told more as ``variant`` says
    (:data:`GHOSTS`, :class:`ExactGhostMap`)."""
    if variant not in GHOSTS:
        raise SystemExit(f"a ghost variant is one of {', '.join(GHOSTS)}; got {variant!r}")
    planner = doubt.doubting_planner(profile, "told")
    if variant != "told":
        planner.map.__class__ = ExactGhostMap
        planner.map.exact = frozenset(variant.split("+"))  # type: ignore[attr-defined]
    return planner


def build(profile: Profile, name: str):
    """``S:PART`` (:func:`split`) or ``ghost:VARIANT`` (:func:`ghost`)."""
    kind, _, variant = name.partition(":")
    if kind not in ("S", "ghost"):
        raise SystemExit(f"a variant is S:PART or ghost:VARIANT; got {name!r}")
    return split(profile, variant) if kind == "S" else ghost(profile, variant)


def split(profile: Profile, part: str) -> memory.MemoryToldPlanner:
    """The disc planner whose map is told rule ``S`` for the drops ``part`` names (:class:`PartMap`;
    ``all``: rule ``S`` itself)."""
    if part not in PARTS:
        raise SystemExit(f"a part is one of {', '.join(PARTS)}; got {part!r}")
    planner = memory.MemoryToldPlanner(profile, "S")
    if part != "all":
        planner.map.__class__ = PartMap
        planner.map.part = part  # type: ignore[attr-defined]
    planner.name = f"discs, told S for {part} drops (privileged)"
    return planner


def runs(args: tuple[Profile, list[int]]) -> tuple[list, list, list]:
    """The drops, remembered discs and births of walkers' discs along the planner's runs on ``seeds``."""
    profile, seeds = args
    planner = memory.MemoryToldPlanner(profile, "")  # told nothing: it decides as the planner does
    planner.map.__class__ = DriftMap
    sim, m = FastSimulator(profile.sim), planner.map
    for seed in seeds:
        run_episode(planner, sim, seed, profile.sim.max_primitives)
    return m.drift, m.remembered, m.births  # type: ignore[attr-defined]


def report(drift: list, held: list, births: list, first: int, n: int, profile: str) -> None:
    """Print the tables (module docstring)."""
    print(f"walkers' discs dropped at their centre column on moving tuning worlds {first}-{first + n - 1} "
          f"(evaluation set 1, {profile} profile): {len(drift)}")
    print(f"  {'speed read at birth':16s} {'drops':>6s} {'steps':>6s} {'error now':>10s} {'at birth':>9s} "
          f"{'speed x steps':>14s} {'not shown':>10s} {'dropped / held':>15s}")
    counts: dict[int, list[int]] = defaultdict(lambda: [0, 0])
    for r, drop in held:
        counts[r][0] += drop
        counts[r][1] += 1
    rows = [("all", drift, sum(c[0] for c in counts.values()), sum(c[1] for c in counts.values()))]
    rows += [(name, [f for f in drift if f[1] == r], *counts[r]) for r, name in enumerate(READINGS)]
    for name, part, drops, total in rows:
        if not part:
            print(f"  {name:16s} {0:6d}")
            continue
        steps, now, birth, speed = (np.array([f[k] for f in part], float) for k in (2, 3, 4, 5))
        share = f"{drops / total:.3f} of {total}" if total else "-"
        unseen = sum(f[0] in ("hidden", "out of view") for f in part)
        print(f"  {name:16s} {len(part):6d} {np.median(steps):6.1f} {np.median(np.abs(now)):9.2f}m "
              f"{np.median(np.abs(birth)):8.2f}m {np.median(np.abs(speed * steps)):13.2f}m {unseen:10d} "
              f"{share:>15s}")
    turns = sum(f[6] for f in drift)
    print(f"  a turn at a wall the disc's walk missed (or made) while remembered: {turns}; "
          f"dropped by the first image after their birth: {sum(f[2] == 1 for f in drift)}")
    b = np.array(births, float).reshape(-1, len(BORN))
    tracked = b[b[:, 3] > 0]
    print(f"tracked walkers' discs at birth: {len(tracked)}; off by more than {OFF} m per step (read "
          f"standing or the wrong way included), by what the track read:")
    for label, mask in [("2 looks", tracked[:, 4] == 2), ("3 looks", tracked[:, 4] == 3),
                        ("4 looks", tracked[:, 4] >= 4), ("turned at a wall", tracked[:, 5] == 1),
                        ("no turn", tracked[:, 5] == 0), ("partly hidden", tracked[:, 6] == 1),
                        ("in full view", tracked[:, 6] == 0)]:
        part = tracked[mask]
        big = np.abs(part[:, 2]) > OFF
        if len(part):
            print(f"  {label:18s} {len(part):6d} discs, {big.mean():.3f} off (read standing "
                  f"{(part[:, 3] == 1).mean():.3f}, wrong way {(part[:, 3] == 2).mean():.3f})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=1000)
    parser.add_argument("--start", type=int, default=1000, help="the first tuning world (evaluation set 1)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--episodes", type=int, default=0, help="tuning worlds per variant (0: none)")
    parser.add_argument("--variants", nargs="+", default=[f"S:{p}" for p in PARTS],
                        help=f"S:PART (PART one of {', '.join(PARTS)}) or ghost:VARIANT (one of "
                             f"{', '.join(GHOSTS)})")
    parser.add_argument("--base", type=Path, help=variants.BASE_HELP)
    args = parser.parse_args()
    if args.worlds < 0 or args.episodes < 0 or not args.worlds + args.episodes:
        raise SystemExit(f"--worlds and --episodes must be 0 or more, one of them positive; got "
                         f"{args.worlds} and {args.episodes}")
    profile = with_world(get_profile(args.profile), "moving")
    for name in args.variants:
        build(profile, name)  # a bad name fails before any world runs
    if args.worlds:
        seeds = [int(s) for s in eval_world_seeds(args.start + args.worlds, 1)[args.start:]]
        parts = map_tasks(runs, [(profile, seeds[i : i + 10]) for i in range(0, len(seeds), 10)],
                          workers=args.workers, desc="drift", unit="10 worlds")
        report([f for p in parts for f in p[0]], [h for p in parts for h in p[1]],
               [b for p in parts for b in p[2]], args.start, args.worlds, profile.name)
    if args.episodes:
        worlds = variants.tuning_worlds(args.start, args.episodes, profile.name)
        variants.paired_episodes(build, args.variants, profile, worlds, args.workers, args.base)


if __name__ == "__main__":
    main()
