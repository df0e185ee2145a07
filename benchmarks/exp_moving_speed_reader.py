"""Experiment: a network that reads a tracked cylinder's speed, against the tracks' own judging.

Run: ``python benchmarks/exp_moving_speed_reader.py [--profile full] [--worlds 1500] [--episodes 1000]
[--episodes-start 1000] [--variants speeds draws standing columns] [--readers R.pt] [--base B.npz]
[--workers 2]`` (the disc planner needs its network: ``python -m husky_course
train discs``).

Why: told the true motion of its *tracked* discs alone (those seen by two images or more; not the first
sights), the disc planner makes 52 fatal choices from the same states where it makes 66
(``exp_moving_memory.py --rules t``, tuning worlds 0-499; 6 / 20, p = 0.009; every disc's motion: 42).
Along its runs the tracks read a tracked disc's speed more than 0.1 m per step off at 6.5% of its
sightings within 6 m, and 331 of those 410 errors come from tracks with two looks (a throwaway count
along its runs on 200 tuning worlds): a line through two looks is as good as the worse of them (a first
sight cut by the view's edge, a piece that joined two cylinders, a walker passing a standing cylinder's
place). With three looks the share is 3%, with four 1.5%.

1. **Sightings.** The disc planner as it is drives ``--worlds`` training worlds of collection
   :data:`COLLECTION` (no dataset, network or certificate uses it). At every image, each disc whose
   track has two looks or more gives one row: its track's last four looks (age, place, sigma) relative
   to the newest, the speed the tracks judged (:meth:`~husky_course.planners.motion.Tracks.judged`) and
   the line's raw slope, the disc, its gap to the image's nearest other disc and, per walking
   hypothesis of :class:`~husky_course.planners.arrivals.Arrivals`, the last three images' columns that
   saw through or matched its circle (:meth:`~husky_course.planners.arrivals.Arrivals.columns`); its
   label, the lateral speed of the cylinder the disc lies on (within ``ON_CYLINDER``).
2. **Readers.** Two hidden layers of 64 classify the speed into standing or one of 8 bins of each
   direction's walks (cross-entropy), from the looks alone or with the columns; trained on the worlds
   but a fifth, judged on that fifth against the judging (printed: the share off by more than 0.1 m
   per step, and its kinds).
3. **Episodes.** Retrained on every world, the readers run inside the planner on tuning worlds
   ``--episodes-start`` onwards (evaluation set 1), beside the planner as it is: ``speeds``, the
   two-look discs' speeds read by the reader with the columns (its most likely bin); ``draws``, in each
   of the planner's draws (``ArrivalsConfig.samples``) every tracked disc's speed drawn from the
   looks' reader's probabilities, in place of the tracked walkers' normal error (``speed_sigma``).
   ``--variants`` may also name ``standing``: only the tracked discs the tracks *read standing* drawn from
   the reader with the columns (a walk in the share of draws its chance of walking gives; the tracked
   walkers keep their normal error); and ``columns``: ``draws`` with the reader with the columns. The
   readers' chances for the discs read standing are printed against the truth (their calibration).
   ``--readers F`` keeps the trained readers in ``F`` (read instead of trained when it exists), and
   ``--base F`` the planner's own episodes (as ``exp_moving_variants.py`` keeps them).

Measured (full profile): see :data:`MEASURED`.
Its first figures were measured before the planner broke the last ties by its draws' options
(``ArrivalsConfig.ties`` "options"); those of ``standing`` and ``columns`` with the planner as it is now.
"""

from __future__ import annotations

import argparse
import tempfile
import types
from pathlib import Path

import numpy as np
import torch
from exp_moving_variants import BASE_HELP, paired_episodes, tuning_worlds

from husky_course.config import Profile, get_profile, with_world
from husky_course.data.collect import world_seed_for
from husky_course.engines import map_tasks
from husky_course.evaluation.rollout import Rollout
from husky_course.planners import tracking
from husky_course.planners.reference import ON_CYLINDER, truth_in_frame
from husky_course.planners.registry import make_planner
from husky_course.sim.fast import FastSimulator

COLLECTION = 7  #: training worlds' collection seed (0-6 are taken)
LOOKS = 4  #: the looks a track keeps (``TrackingConfig.looks``)
WIDTH = 1 + 4 * LOOKS + 6  #: a row's columns before the evidence: looks, judged, slope, disc, gap
VARIANTS = ("speeds", "draws")
#: variants ``--variants`` may also name: ``standing``, the tracked discs *read standing* drawn from the
#: reader with the columns (the tracked walkers keep ``speed_sigma``); ``columns``, every two-look-or-more
#: disc drawn from it (``draws`` with the columns' reader)
MORE = ("standing", "columns")
MEASURED = """
Full profile, this script's defaults (``--worlds 1500 --episodes 1000``; 21 minutes on 2 cores):
47,250 tracked sightings, 9,444 of them in the held-out fifth. Off by more than 0.1 m per step there:
the tracks' judging 0.0615 (walkers read standing 0.0506, standing read walking 0.0165; two-look
tracks 0.1060); the looks' reader 0.0675 (0.0557, 0.0163; 0.1120): no better, the judging already reads
what the looks hold; the reader with the columns 0.0590 (0.0414, 0.0111; 0.0944): a little better, both
ways. Episodes on tuning worlds 1,000-1,999: the planner as it is 0.846; ``speeds`` 0.839 (won only with
/ only without: 20 / 27, p = 0.38); ``draws`` 0.850 (35 / 31, p = 0.71). Neither moves success.
Prototypes of the same steps (their readers trained on the same rows in another order) crossed 0.844
(23 / 25) and 0.845 (33 / 34); from the same states (``exp_moving_paired.py``'s screen, worlds 0-499,
66 fatal choices of the planner) the prototype's ``draws`` shadow made 56 (8 / 18, p = 0.08), the
screen's usual overstatement of a rule that changes many decisions (882 of 4,527 here): better-read
speeds, the same worlds, as when the columns overruled the tracks (``ArrivalsConfig.speed_sigma``).

With the planner as it is (library fingerprint 28e5ef29ec515817; ``--worlds 1500``, readers kept with
``--readers``; 10.5 min of sightings): 46,910 tracked sightings, 9,348 held out. Of the 5,703 held-out
sightings the tracks read standing, 3.3% are walkers; the reader with the columns gives them a mean chance
of walking of 0.029, and is calibrated: below 0.02 (4,906 sightings) 0.3% walk, 0.02-0.05 3.6%, 0.05-0.1
10%, 0.1-0.2 22%, 0.2-0.5 38%, above 0.5 (107) 67% (the looks' reader: 0.2%, 2.4%, 5.8%, 16%, 24%, 63%,
and fewer sightings at the top). Episodes (about 8 minutes per variant and 1,000 worlds), beside the
planner as it is; chosen on tuning worlds 7,000-8,999 between ``standing`` and ``columns``:

- tuning worlds 7,000-7,999 (choose): as it is 0.838; ``standing`` 0.850 (29 / 17, p = 0.10); ``columns``
  0.858 (43 / 23, p = 0.019);
- 8,000-8,999 (choose): 0.862; ``standing`` 0.874 (31 / 19, p = 0.12); ``columns`` 0.878 (39 / 23, p = 0.056);
- 9,000-9,999 (test): 0.844; ``columns`` 0.844 (29 / 29);
- 10,000-10,999 (test): 0.837; ``columns`` 0.865 (48 / 20, p = 0.001);
- 11,000-11,999 (test): 0.855; ``columns`` 0.851 (25 / 29);
- 12,000-12,999 (test): 0.852; ``columns`` 0.852 (33 / 33).

``columns`` was chosen (82 / 46 on the choosing slices, ``standing`` 60 / 36). On the four test slices,
named before they ran, it crossed 0.853 against 0.847: 135 / 111, p = 0.14, and one slice of four carries
it. Not shown; not landed. Its gain on the choosing slices (+1.8 points) shrank to +0.6 on the test
slices, as the 0.25 quantile's did (``ArrivalsConfig.ties``: +1.1 chosen, +0.0 tested): the better of two
rules on 2,000 worlds carries that much of those worlds' luck.
What a perfect reader of the tracked discs' speeds would give, on the same four test slices
(``exp_moving_variants.py --variants memory:t``, privileged: every tracked disc's true velocity, not
drawn): 0.865 / 0.855 / 0.864 / 0.868, together 0.863 against 0.847 (130 / 66, p < 0.001). The reader took
about a third of that (+0.6 of +1.6 points), and not on the same slices: nothing on 9,000-9,999, where
the true speeds gained the most (+2.1), and +2.8 on 10,000-10,999, more than they gained there (+1.8).
Not a ceiling for the draws (a rule that draws may keep clear of more than the truth does), but the size
of the rung: tracked speeds are worth under two points of the 4.1 missing.

A second test of ``columns``, named before it ran (in the closing note of the stop that measured the
first), on tuning worlds 13,000-16,999 and judged alone; the readers trained again by the same command
(the same calibration to the last sighting): as it is 0.863 / 0.863 / 0.832 / 0.832, ``columns`` 0.865
(29 / 27) / 0.871 (29 / 21) / 0.832 (31 / 31) / 0.840 (37 / 29); together 0.852 against 0.847, 126 / 108,
p = 0.27. Not shown again. Both tests' 8,000 worlds together (a figure, not a test named before): 261 /
219, p = 0.06, about half a point. If the gain is real, it is about an eighth of the 4.1 points missing,
and showing it would take some 20,000 worlds.
"""


def rows_of(planner) -> dict:
    """Make ``planner`` (the disc planner) keep, per image, what :func:`rows` reads: each piece's track,
    the image's discs and which are cylinders, and the columns' evidence on them."""
    m, rec = planner.map, {}
    tracks, decode, remember = m.motion.tracks, m.decode, m.arrivals.remember
    update = tracks.update

    def kept_update(pieces, now, centres=None):
        v = update(pieces, now, centres)
        small = [k for k, idx in enumerate(pieces) if np.ptp(now[idx], axis=0).max() <= 1.0]
        rec["tracks"] = {k: tracks.tracks[i].copy() for i, k in enumerate(small)}
        return v

    def kept_decode(*args, **kwargs):
        out = decode(*args, **kwargs)
        rec["discs"], rec["cyl"] = out[0].copy(), out[1].copy()
        return out

    def kept_remember(depth: np.ndarray) -> None:
        if len(rec.get("discs", ())):
            through, match = m.arrivals.columns(rec["discs"])
            rec["evidence"] = np.c_[through, match]
        remember(depth)

    tracks.update, m.decode, m.arrivals.remember = kept_update, kept_decode, kept_remember
    return rec


def rows(planner, rec: dict) -> tuple[np.ndarray, np.ndarray]:
    """``(rows (k, F), index (k,))``: one row per disc of the last image whose track has two looks or
    more (module docstring, 1), and its index among the map's discs."""
    m = planner.map
    width = WIDTH + 2 * len(m.arrivals.hypotheses)
    if "discs" not in rec:
        return np.zeros((0, width)), np.zeros(0, int)
    discs, cyl, tracks = rec["discs"], rec["cyl"], rec.get("tracks", {})
    evidence = rec.get("evidence", np.zeros((len(discs), 2 * len(m.arrivals.hypotheses))))
    held, out, at = discs[cyl], [], []
    for k in np.flatnonzero(cyl):
        t, i = tracks.get(int(k)), int(np.sum(cyl[:k]))  # the image's discs come first in the map
        if t is None or len(t) < 2 or m.fresh[i]:
            continue
        disc, others = discs[k], np.delete(held, i, axis=0)
        gap = np.hypot(others[:, 0] - disc[0], others[:, 1] - disc[1]) - others[:, 2] - disc[2]
        looks = np.zeros((LOOKS, 4))
        looks[: len(t)] = t[-LOOKS:]
        out.append(np.r_[len(t), looks.ravel(), m.speeds[i], tracks_slope(m, t), disc,
                         gap.min() if len(gap) else 9.0, evidence[k]])
        at.append(i)
    return np.array(out).reshape(len(out), width), np.array(at, int)


def tracks_slope(m, track: np.ndarray) -> float:
    """The track's raw least-squares slope (m per step), before judging."""
    return m.motion.tracks.line(track)[1]


def sightings(args: tuple[Profile, list[int]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(rows, speeds, worlds)`` of every tracked sighting along the disc planner's runs in ``seeds``."""
    profile, seeds = args
    sim, limit = FastSimulator(profile.sim), profile.sim.max_primitives
    planner = make_planner("discs", config=profile.sim, profile=profile)
    rec = rows_of(planner)
    x, y, w = [], [], []
    for seed in seeds:
        rollout = Rollout(planner, sim, seed, limit)
        for d in rollout:
            r, at = rows(planner, rec)
            rec.clear()
            cyl, vy = truth_in_frame(rollout.world, d.pose, float(d.step))
            for row, i in zip(r, at, strict=True):
                disc = planner.map.discs[i]
                gap = np.hypot(cyl[:, 0] - disc[0], cyl[:, 1] - disc[1]) - cyl[:, 2]
                if gap.min() < ON_CYLINDER:
                    x.append(row), y.append(vy[int(np.argmin(gap))]), w.append(seed)
    width = WIDTH + 2 * len(planner.map.arrivals.hypotheses)
    return np.array(x).reshape(len(x), width), np.array(y), np.array(w)


def bins(profile: Profile) -> np.ndarray:
    """The classes' speeds (m per step): standing, then 8 bins' centres of each direction's walks."""
    lo, hi = profile.sim.world.speed_range  # type: ignore[attr-defined]
    edges = np.linspace(lo, hi, 9)
    mid = (edges[:-1] + edges[1:]) / 2
    return np.r_[0.0, mid, -mid]


def features(x: np.ndarray, columns: bool) -> np.ndarray:
    """A reader's inputs from :func:`rows`' rows: each look (present, age, place and sigma, relative to the
    newest), the judged speed, the slope, the disc's range and radius, its gap; with ``columns``, the
    evidence's counts (log)."""
    n = x[:, 0].astype(int)
    looks = x[:, 1 : 1 + 4 * LOOKS].reshape(-1, LOOKS, 4)
    newest = looks[np.arange(len(x)), n - 1]
    present = (np.arange(LOOKS)[None] < n[:, None]).astype(float)
    rel = looks - np.c_[np.zeros(len(x)), newest[:, 1:3], np.zeros(len(x))][:, None]
    judged, slope, disc, gap = x[:, 17], x[:, 18], x[:, 19:22], x[:, 22]
    out = [present, (rel * present[..., None]).reshape(len(x), -1), judged, np.clip(slope, -1, 1),
           disc[:, 0] / 5, disc[:, 2], np.clip(gap, -0.5, 2)]
    if columns:
        out.append(np.log1p(x[:, WIDTH:]))
    return np.column_stack(out).astype(np.float32)


def label(y: np.ndarray, speeds: np.ndarray) -> np.ndarray:
    """Each true speed's class (the nearest of ``speeds`` of its sign; standing only when it stands)."""
    walks = speeds[1:9]
    k = np.argmin(np.abs(np.abs(y)[:, None] - walks[None]), axis=1) + 1
    return np.where(np.abs(y) < 1e-9, 0, np.where(y > 0, k, k + 8))


def learn(x: np.ndarray, y: np.ndarray, speeds: np.ndarray, columns: bool, seed: int = 0,
          epochs: int = 60) -> dict:
    """A reader (module docstring, 2): its weights and input scaling, as plain tensors."""
    torch.manual_seed(seed)
    f, t = torch.tensor(features(x, columns)), torch.tensor(label(y, speeds))
    mu, sd = f.mean(0), f.std(0) + 1e-6
    net = reader_net(f.shape[1])
    opt = torch.optim.Adam(net.parameters(), 1e-3, weight_decay=1e-5)
    for _ in range(epochs):
        order = torch.randperm(len(f))
        for i in range(0, len(f), 256):
            b = order[i : i + 256]
            loss = torch.nn.functional.cross_entropy(net((f[b] - mu) / sd), t[b])
            opt.zero_grad()
            loss.backward()
            opt.step()
    return {"state": net.state_dict(), "mu": mu, "sd": sd, "columns": columns}


def reader_net(inputs: int) -> torch.nn.Module:
    """Two hidden layers of 64, 17 classes (:func:`bins`)."""
    return torch.nn.Sequential(torch.nn.Linear(inputs, 64), torch.nn.ReLU(), torch.nn.Linear(64, 64),
                               torch.nn.ReLU(), torch.nn.Linear(64, 17))


def probabilities(reader: dict, x: np.ndarray) -> np.ndarray:
    """``(k, 17)``: the reader's class probabilities for rows ``x``."""
    net = reader_net(len(reader["mu"]))
    net.load_state_dict(reader["state"])
    with torch.no_grad():
        f = (torch.tensor(features(x, reader["columns"])) - reader["mu"]) / reader["sd"]
        return torch.softmax(net(f), 1).numpy()


def errors(v: np.ndarray, y: np.ndarray, n: np.ndarray) -> str:
    """The share of speeds ``v`` off the truth ``y`` by more than 0.1 m per step, and its kinds."""
    off, walks = np.abs(v - y) > 0.1, np.abs(y) > 1e-9
    two = n == 2
    return (f"{off.mean():.4f} (walkers read standing {np.mean(v[walks] == 0):.4f}, standing read walking "
            f"{np.mean(v[~walks] != 0):.4f}; two looks {off[two].mean() if two.any() else 0:.4f})")


def wire(planner, readers: dict, variant: str, speeds: np.ndarray) -> None:
    """Put ``variant``'s reader in ``planner`` (module docstring, 3)."""
    rec, add = rows_of(planner), planner.map.add
    planner.map.read = np.zeros((0, 17)), np.zeros(0, int)

    def read_add(obs: np.ndarray) -> None:
        rec.clear()
        add(obs)
        x, at = rows(planner, rec)
        if variant == "speeds":
            two = x[:, 0] == 2
            if two.any():
                planner.map.speeds[at[two]] = speeds[probabilities(readers["columns"], x[two]).argmax(1)]
        else:
            reader = readers["looks" if variant == "draws" else "columns"]
            if variant == "standing":  # only the discs the tracks read standing
                still = planner.map.speeds[at] == 0
                x, at = x[still], at[still]
            planner.map.read = (probabilities(reader, x) if len(x) else np.zeros((0, 17))), at

    planner.map.add = read_add
    if variant != "speeds":
        planner._decide_over_draws = types.MethodType(lambda self, h: drawn(self, h, speeds), planner)


def drawn(self, horizon: int, speeds: np.ndarray) -> tuple[int, np.ndarray]:
    """``TrackingPlanner._decide_over_draws`` with each read disc's speed drawn from its reader's classes
    (a bin's speed uniform within it) in place of the tracked walkers' normal error; the map's ghosts drawn
    as the library draws them (before 2026-12-08 none: the module docstring's figures were measured before
    the planner had ghosts)."""
    prob, at = self.map.read
    if not len(at):  # nothing read: the planner's own draws (before 8fed14f, ``draws`` drew here too)
        return tracking.TrackingPlanner._decide_over_draws(self, horizon)
    keys = tracking.MappingPlanner._decide(self, horizon)[1]
    group, weights = self.map.walk_doubt
    read = np.zeros(len(self.points), bool)
    read[at] = True
    tracked = self.tracked & ~read
    rng, h = np.random.default_rng((self._key, self._remaining)), self.map.arrivals.hypotheses
    later = np.random.default_rng((self._key, self._remaining, 7))  # the library's ghosts, as it draws them
    ghosts = self.map.dropped
    ghost_weights = ghosts.weights() if ghosts is not None else []
    tally, base, k = tracking.Tally(self.ties, keys), self.velocity, int(tracked.sum())
    drawn_ones = (group >= 0) & self.doubtful if len(weights) else None
    half = (speeds[2] - speeds[1]) / 2
    for _ in range(self.samples):
        v = base.copy()
        if drawn_ones is not None:
            first = h[[rng.choice(len(h), p=w) for w in weights]]
            v = np.where(drawn_ones, first[np.maximum(group, 0)], v)
        if k:
            v[tracked] += rng.normal(0.0, self.speed_sigma, k)
        if len(at):
            c = np.array([rng.choice(17, p=p / p.sum()) for p in prob])
            v[at] = speeds[c] + np.where(c > 0, rng.uniform(-half, half, len(c)), 0.0)
        if ghost_weights:  # each ghost at an open walk, its slot after the map's points (DiscTrackingPlanner)
            ghosts.draw = [int(later.choice(len(h), p=w)) for w in ghost_weights]
            v = np.r_[v, ghosts.slots()[1]]
        try:
            tally.add(self._keys_if(horizon, v), self._drawn)
        finally:
            if ghosts is not None:
                ghosts.draw = None
    return tally.ranked()


def reader_planner(profile: Profile, name: str):
    """The disc planner with ``name``'s reader, ``VARIANT@READERS`` (a file :func:`main`'s ``--readers``
    wrote); a module-level builder for :func:`exp_moving_variants.paired_episodes`."""
    variant, _, path = name.partition("@")
    planner = make_planner("discs", config=profile.sim, profile=profile)
    wire(planner, load_readers(Path(path)), variant, bins(profile))
    return planner


def save_readers(path: Path, readers: dict) -> None:
    """Keep the trained readers (plain tensors; read back with ``weights_only=True``)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    torch.save(readers, tmp)
    tmp.replace(path)  # never half-written


def load_readers(path: Path) -> dict:
    """The readers :func:`save_readers` kept."""
    return torch.load(path, weights_only=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--worlds", type=int, default=1500, help="training worlds of collection 7")
    parser.add_argument("--episodes", type=int, default=1000, help="tuning worlds per planner (0: none)")
    parser.add_argument("--episodes-start", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--epochs", type=int, default=60)
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=[*VARIANTS, *MORE])
    parser.add_argument("--readers", type=Path, help="a file of the trained readers: read if it exists, "
                        "else the sightings are collected, the readers trained and the file written")
    parser.add_argument("--base", type=Path, help=BASE_HELP)
    args = parser.parse_args()
    if args.worlds < 5:
        parser.error("--worlds needs at least 5 (a fifth is held out)")
    profile = with_world(get_profile(args.profile), "moving")
    speeds = bins(profile)
    if args.readers is not None and args.readers.exists():
        readers = load_readers(args.readers)
        print(f"the readers: read from {args.readers}")
    else:
        readers = train_readers(profile, speeds, args)
        if args.readers is not None:
            save_readers(args.readers, readers)
    if not args.episodes:
        return
    worlds = tuning_worlds(args.episodes_start, args.episodes, args.profile)
    with tempfile.TemporaryDirectory() as scratch:  # the workers read the readers from a file
        path = args.readers
        if path is None:
            path = Path(scratch) / "readers.pt"
            save_readers(path, readers)
        paired_episodes(reader_planner, [f"{v}@{path}" for v in args.variants], profile, worlds,
                        args.workers, args.base)


def train_readers(profile: Profile, speeds: np.ndarray, args: argparse.Namespace) -> dict:
    """Collect the sightings of ``args.worlds`` training worlds, print the readers' errors on a held-out
    fifth, and return both readers retrained on every world (module docstring, 1-2)."""
    seeds = [world_seed_for(COLLECTION, i) for i in range(args.worlds)]
    parts = map_tasks(sightings, [(profile, seeds[i : i + 10]) for i in range(0, len(seeds), 10)],
                      workers=args.workers, desc="sightings", unit="10 worlds")
    x, y, w = (np.concatenate([p[j] for p in parts]) for j in range(3))
    held = np.isin(w, seeds[::5])
    print(f"discs on {args.worlds} moving training worlds of collection {COLLECTION} ({profile.name} "
          f"profile): {len(x)} tracked sightings, {int(held.sum())} of them in the held-out fifth")
    judged = errors(x[held, 17], y[held], x[held, 0])
    print(f"  off by more than 0.1 m per step, the tracks' judging: {judged}")
    standing = held & (x[:, 17] == 0)
    readers = {}
    for name, columns in (("looks", False), ("columns", True)):
        r = learn(x[~held], y[~held], speeds, columns, epochs=args.epochs)
        p = probabilities(r, x[held]) if held.any() else np.zeros((0, 17))
        print(f"  the reader of the {name:7s}: {errors(speeds[p.argmax(1)], y[held], x[held, 0])}")
        if standing.any():
            print(f"    {calibration(p[standing[held]], y[standing])}")
        readers[name] = learn(x, y, speeds, columns, epochs=args.epochs)
    return readers


def calibration(p: np.ndarray, y: np.ndarray) -> str:
    """How well the chance of walking a reader gives the discs *read standing* (rows ``p``, their true
    speeds ``y``) is calibrated: the walkers' share by bins of that chance."""
    walk, walks = 1 - p[:, 0], np.abs(y) > 1e-9
    edges = np.array([0, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0001])
    k = np.digitize(walk, edges) - 1
    parts = [f"[{edges[i]:.2f}, {min(edges[i + 1], 1):.2f}): {np.sum(k == i)} read, walkers "
             f"{walks[k == i].mean() if np.any(k == i) else 0:.3f}" for i in range(len(edges) - 1)]
    return (f"read standing by the tracks: {len(y)}, walkers {walks.mean():.3f}, mean chance given "
            f"{walk.mean():.3f}; by chance " + "; ".join(parts))


if __name__ == "__main__":
    main()
