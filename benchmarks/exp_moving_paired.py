"""Experiment: compare variants of the moving disc planner decision by decision, from the same states.

Run: ``python benchmarks/exp_moving_paired.py [--profile full] [--worlds 1000] [--start 0]
[--workers 2] [--variants "samples=0" "margin=0.05" ...]`` (the disc planner needs its network:
``python -m husky_course train discs``).

Why: an episode's outcome is a noisy readout of a decision rule. Two rules that differ at many
decisions walk into different states, and on 1,000 worlds their success differs by about 2 points at
random (the search's own tie-break, mirrored, crossed 0.810 against 0.828 on the same worlds:
``ArrivalsConfig.samples`` records it). Here every variant is judged at the *same* states: the disc
planner as it is drives the episode (:class:`~husky_course.evaluation.rollout.Rollout`, the tuning
set, evaluation set 1), and every variant runs beside it as a *shadow*: it sees the same images and
moves its map by the driver's primitives, and at every decision says what it would have played.

At each decision from which the true world still has a way through to the end (found by the oracle's
lattice search: ``crossable``), every choice is judged in the true world: it is *fatal* when no way
through remains after it (``survives``). The driver's fatal decision ends the comparison in that world
(every later state is lost). Per variant the script prints the fatal choices the driver and the variant
make at the same winnable states, and the decisions where only one of them is fatal, with an exact
sign test over those. A variant identical to the driver (``--check``) must agree at every decision.

What this measures is a rule's choice from the driver's states (off its own path): a variant that
would have avoided the driver's states altogether is not credited for that, and a choice that keeps a
way through open but leaves the robot where the planner later fails counts as safe. It is a low-noise
screen for rules, not their success; a rule it favours is then run as a planner on pooled slices.

Measured (full profile, worlds 0-999 of the tuning set; 8,879 winnable decisions, 151 fatal choices of
the driver, which crossed 0.828; about 30 minutes on 2 cores with five to seven shadows). ``only variant`` /
``only driver``: the decisions where only that one's choice was fatal.

==========================================  =======  =====  ============  ===========  =====
variant                                     differs  fatal  only variant  only driver  p
==========================================  =======  =====  ============  ===========  =====
the search's tie-break mirrored (a control)    3,860    159            33           25  0.358
no draws (``samples=0``)                         446    175            39           15  0.001
the search's margin 0.05 m                     3,629    181            58           28  0.002
ties of the mean broken by options first       3,216    147            41           45  0.747
draws surviving the whole horizon first            3    152             1            0  1.000
the draws' lower quartile of safe steps first      7    153             3            1  0.625
horizon 6                                         78    150             0            1  1.000
64 draws                                         219    151             4            4  1.000
the search's clearance cap 0.4 m                2,904    158            13            6  0.167
``speed_sigma`` 0.1                              341    159            17            9  0.169
tracked speeds overruled by the columns        1,139    161            30           20  0.203
... only where the track reads a walk            949    161            23           13  0.132
==========================================  =======  =====  ============  ===========  =====

The two settings that episodes had shown to cost success (no draws: 0.815 against 0.826 pooled over 4,000
worlds, p = 0.001; margin 0.05: 0.799 against 0.828 on these worlds) stand out here on 1,000 worlds at
p = 0.001 and 0.002, and the mirrored tie-break, which crossed 0.810 against 0.828 as a planner on the same
worlds (63 / 81), does not (33 / 25, p = 0.36): it changes 43% of the choices and, from the same states,
almost none of their outcomes. *Options* counts, per first primitive, the end states of the horizon its
safe plans still reach in the map (a hedge against surprise); the draws' whole-horizon share and their
lower quartile rank almost exactly as their mean does (3 and 7 decisions of 8,879 differ). Better speeds
for tracked walkers (the last images' columns, ``Arrivals.evidence``, overruling a track's speed where
they decide: off by more than 0.1 m per step at 9% of walkers' sightings instead of 13%) make no fewer
fatal choices. No variant here makes fewer than the planner as it is, whose settings were chosen on these
worlds; the shadows are judged at its states, not at the states their own choices would have led to. The
prototypes (tie-break, options, quartile, overruled speeds) were throwaway patches of the shadows only,
through :func:`variant_planner`.

On worlds 1,000-1,999 (8,868 decisions, 151 fatal choices of the driver, which crossed 0.826 there), the
course's motion model as the draws weigh it: a first sight walks with probability 0.6 / 0.25 instead of
the course's 0.4, 156 (14 / 9) / 154 (12 / 9); nine speeds per direction instead of five, 153 (9 / 7);
the columns of the last five images instead of three, 152 (1 / 0); 16 draws, 157 (12 / 6). Again none
makes fewer.

The tables above were measured with the planner before its ties went to the draws' clearance
(``ArrivalsConfig.ties``). With them (worlds 0-999: 8,938 winnable decisions, 144 fatal choices of the
driver, which crossed 0.835; 18 minutes), a wider clearance cap, which leaves every draw's safe steps as
they are and so changes only how ties are broken, makes no fewer: 0.4 / 0.5 / 0.7 m, 145 (6 / 5) / 144
(8 / 8) / 144 (11 / 11). Nor does a search margin (the disc planner's is 0; 13 minutes): 0.01 / 0.02 m,
139 (17 / 22) / 150 (22 / 16).

A privileged shadow prices knowledge the same way: the disc planner told the truth by
:class:`~husky_course.planners.reference.ToldDiscsPlanner` (worlds 0-999, the same 8,879 decisions and
151 fatal choices of the driver, pooled from runs of 300 and 700 worlds): told its first sights' true
motion, 122 fatal choices (23 / 52, p = 0.001); every disc's, 107 (33 / 77); every cylinder an image has
rendered so far, exactly, with its motion, 55 (14 / 110). Two thirds of the fatal choices go when the map
holds the seen cylinders where they are; every disc's motion alone, less than half of that. What the map
remembers of what it has seen (discs off their cylinders, lost cylinders) is where the next gain lies,
more than in how it reads motion or how it decides.

``--save F`` writes every compared decision to ``F`` as each ten worlds finish (a killed run loses only
the worlds in flight); the same command, or one asking for more worlds, given ``F`` again resumes from it.

A variant is a comma-separated list of the disc planner's settings (``key=value``, values as Python
literals: ``samples=0``, ``margin=0.05``, ``horizon=6``, ``speed_sigma=0.0``).
"""

from __future__ import annotations

import argparse
import ast
import os
import sys
import time
from contextlib import nullcontext
from multiprocessing import Pool
from pathlib import Path

import numpy as np
from exp_moving_failures import crossable
from exp_moving_fatal import survives

from husky_course.config import Profile, get_profile, with_world
from husky_course.course.diagnosis import sign_test
from husky_course.data.code import library_fingerprint
from husky_course.data.io import atomic_save_npz, load_npz, sha256_file
from husky_course.engines import limit_worker_threads
from husky_course.evaluation.episodes import eval_world_seeds
from husky_course.evaluation.rollout import Rollout
from husky_course.planners.base import episode_start
from husky_course.planners.registry import make_planner
from husky_course.progress import tqdm
from husky_course.sim.fast import FastSimulator
from husky_course.sim.world import World

AS_IT_IS = ""  #: the variant with no settings changed: the driver itself (``--check``)


def parse_variant(text: str) -> dict:
    """The settings ``{key: value}`` of a variant written ``key=value,key=value`` (``""``: none)."""
    settings = {}
    for part in filter(None, (p.strip() for p in text.split(","))):
        key, sep, value = part.partition("=")
        if not sep or not key.strip().isidentifier():
            raise SystemExit(f"a variant is key=value[,key=value...]; got {text!r}")
        try:
            settings[key.strip()] = ast.literal_eval(value.strip())
        except (ValueError, SyntaxError):
            raise SystemExit(f"{value!r} in variant {text!r} is not a Python literal") from None
    return settings


def variant_planner(profile: Profile, variant: str):
    """The disc planner with ``variant``'s settings (an experiment may put its own rules here: the
    workers are forked, so a replacement made before :func:`main` runs reaches them; a privileged
    shadow, such as :class:`~husky_course.planners.reference.ToldDiscsPlanner`, is handed the
    simulator at the start and the true pose at every decision, as ``run_episode`` hands them)."""
    return make_planner("discs", config=profile.sim, profile=profile, **parse_variant(variant))


def judge(sim: FastSimulator, world: World, pose: np.ndarray, step: int, limit: int,
          actions: set[int]) -> dict[int, bool]:
    """Per primitive of ``actions``: whether playing it from ``pose`` at ``step`` is fatal (no way
    through the true world remains after it)."""
    return {a: not survives(sim, world, pose, a, step, limit) for a in actions}


def chunk(args: tuple[Profile, list[int], list[str]]) -> list[dict]:
    """Per world of ``seeds``: each compared decision's ``(driver fatal, [variant fatal...],
    [variant disagrees...])``, and the world's seed."""
    profile, seeds, variants = args
    sim, limit = FastSimulator(profile.sim), profile.sim.max_primitives
    driver = make_planner("discs", config=profile.sim, profile=profile)
    shadows = [variant_planner(profile, v) for v in variants]
    out = []
    for seed in seeds:
        rollout = Rollout(driver, sim, seed, limit)
        for s in shadows:
            s.reset(episode_start(s, sim, seed, rollout.start, limit))
        rows, last = [], None
        for d in rollout:
            for s in shadows:
                if last is not None:
                    s.observe(last, d.obs)
            choices = [s.act(d.obs, d.pose.copy() if s.privileged else None) for s in shadows]
            last = d.action
            if d.step == 0 and not crossable(sim, rollout.world, d.pose, 0, limit):
                break  # no way through this world at all (later states are winnable: the driver's choice
                # before each was not fatal, and its fatal one ends the comparison)
            fatal = judge(sim, rollout.world, d.pose, d.step, limit, {d.action, *choices})
            rows.append((fatal[d.action], [fatal[c] for c in choices], [c != d.action for c in choices]))
            if rows[-1][0]:
                break
        out.append({"seed": seed, "rows": rows})
    return out


def made_by() -> str:
    """What made a saved run's decisions: the library's code and this run's script (a file made by other
    code is not resumed: its decisions may differ)."""
    return f"{library_fingerprint()}-{sha256_file(Path(sys.argv[0]))[:12]}"


def load_done(path: str, variants: list[str], profile: str) -> dict[int, list]:
    """The worlds an earlier run with ``--save path`` finished, ``{seed: rows}`` (empty when there is no
    such file); a clear error when it was made with other variants, another profile or other code."""
    if not os.path.exists(path):
        return {}
    f = load_npz(Path(path))
    kept, made = [str(v) for v in f["variants"]], str(f.get("profile", "?"))
    if kept != variants or made != profile:
        raise SystemExit(f"{path} holds the variants {kept} of the {made} profile; this run asks for "
                         f"{variants} of the {profile} profile: name another --save file")
    if str(f.get("code", "?")) != made_by():
        raise SystemExit(f"{path} was made by other code (the library or the script changed since): "
                         "name another --save file")
    seed, driver, fatal, differs = f["seed"], f["driver"], f["fatal"], f["differs"]
    return {int(w): [(bool(driver[i]), fatal[i].tolist(), differs[i].tolist())
                     for i in np.flatnonzero(seed == w)] for w in f["worlds"]}


def save(path: str, variants: list[str], profile: str, worlds: list[dict]) -> None:
    """Every compared decision of ``worlds`` to ``path``, atomically (a run killed while writing leaves
    the last complete file)."""
    rows = [r for w in worlds for r in w["rows"]]
    atomic_save_npz(Path(path), {
        "variants": np.array(variants, str), "profile": np.array(profile), "code": np.array(made_by()),
        "driver": np.array([r[0] for r in rows], bool),
        "seed": np.array([w["seed"] for w in worlds for _ in w["rows"]], int),
        "fatal": np.array([r[1] for r in rows], bool).reshape(len(rows), len(variants)),
        "differs": np.array([r[2] for r in rows], bool).reshape(len(rows), len(variants)),
        "worlds": np.array([w["seed"] for w in worlds], int)})


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=1000)
    parser.add_argument("--start", type=int, default=0, help="first world of the tuning set's sequence")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--variants", nargs="+", default=["samples=0", "margin=0.05", "horizon=6"])
    parser.add_argument("--check", action="store_true", help="also shadow the driver itself (must agree)")
    parser.add_argument("--save", help="write every compared decision to this .npz as the worlds finish "
                        "(to pool slices later); a run given the same file again resumes: it reuses the "
                        "worlds the file holds")
    args = parser.parse_args(argv)
    variants = [v for v in args.variants if v.strip()] + ([AS_IT_IS] if args.check else [])
    for v in variants:
        parse_variant(v)
    profile = with_world(get_profile(args.profile), "moving")
    seeds = [int(s) for s in eval_world_seeds(args.start + args.worlds, 1)[args.start :]]
    done = load_done(args.save, variants, profile.name) if args.save else {}
    if done:
        print(f"resuming from {args.save}: {sum(s in done for s in seeds)} of the {len(seeds)} worlds done")
    todo = [s for s in seeds if s not in done]
    parts = [(profile, todo[i : i + 10], variants) for i in range(0, len(todo), 10)]
    t0 = time.perf_counter()
    finished = {s: {"seed": s, "rows": rows} for s, rows in done.items()}
    with Pool(args.workers, initializer=limit_worker_threads) if args.workers > 1 else nullcontext() as pool:
        for part in tqdm((pool.imap if pool else map)(chunk, parts), total=len(parts), desc="worlds / 10"):
            finished.update({w["seed"]: w for w in part})
            if args.save:
                save(args.save, variants, profile.name, list(finished.values()))
    worlds = [finished[s] for s in seeds]
    rows = [r for w in worlds for r in w["rows"]]
    driver = np.array([r[0] for r in rows], bool)
    first, end = args.start, args.start + args.worlds - 1
    print(f"discs on moving tuning worlds {first}-{end} (evaluation set 1, {args.profile} profile): "
          f"{len(rows)} winnable decisions compared, {int(driver.sum())} fatal choices of the driver "
          f"({time.perf_counter() - t0:.0f} s)")
    crossed = np.mean([bool(w["rows"]) and not w["rows"][-1][0] for w in worlds])
    print(f"the driver crossed {crossed:.3f} of the worlds (each had a way through, and no choice of "
          "the driver's closed it)")
    print(f"{'variant':32s} {'differs':>8s} {'fatal':>6s} {'only variant':>13s} {'only driver':>12s}  p")
    for i, v in enumerate(variants):
        fatal = np.array([r[1][i] for r in rows], bool)
        differs = int(sum(r[2][i] for r in rows))
        only_v, only_d, p = sign_test(fatal, driver)
        name = v or "(the driver itself)"
        print(f"{name:32s} {differs:8d} {int(fatal.sum()):6d} {only_v:13d} {only_d:12d}  {p:.3f}")


if __name__ == "__main__":
    main()
