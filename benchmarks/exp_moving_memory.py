"""Experiment: what the moving disc planner's memory of seen cylinders costs, priced from the same states.

Run: ``python benchmarks/exp_moving_memory.py [--profile full] [--worlds 1000] [--start 0] [--workers 2]
[--rules l S N L ml mdl mndl] [--check] [--save F.npz] [--episodes 1000 --episodes-start 1000 [--base
B.npz]]`` (the disc planner needs its network: ``python -m husky_course train discs``).

``exp_moving_paired.py`` judges variants of the disc planner as shadows of the planner as it is, at
the same states. Told every cylinder an image has rendered so far, exactly, a shadow made 55 fatal
choices where the planner made 151 (worlds 0-999 of the tuning set, full profile); told every disc's
true motion, 107. Here the difference is split by what the map does with what it has seen. Each
shadow is the disc planner whose map is told the truth (privileged, an analysis tool) as its *rule*
says, a string of letters:

* ``m``: every disc's true lateral velocity (the ``told-discs`` reference's second rule; its tracked
  walkers' speeds are not drawn);
* ``t``: only the tracked discs' true lateral velocity (those that are not first sights: a track with two
  looks or more), what a perfect reader of tracked speeds would give (``exp_moving_speed_reader.py``);
* ``n``: the discs the current image makes, each put on the cylinder it belongs to, exactly;
* ``d``: the remembered discs (made by earlier images), each put back on its cylinder;
* ``e``: every disc the image makes put exactly on the cylinder nearest it (within ``ON_CYLINDER``) as the
  image is read, *before* the tracks read its place: the tracks see exact places and radii (what a
  perfect disc network would give them); unlike ``n``, this changes what the tracks read of motion;
* ``l``: every cylinder an image has rendered that no disc belongs to (and not further behind than the
  map forgets), added exactly with its true velocity; or only those lost one way: ``S`` the disc the
  map held on it was dropped because the column through its centre saw it again or through it, ``L``
  a new disc landed on it, ``B`` it fell behind the map's memory, ``N`` no disc ever belonged to it
  (its pieces read as a wall, or as a neighbour's);
* ``k``: as ``l``, but each cylinder given back walks at the speed the map last held for it (its disc's when
  that was dropped; 0 for one no disc ever belonged to), not its true velocity: the memory without the motion;
* ``f``: discs on no cylinder dropped;
* ``c``: every piece cut again where the true surface its columns hit changes, each part then read by
  the network as a piece of its own (a perfect cut); ``j``: only where one cylinder's columns meet
  another's (two cylinders joined into one piece).

With ``--episodes N`` each rule then runs as a planner on ``N`` tuning worlds from ``--episodes-start``
(evaluation set 1; ``--worlds 0``: episodes only), beside the planner as it is on the same worlds
(success with its exact interval; the worlds won only with the rule / only without it, with an exact sign
test; ``--check`` adds the rule that tells nothing, which must win exactly the planner's worlds;
``--base B.npz`` keeps the planner's own episodes for the next run: ``exp_moving_variants.py``, which also
runs these rules beside the other experiments' variants).

A disc *belongs* to the cylinder whose surface lies nearest its centre (within ``ON_CYLINDER``) when
the image that made it was taken, and keeps that identity as the map carries it: the truth is read
once, at the disc's birth, not again when it drifts. The empty rule tells nothing: that shadow must
agree with the driver at every decision (``--check``).

Measured (full profile, worlds 0-999 of the tuning set, 8,879 winnable decisions, 151 fatal choices of
the driver, which crossed 0.828; all thirteen rules in one run of 26 minutes on 2 cores;
``only rule`` / ``only driver``: the decisions where only that one's choice was fatal):

======================================================  =====  =========  ===========  =======
rule                                                    fatal  only rule  only driver  p
======================================================  =====  =========  ===========  =======
``l``: every lost cylinder given back                     120          5           36  < 0.001
``S``: ... only those dropped at their centre column      139          2           14    0.004
``N``: ... only those no disc ever belonged to            145          6           12    0.238
``L``: ... only those a new disc landed on                149          0            2    0.500
``m``: every disc's motion (identity speeds)              106         32           77  < 0.001
``md``: and the remembered discs on their cylinders       103         30           78  < 0.001
``mn``: and this image's discs on theirs                   99         32           84  < 0.001
``mf``: and discs on no cylinder dropped                  106         32           77  < 0.001
``ml``: and every lost cylinder given back                 69         19          101  < 0.001
``mS``: and those dropped at their centre column           83         20           88  < 0.001
``mN``: and those no disc ever belonged to                 101         31           81  < 0.001
``mdl``: remembered discs placed, lost given back          65         17          103  < 0.001
``mndlf`` (the told reference's third rule, rebuilt)       55         14          110  < 0.001
``c``: pieces cut where the true surface changes          125         22           48    0.003
``j``: ... only where two cylinders meet                  126         18           43    0.002
``mc``: and every disc's motion                            79         28          100  < 0.001
``mj``                                                     79         27           99  < 0.001
======================================================  =====  =========  ===========  =======

The table is the planner's before it carried the cut network (``planners/cuts.py``). Priced again with
it (worlds 0-499, 4,523 winnable decisions, 70 fatal choices of the driver, 405 s): ``j`` 68 (12 / 14,
p = 0.85: a perfect cut adds nothing that can be shown), ``m`` 44 (12 / 38, p < 0.001), ``l`` 57
(1 / 14, p = 0.001). The lost by kind, the same worlds and planner (644 s): ``S`` 61 (0 / 9, p = 0.004),
``N`` 68 (2 / 4), ``L`` 70 (0 / 0), ``B`` 70 (0 / 0): most are still discs dropped at their centre column.
(Both runs were before the planner broke its draws' ties by their clearance, ``ArrivalsConfig.ties``.)
With those ties (worlds 0-499, 4,531 winnable decisions, 65 fatal choices of the driver, which crossed
0.856; ``--rules m l S N ml``, 575 s): ``m`` 43 (13 / 35, p = 0.002), ``l`` 57 (1 / 9, p = 0.02), ``S`` 62
(1 / 4), ``N`` 61 (0 / 4), ``ml`` 31 (7 / 41, p < 0.001). Every disc's motion is still the largest single
share: a third of the fatal choices.
The tracked discs' share of it, the planner as it is now (with the faster space-time check, the same
decisions; worlds 0-499, 4,527 winnable decisions, 66 fatal choices of the driver, which crossed 0.854;
``--rules t m``, 347 s): ``t`` 52 (6 / 20, p = 0.009), ``m`` 42 (12 / 36, p < 0.001). Perfect speeds
for the discs seen twice or more would remove 14 of the 66; the first sights' take 10 more.

Of the 51 fatal choices that exact seen cylinders remove beyond every disc's motion (106 to 55), the
lost cylinders account for 37 (106 to 69); the remembered discs' drift off their cylinders for 3
(106 to 103), this image's discs' own errors for 7. (A prototype of this script, on the same worlds, gave the
same figures, and ``mL`` 104, ``mB`` 106.) Without any motion told, the lost cylinders given
back remove 31 of 151. Of the lost, those dropped at their centre column are the largest single kind
(12 without motion, 23 with). Counted along the planner's runs on 200 tuning worlds (a throwaway
count), 246 cylinders were lost that way: in 77% the column through the cylinder's true centre saw it
again, in 54% a new disc lay within 0.3 m of its surface but nearer another cylinder, and 49% were
walkers. Four of the decisions that giving them back saves, replayed by hand, show the same thing: a
cylinder beside or partly behind a nearer one, its remembered disc dropped because its centre column
reached its front (or an occluder within 5 cm of it), and the new image's piece joining the two
cylinders, so that its one disc covers one of them. Rules that keep such a disc, or cut such a piece
again, were tried through ``exp_moving_paired.py``'s ``variant_planner``; none made measurably fewer
fatal choices; nor did finer cuts of every piece (the figures are in comments in ``DiscMap.forgotten``
and ``PieceReader.pieces``).

A perfect cut of the pieces that join two cylinders (``j``, a separate run of 14 minutes on the same
worlds, with ``c``, ``mc``, ``mj`` and ``m``, which made the same 106 as above) removes 25 of the 151
fatal choices, more than giving back every lost cylinder (31 with the lost cylinders of every other
kind), and 27 of 106 with every disc's motion told: a cut, read by the network as it is, is worth as
much as the memory itself. In random views of training worlds, 7% of the pieces that hit a cylinder
join two (577 of 8,086), and the depth step where they meet is no larger than within one cylinder's
arc at the same range (median 0.14 m against 0.07 m, overlapping widely): the cut the tracker uses
(gaps of 0.3 m, arcs' peaks) cannot find them. The disc planner's cut network
(:mod:`husky_course.planners.cuts`) learns that cut; its prototypes and its measurements are there. All
the figures above were measured before it: its learned cuts now come on top of a rule's (``c``, ``j``).

As episodes, the planner as it is now (full profile, ``--worlds 0 --episodes 1000 --episodes-start S``, about
5 minutes per rule and slice on 2 cores; won only with the rule / only without it):

=========================================  ===============  ===============  ===============
rule                                       1,000-1,999      2,000-2,999      3,000-3,999
=========================================  ===============  ===============  ===============
(as it is)                                 0.846            0.875            0.840
``e``: exact places before the tracks      0.859 (47 / 34)  0.877 (37 / 35)  0.855 (56 / 41)
``n``: exact places after the tracks       0.840 (31 / 37)
``et``: and the tracked discs' motion      0.873 (56 / 29)
``k``: lost cylinders back, own speeds     0.854 (16 / 8)                    0.849 (19 / 10)
``l``: lost cylinders back, true speeds    0.868 (39 / 17)                   0.867 (41 / 14)
``el``                                     0.881 (59 / 24)                   0.885 (78 / 33)
``ek``                                     0.868 (52 / 30)
=========================================  ===============  ===============  ===============

``k`` everywhere and, on 1,000-1,999, ``e``, ``l``, ``el`` and ``ek`` come from throwaway drivers of this
script's planners (:class:`MemoryToldPlanner`, the base figure reproduced to the last world), the rest from
the script itself; ``e`` on 3,000-3,999 printed the same figures through both. Exact places are worth 0.2 to
1.5 points (pooled 140 / 110, p = 0.07), all of it through what the tracks read of motion: the same places
put in after the tracks have read them (``n``) gain nothing. A better network would find little to give
there: along the planner's runs (a throwaway count on tuning worlds 4,000-4,149, 13,957 cylinder discs) its
centres are off by 0.021 m at the median, 0.009 m for a cylinder seen whole within 3 m and 0.038 m beyond
(one of the 50 columns spans 0.14 m at 3 m, 0.18 m at 4 m), 0.059 m where a nearer surface hides part of it;
laterally more than 0.1 m off at 5.8% of the discs, 0.5% of the whole ones within 3 m, 14.7% of the partly
hidden ones. The lost cylinders given back are worth two to three points, but given back walking at the
speed the map last held for them (``k``) only 0.8 and 0.9 (on 1,000-1,999 ``l`` against ``k``: 29 / 15, p =
0.049; with exact places, ``ek`` 0.868 against ``el`` 0.881): what the memory misses is mostly where its
hidden walkers have walked, a motion error again. With both told (``el``) the planner crosses above 0.873,
the goal's figure on the reporting set, on both slices; neither half is within a camera's reach as it is
told here.
The figures above were measured before the planner broke the last ties by its draws' options
(``ArrivalsConfig.ties`` "options"); the script runs the planner as it is now.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import exp_moving_paired as paired
import exp_moving_variants as variants
import numpy as np

from husky_course.config import Profile, get_profile, with_world
from husky_course.planners.base import EpisodeStart, Planner
from husky_course.planners.moving_discs import WalkingDiscMap
from husky_course.planners.reference import ON_CYLINDER, TOLD_RULES, ToldDiscsPlanner, truth_in_frame
from husky_course.sim.fast import FastSimulator

LETTERS = "mtndelkSLNBfcj"  #: the rules' letters (module docstring)
LOST_WAYS = "SLNB"  #: how a cylinder was lost: ``l`` gives back every one, these only their kind


def belonging(discs: np.ndarray, cylinders: np.ndarray) -> np.ndarray:
    """Per disc of ``discs (k, 3+)``: the index of the cylinder of ``cylinders (n, 3)`` whose surface lies
    nearest its centre, or -1 when that is ``ON_CYLINDER`` or further."""
    gap = np.hypot(discs[:, :1] - cylinders[:, 0], discs[:, 1:2] - cylinders[:, 1]) - cylinders[:, 2]
    j = np.argmin(gap, axis=1)
    return np.where(gap[np.arange(len(j)), j] < ON_CYLINDER, j, -1)


class RememberingMap(WalkingDiscMap):
    """A walking disc map that knows which cylinder each disc belongs to, and how each seen cylinder
    it no longer holds was lost; told the truth as ``rule`` says (module docstring). Privileged."""

    rule: str
    eyes: FastSimulator
    pose: np.ndarray
    time: float
    seen: np.ndarray  #: the cylinders any image so far (this one included) has rendered
    ids: np.ndarray  #: per disc: the cylinder it belongs to (-1: none)
    lost: dict  #: cylinder -> how its last disc was dropped (``S``, ``L`` or ``B``)
    held: dict  #: cylinder -> the speed its last disc had when it was dropped (rule ``k``)

    def decode(self, d: np.ndarray, cols: np.ndarray, pts: np.ndarray,
               pieces: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        discs, cyl, other = super().decode(d, cols, pts, pieces)
        if "e" in self.rule and cyl.any():  # before the tracks read the discs' places
            assert self.eyes.world is not None
            true = truth_in_frame(self.eyes.world, self.pose, self.time)[0]
            j = belonging(discs, true)
            on = cyl & (j >= 0)
            discs = discs.copy()
            discs[on] = true[j[on]]
        return discs, cyl, other

    def _merge(self, obs: np.ndarray, d: np.ndarray, new: np.ndarray, other: np.ndarray) -> np.ndarray:
        seen, landed = self.forgotten(d, new)
        gone = (seen | landed) & (self.ids >= 0)
        self.held.update(zip(self.ids[gone].tolist(), self.speeds[gone].tolist(), strict=True))
        self.lost.update({int(i): "S" for i in self.ids[seen & (self.ids >= 0)]})
        self.lost.update({int(i): "L" for i in self.ids[landed & ~seen & (self.ids >= 0)]})
        self.kept = super()._merge(obs, d, new, other)
        return self.kept

    def add(self, obs: np.ndarray) -> None:
        old = self.ids
        super().add(obs)
        assert self.eyes.world is not None
        cyl, vy = truth_in_frame(self.eyes.world, self.pose, self.time)
        born = len(self.discs) - int(self.kept.sum())
        if born:
            self.ids = np.r_[belonging(self.discs[:born], cyl), old[self.kept]]
        else:
            self.ids = old[self.kept]
        on, rule = self.ids >= 0, self.rule
        if "m" in rule:
            self.speeds = np.where(on, vy[np.maximum(self.ids, 0)], self.speeds)
            self.doubt = np.zeros_like(self.doubt)
        if "t" in rule:  # the tracked discs' (not the first sights')
            self.speeds = np.where(on & ~self.fresh, vy[np.maximum(self.ids, 0)], self.speeds)
        now = np.arange(len(self.ids)) < born
        place = on & ((now & ("n" in rule)) | (~now & ("d" in rule)))
        self.discs[place] = cyl[self.ids[place]]
        if "f" in rule:
            self._keep(on)
        ways = set(rule) & set(LOST_WAYS)
        if "l" in rule or "k" in rule or ways:
            gone = np.setdiff1d(self.seen, self.ids).astype(int)
            gone = gone[cyl[gone, 0] > -self.forget_behind]
            if ways:
                gone = gone[[self.lost.get(int(i), "N") in ways for i in gone]].astype(int)
            walk = np.array([self.held.get(int(i), 0.0) for i in gone]) if "k" in rule else vy[gone]
            self.discs, self.speeds = np.r_[self.discs, cyl[gone]], np.r_[self.speeds, walk]
            self.fresh, self.ids = np.r_[self.fresh, np.zeros(len(gone), bool)], np.r_[self.ids, gone]
            self.doubt = np.r_[self.doubt, np.zeros((len(gone), self.doubt.shape[1]))]

    def _keep(self, keep: np.ndarray) -> None:
        self.discs, self.speeds, self.fresh = self.discs[keep], self.speeds[keep], self.fresh[keep]
        self.doubt, self.ids = self.doubt[keep], self.ids[keep]

    def move(self, dx: float, dy: float) -> np.ndarray:
        behind = (self.discs[:, 0] - dx <= -self.forget_behind) & (self.ids >= 0)
        self.lost.update({int(i): "B" for i in self.ids[behind]})
        kept = super().move(dx, dy)
        self.ids = self.ids[kept]
        return kept


def true_cut(m: RememberingMap, joined_only: bool):
    """``m.reader.pieces`` that cuts every piece again where the true surface its columns hit changes
    (``joined_only``: only where one cylinder's columns meet another's); privileged: ``m``'s simulator,
    the true pose and time. Each part is then read by the network as a piece of its own."""
    base = m.reader.pieces

    def pieces(obs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[np.ndarray]]:
        d, cols, pts, cut = base(obs)
        kind = m.eyes.column_hits(m.pose[None], m.time)[1][0][cols]
        out = []
        for idx in cut:
            k = kind[idx]
            change = k[1:] != k[:-1]
            if joined_only:
                change &= (k[1:] >= 2) & (k[:-1] >= 2)
            out += np.split(idx, np.flatnonzero(change) + 1)
        return d, cols, pts, out

    return pieces


class MemoryToldPlanner(ToldDiscsPlanner):
    """The moving disc planner whose map is a :class:`RememberingMap` told ``rule`` (privileged). The
    ``told-discs`` reference's machinery: the true world at the start, the true pose at each decision,
    the cylinders each image renders; built as its first rule (tracked walkers' speeds drawn as the
    disc planner draws them) or, with ``m``, its second (every speed told: none drawn)."""

    def __init__(self, profile: Profile, rule: str) -> None:
        super().__init__(profile, TOLD_RULES[1] if "m" in rule else TOLD_RULES[0], profile.sim)
        self.map.__class__ = RememberingMap
        self.map.rule = rule  # type: ignore[attr-defined]
        if "c" in rule or "j" in rule:
            self.map.reader.pieces = true_cut(self.map, joined_only="c" not in rule)  # type: ignore[arg-type]
        self.name = f"discs, memory told {rule!r} (privileged)"

    def reset(self, start: EpisodeStart) -> None:
        super().reset(start)
        self.map.ids, self.map.lost, self.map.held = np.zeros(0, int), {}, {}  # type: ignore[attr-defined]


def check_rule(rule: str) -> str:
    """``rule`` if it is made of :data:`LETTERS` (each at most once), else a clear error."""
    if set(rule) - set(LETTERS) or len(set(rule)) != len(rule):
        raise SystemExit(f"a rule is a string of distinct letters of {LETTERS!r}; got {rule!r}")
    return rule


NOTHING_TOLD = "(told nothing)"  #: the rule that tells nothing, as ``--check`` names it


def told(profile: Profile, rule: str) -> Planner:
    """The planner whose map is told ``rule`` (:class:`MemoryToldPlanner`; :data:`NOTHING_TOLD`: "")."""
    return MemoryToldPlanner(profile, "" if rule == NOTHING_TOLD else rule)


def main(argv: list[str] | None = None) -> None:
    """Run ``exp_moving_paired.py`` with :class:`MemoryToldPlanner` shadows, one per ``--rules``; with
    ``--episodes``, then each rule as a planner."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rules", nargs="+", default=["l", "S", "N", "L", "ml", "mdl", "mndl"])
    parser.add_argument("--episodes", type=int, default=0, help="worlds of episodes per rule (0: none)")
    parser.add_argument("--episodes-start", type=int, default=1000)
    parser.add_argument("--base", type=Path, help=variants.BASE_HELP)
    args, rest = parser.parse_known_args(argv)
    rules = [check_rule(r.strip()) for r in args.rules]
    known, _ = paired_options().parse_known_args(rest)
    if known.worlds > 0:  # the same states (0: episodes only)
        paired.parse_variant = check_rule
        paired.variant_planner = MemoryToldPlanner  # the workers are forked: they see the replacement
        paired.main([*rest, "--variants", *rules])
    if args.episodes > 0:
        profile = with_world(get_profile(known.profile), "moving")
        worlds = variants.tuning_worlds(args.episodes_start, args.episodes, profile.name)
        variants.paired_episodes(told, rules + ([NOTHING_TOLD] if known.check else []), profile, worlds,
                                 known.workers, args.base)


def paired_options() -> argparse.ArgumentParser:
    """The options of ``exp_moving_paired.py`` that the episodes share."""
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument("--profile", default="full")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--check", action="store_true")
    parser.add_argument("--worlds", type=int, default=1000)
    return parser


if __name__ == "__main__":
    main(sys.argv[1:])
