"""The configuration of planning and its evaluation: the oracle's ranking, the classical planners'
tuned settings, and how the planning chapters evaluate."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class OracleConfig:
    """How the oracle ranks plans of equal length (see :func:`husky_course.sim.lattice.rank_plans`)."""

    cap: float = 0.3  #: clearance (m) above which plans are not told apart
    quantum: float = 0.02  #: clearance is compared in bins of this size (m)


@dataclass(frozen=True)
class EvalPlan:
    """How many held-out worlds the planning chapters evaluate on (tables), and tune on (sweeps)."""

    worlds: int = 500
    seed: int = 0  #: which held-out set (see :func:`husky_course.evaluation.episodes.eval_world_seeds`)
    tuning_worlds: int = 200  #: a sweep's worlds, of evaluation set ``tuning_seed``
    tuning_seed: int = 1  #: the held-out set every sweep and choice is made on (never ``seed``)
    workers: int = 2  #: local processes the chapters evaluate with (every result but timing is the same)
    look_ahead: int = 2  #: Algorithm 1's and the RNN's look-ahead in the tables (chapter 7's sweep shows it)
    static_goal: float = 0.95  #: share of the oracle's success the static course's goal asks (chapter 8)
    moving_goal: float = 0.9  #: share of the space-time oracle's the moving course's goal asks (chapter 10)
    sensing_loss: float = 0.03  #: success the noise-trained planner may lose to realistic senses (chapter 11)


@dataclass(frozen=True)
class MappingConfig:
    """The mapping planner's settings (:mod:`husky_course.planners.mapping`), also the tracker's and the
    disc planner's unless they say otherwise.

    Chosen on evaluation set 1, the tuning set (200 worlds, full profile): success 0.84 / 0.89 /
    0.905 / 0.905 / 0.905 for horizons 3 / 4 / 5 / 6 / 8, and the margin of 0.02 m over 0.05 and
    0.08. ``resolution`` fixes the cells of the path tables the search reads; ``path_samples``, how
    many samples of an edge the tracker judges against its walking points (neither tuned: their
    rounding is covered by the margin; the path tables at 0.0125 m crossed 0.951 of 3,000 tuning
    worlds with the disc planner, as at 0.025 m).
    """

    horizon: int = 5
    margin: float = 0.02  #: m of clearance an edge must keep beyond contact
    resolution: float = 0.025  #: m per cell of the path tables
    path_samples: int = 21  #: samples of each edge judged against walking points


@dataclass(frozen=True)
class HeuristicConfig:
    """The depth-scan heuristic's settings (:class:`~husky_course.planners.classic.HeuristicPlanner`).

    Not chosen by a recorded tuning-set sweep: these values predate the course's tuning set, and
    no sweep of them has been kept (``bench_planners.py`` compares ``lateral_weight`` 0.05 with
    memory). They are the planner as chapter 7 presents it, a baseline and not a tuned rival.
    """

    cap: float = 0.35  #: m of clearance beyond which paths are not told apart
    lateral_weight: float = 0.1  #: cost per metre of sideways offset
    depth: int = 2  #: primitives looked ahead (1 or 2)
    path_samples: int = 11


@dataclass(frozen=True)
class TrackingConfig:
    """How the moving course's planners follow cylinders from image to image
    (:class:`~husky_course.planners.motion.Tracks`).

    ``error_scale`` was chosen on the tuning set (100 worlds along the tracker's own runs and 200
    for its success; see :meth:`~husky_course.planners.motion.Tracks.judged`); the others are the
    tracker's first design (four looks, a track kept two steps unseen, 0.2 m gate, 0.3 m along). For the
    disc planner, as it is (tuning worlds 1,000-1,999, full profile, 0.846; a throwaway driver setting its
    tracks' attributes): ``keep`` 3, 0.845 (won only with / only without: 2 / 3); ``gate`` 0.3, 0.843 (0 / 3).
    An exact assignment of pieces to tracks in place of the greedy cheapest pair first
    (:meth:`~husky_course.planners.motion.Tracks.join`; ``benchmarks/exp_moving_association.py``, the disc
    planner with its ghosts): 9 / 6 on tuning worlds 7,000-8,999, then 3 / 6 on the test, 13,000-14,999: not
    shown.
    """

    looks: int = 4
    keep: int = 2
    gate: float = 0.2
    x_gate: float = 0.3
    error_scale: float = 0.5
    #: the disc planner's tracks locate a cylinder's piece by its network's disc centre, not by the
    #: fitted circle (:class:`~husky_course.planners.moving_discs.WalkingDiscMap`). Along its runs the
    #: centres' median lateral error within 3 m is 0.007 m against the fit's 0.030 m; on four slices of
    #: 1,000 moving tuning worlds (full profile; worlds 0-999 / ... / 3,000-3,999) it crossed 0.805 /
    #: 0.801 / 0.815 / 0.812 against the fit's 0.798 / 0.793 / 0.811 / 0.797 (won only with / only
    #: without: 35 / 28, 35 / 27, 37 / 33, 35 / 20; pooled 142 / 108, p = 0.04; the fourth slice was
    #: run after three had left it at p = 0.2, so that p is a second look). With the centres, none of these
    #: moved the disc planner on worlds 0-999 (0.805; won only with / only without): ``looks`` 2, 0.798
    #: (7 / 14); ``error_scale`` 0.15, 0.807 (12 / 10); the centre-located sightings' sigma times 0.5 / 0.25
    #: (which also tightens the gate), 0.803 / 0.803 (10 / 12, 17 / 19); a track whose line fits badly read
    #: off its last two looks (walkers that bounced off a wall within 3 steps are off by over 0.1 m per step
    #: 46.5% of the time, against 8.1%, but are 7% of tracked walkers within 4 m), at two thresholds 0.807 /
    #: 0.805 (4 / 2, 6 / 6). With the disc planner's draws (``ArrivalsConfig.samples``; 0.828 on worlds
    #: 0-999): ``looks`` 6, 0.826 (0 / 2: a cylinder is rarely seen more than four times); ``error_scale``
    #: 0.25, 0.826 (7 / 9). A tracked disc's speed overruled by the last three images' columns where they
    #: decide (:meth:`~husky_course.planners.arrivals.Arrivals.evidence` over 9 walks a direction): along
    #: the runs (300 tuning worlds) walkers' speeds off by more than 0.1 m per step fell from 0.127 to
    #: 0.088, standing ones read walking rose from 0.030 to 0.051 (only where the track reads a walk:
    #: 0.112 / 0.020); the planner crossed 0.833 / 0.829 (35 / 30, 26 / 25): better speeds, the same worlds
    disc_centres: bool = True
    #: a track whose looks fold at a side wall's face (a walker that bounced between two looks, whose
    #: straight line is flat) is unfolded where the fold lowers its weighted squared residual by more
    #: than this (:func:`~husky_course.planners.walls.reflected_line`; ``None``: never); both planners.
    #: Our first value, not swept. Full profile, tuning worlds 1,000-2,999 / 3,000-4,999 (the second slice
    #: used for nothing before), episodes: the disc planner 0.858 -> 0.861 / 0.832 -> 0.837 (worlds won
    #: only with / only without: 8 / 2, 10 / 1; pooled 18 / 3, p = 0.001), the tracker 0.759 -> 0.760 /
    #: 0.736 -> 0.738 (7 / 4, 6 / 3; pooled 13 / 7, p = 0.26: no gain shown; it folds too, so that neither
    #: planner holds a reading the other lacks). ``benchmarks/exp_moving_fold.py`` runs both side by side.
    #: A prototype that bounced only the predictions new pieces are gated against, without the fold, took
    #: the tracker to 0.754 / 0.732. The fold takes about one line in a hundred with the faces known
    bounce_gain: float | None = 4.0


@dataclass(frozen=True)
class WallsConfig:
    """Where the moving disc planner places the side walls' faces, so that its walking discs bounce
    off them (:mod:`husky_course.planners.walls`). Our first choice, not swept; on 2,000 moving tuning
    worlds (full profile, ``benchmarks/exp_moving_walls.py``) bouncing took the disc planner from
    0.770 / 0.766 to 0.780 / 0.776 (worlds 0-999 / 1,000-1,999 of evaluation set 1; won only with /
    only without: 12 / 2, 13 / 3), the same worlds as with the faces told from the true start."""

    beyond: float = 2.5  #: m to the side beyond which a remembered non-cylinder point may be a wall
    bin: float = 0.1  #: m, the width of the bins of lateral position searched for a face
    points: int = 5  #: points a bin needs to be a face
    #: the tracker's walking points bounce too (its wall points: pieces over 1 m). On worlds 0-999 /
    #: 1,000-1,999 of the tuning set it crossed 0.735 / 0.756 straight, 0.741 / 0.761 bouncing (8 / 2,
    #: 9 / 4): the same rule as the disc planner's, so that neither holds a reading the other lacks
    tracker: bool = True


@dataclass(frozen=True)
class ArrivalsConfig:
    """First sightings that walked in (:mod:`husky_course.planners.arrivals`), chosen on 300 moving
    tuning worlds (full profile, the disc planner): tolerance 0.08 / 0.15 / 0.25 m gave 0.780 /
    0.787 / 0.783; the mean of the speeds left 0.787 against the slowest 0.780 and fastest 0.767."""

    tolerance: float = 0.15  #: m beyond a hypothesised front the previous ray must reach
    hypotheses: int = 5  #: walking speeds tried per direction
    #: previous images whose columns' evidence :meth:`~husky_course.planners.arrivals.Arrivals.read`
    #: weighs (0: off; the module gives the measurements: 1 / 3 images chosen on three slices)
    images: int = 3
    evidence_tolerance: float = 0.1  #: m within which a column matches a hypothesised circle
    #: the tracker's ``images`` (:class:`~husky_course.planners.tracking.TrackingPlanner`). Off: offered
    #: the same evidence on its fitted circles, the tracker crossed 0.735 -> 0.744 (24 / 15) and 0.756 ->
    #: 0.756 (16 / 16) on worlds 0-999 / 1,000-1,999 of the tuning set (full profile;
    #: ``benchmarks/exp_moving_evidence.py``)
    tracker_images: int = 0
    #: steps over which a first sight left standing is also taken as possibly walking (0: off). Off:
    #: on the tuning set (300 moving worlds, full profile, the tracker; ``exp_moving_doubt.py``) the
    #: band cost success in every form tried: off 0.740; in the clearance only, 1 / 2 steps, 0.700 /
    #: 0.657; as an obstacle, 0.5 / 1 step, 0.723 / 0.667. Most first sights stand, and the band
    #: steers the robot around them into what it has not seen.
    doubt_steps: float = 0.0
    doubt_hard: bool = False  #: that band blocks an edge (else it only lowers a plan's clearance)
    #: choose the first primitive by its expected safe steps over three hypotheses for those first sights
    #: (standing, walking either way at the mean speed, weighted by the course's walking share). Off:
    #: on 300 moving tuning worlds (full profile, ``exp_moving_doubt.py --settings off,hedge``) it
    #: changed nothing measurable: the tracker 0.740 / 0.733, the disc planner 0.777 / 0.777 (10 worlds
    #: of 300 decided differently each), at about three times the time per decision.
    hedge: bool = False
    #: at the episode's first decision (one image: every first sight in view doubtful), choose the first
    #: primitive by its mean safe steps over this many draws of the course's motion model for the
    #: doubtful pieces (``TrackingPlanner._decide``; 0: off). Off: on 1,000 moving tuning worlds (full
    #: profile, ``benchmarks/exp_moving_start.py --worlds 1000``) the disc planner crossed 0.770 off,
    #: 0.778 / 0.771 with 16 / 32 draws (worlds won only with / only without: 15 / 7, 21 / 20), the
    #: tracker 0.735 off, 0.728 with 16. A first prototype's 0.784 (20 / 6) came from its own draws.
    first_samples: int = 0
    #: every decision, choose the first primitive by its mean safe steps over this many draws of walks for
    #: the last image's first sights that the earlier images leave undecided, each from the course's
    #: motion model over the walks no earlier column saw through, and (``speed_sigma``) of the tracked
    #: walkers' speeds (``TrackingPlanner._decide``,
    #: :meth:`~husky_course.planners.arrivals.Arrivals.weights`; 0: off; the disc planner's). 32 with
    #: ``speed_sigma`` 0.05: on four slices of 1,000 moving tuning worlds (full profile; worlds 0-999 /
    #: ... / 3,000-3,999; network centres) this code crossed 0.828 / 0.826 / 0.815 / 0.817 against
    #: 0.805 / 0.801 / 0.815 / 0.812 off (won only with / only without: 46 / 23, 45 / 20, 33 / 33,
    #: 35 / 30; pooled 159 / 106, p = 0.001); its prototype (errors drawn for walkers 1-6 m ahead)
    #: 0.825 / 0.822 / 0.814 / 0.818; the first sights' draws alone (``speed_sigma`` 0), 0.815 / 0.813 /
    #: 0.810 / 0.816 (23 / 13, 32 / 20, 25 / 30, 26 / 22; pooled 106 / 85, p = 0.15); 64 draws, 0.827 on
    #: worlds 0-999 (twice the time).
    #: Earlier measurements, before the network's centres and of the first sights' draws alone: on
    #: four slices of 1,000 moving tuning worlds (full profile; worlds 0-999 / ... / 3,000-3,999) a
    #: prototype with 16 draws crossed 0.809 / 0.802 / 0.814 / 0.795 against 0.798 / 0.793 / 0.811 /
    #: 0.797 (won only with / only without: 22 / 13, 25 / 16, 27 / 24, 20 / 22; pooled 94 / 75, p = 0.17),
    #: 32 draws 0.807 (34 / 25) on the first slice, and this code's own draws 0.802 (23 / 19) there: no
    #: gain that can be shown, at about four times the time per decision. Two variants, prototypes on
    #: worlds 0-999 / 1,000-1,999 / 2,000-2,999 against 0.805 / 0.801 / 0.815 (network centres): 32 draws
    #: at the first decision only, 0.815 / 0.817 / 0.802 (23 / 13, 30 / 14, 16 / 29); every decision,
    #: ranked by the share of draws whose plan survives the whole horizon, 0.817 / 0.812 / 0.809 (30 / 18,
    #: 32 / 21, 24 / 30). Neither gain holds across slices. Against this code with 32 draws (0.828 on
    #: worlds 0-999; prototypes there, won only with / only without): each draw's safe steps capped at 3
    #: before the mean, 0.823 (20 / 25); the draws surviving the whole horizon first, then the mean, 0.829
    #: (1 / 0); every first sight of the image drawn (those read walking among the walks left their way,
    #: those whose every walk some column saw through from the course's model), 0.828 (5 / 5); horizon
    #: 6 / 4, 0.831 / 0.823 (6 / 3, 17 / 22); no unexplained points (``DiscConfig.unexplained`` inf), 0.813
    #: (19 / 34); with the draws' ties (``ties``), horizon 6 on worlds 1,000-1,999 crossed 0.845 against
    #: 0.846 (4 / 5: nine worlds decided differently). Along its runs the undecided first sights are
    #: believed to walk as often as they do
    #: (``benchmarks/exp_moving_beliefs.py``: 0.400 against 0.394 at the first decision, 0.390 against
    #: 0.398 later, 300 worlds). Scoring, against this code on worlds 0-999 (0.828): each first primitive
    #: by one plan per lattice state for all the draws (not each draw's own best: non-clairvoyant), 0.825
    #: (38 / 41); the mean of the two, 0.834 (29 / 23), but 0.816 on worlds 1,000-1,999 (35 / 45 against
    #: 0.826); ties of the mean broken by the draws' mean clearance bins before the map's own, 0.822
    #: (44 / 50). Ties: at 222 of 558 decisions (60 worlds) several first primitives tie exactly, mostly
    #: plans that make the same lateral move now or later (the lateral cost adds up the moves); the search
    #: takes the lowest index, so it moves early to one side and late to the other. Its exact mirror
    #: crossed 0.810 (63 / 81): differences of about 2 points on 1,000 worlds are noise for rules that
    #: change this many decisions. Within that, none did better: every move as early / as late as it can,
    #: 0.817 / 0.802; toward the middle between the faces read, at every level / the first only, 0.820 /
    #: 0.821; the previous decision's plan continued among equals, 0.814; with means within 1/16 counted
    #: equal, 0.811. Judged from the same states instead (``benchmarks/exp_moving_paired.py``: this code
    #: drives worlds 0-999, each variant shadows it; 8,879 winnable decisions, 151 of this code's choices
    #: fatal; a variant's fatal choices, only its own / only this code's): no draws 175 (39 / 15, p = 0.001);
    #: the mirrored tie-break 159 (33 / 25); 64 draws 151 (4 / 4); ``speed_sigma`` 0.1, 159 (17 / 9); ties of
    #: the mean broken first by the end states each first primitive's safe plans still reach, 147 (41 / 45);
    #: the draws' whole-horizon share or lower quartile ranked first, 152 / 153 (3 and 7 choices differ);
    #: tracked discs' speeds overruled by the last images' columns where they decide, 161 (30 / 20), only
    #: where the track reads a walk, 161 (23 / 13)
    samples: int = 32
    #: m per step: in each of ``samples``' draws, every walker the tracks follow walks at its track's
    #: speed plus a normal error of this spread (0: only the first sights are drawn). Along the disc
    #: planner's runs (300 tuning worlds) the tracks read a walker's speed more than 0.1 m per step off
    #: in 8% of its sightings within 4 m when it had not bounced in the last 3 steps (46% when it had).
    #: ``samples`` above gives the measurements; on worlds 0-999 of the tuning set, with 32 draws (a
    #: prototype), spreads 0.03 / 0.05 / 0.07 / 0.1 gave 0.827 / 0.825 / 0.826 / 0.815: a plateau. Drawn
    #: besides, there: a 0.1 m error of every tracked walker's place along its walk, 0.819; 0.15 m for
    #: those out of view only, 0.819 (12 / 18 against 0.825); a slow walk (0.2-0.3 m per step, either
    #: way) for each tracked standing disc 1-5 m ahead with probability 0.1, 0.809 (26 / 42). Against this
    #: code (0.828 there): each tracked disc's speed drawn from its own track's posterior (the judging's
    #: model, :meth:`~husky_course.planners.motion.Tracks.judged`: standing, or a walk in ``speed_range``,
    #: the slope's standard error as judged), 0.833 (17 / 12), but 0.816 on worlds 1,000-1,999 (7 / 17
    #: against 0.826); with that error halved (along the runs the slopes' median error is 0.34 of their
    #: standard error, half what a normal error of that spread gives), 0.818 (10 / 20); only the discs
    #: judged standing drawn so, 0.826 (11 / 13); the tracks' ``error_scale`` 0.25, 0.826 (7 / 9). A network
    #: reading each tracked disc's speed (``benchmarks/exp_moving_speed_reader.py``: trained along the
    #: planner's runs in 1,500 training worlds of collection 7, from the track's looks and the last images'
    #: columns) reads speeds a little better than the judging (off by more than 0.1 m per step at 5.9% of
    #: held-out sightings against 6.2%); taken as the two-look discs' speeds it crossed 0.839, its looks'
    #: version drawn in place of this error 0.850, against 0.846 on tuning worlds 1,000-1,999 (20 / 27,
    #: 35 / 31)
    speed_sigma: float = 0.05
    #: how the disc planner breaks ties of the draws' mean safe steps (``TrackingPlanner._decide``): "map",
    #: by the rank of its map's own velocities (clearance bins, then lateral cost, then the lowest index);
    #: "draws", by the draws' clearance bins, the fewest over the draws first, then their mean, then as
    #: "map"; "options", as "draws" but before the map's rank the most options (below). Most decisions tie
    #: at the top. Judged from the same states (``benchmarks/exp_moving_ties.py``,
    #: full profile, "map" driving): fatal choices 148 -> 136 on tuning worlds 0-999 (17 / 29) and 438 ->
    #: 384 on 3,000 worlds of collection 6 (25 / 79, p < 0.001); the draws' mean bins alone, 141 / 391; a
    #: network trained to break the ties (1,000 worlds of collection 6), 143. Episodes on tuning worlds
    #: 1,000-2,999, used for nothing before: 0.838 with "map", 0.858 with "draws" (worlds won only with it
    #: / only with "map": 106 / 67, p = 0.004). Later prototypes, episodes on tuning worlds 1,000-1,999
    #: against "draws" (0.846; won only with / only without): ties first to the first primitive after
    #: which one continuation (some draw's best) survives the most steps on average over every draw (a
    #: plan committed to, not re-chosen per draw), 0.825 (33 / 54); to the fewest such steps, 0.787
    #: (44 / 103); an edge through space none of the last three images saw free counting as at most
    #: 0.1 / 0 m of clearance (the robot's centre line and its sides), 0.844 (38 / 40) / 0.821 (42 / 67); by
    #: *options*, the end states of the horizon each first primitive's safe plans still reach (the lattice's
    #: states at its last step, the mean over the draws), before the draws' clearance bins, 0.771 (49 / 124),
    #: after them (in place of the map's own rank), 0.857 / 0.878 / 0.842 on worlds 1,000-1,999 / 2,000-2,999
    #: / 3,000-3,999 against 0.846 / 0.875 / 0.840 (33 / 22, 31 / 28, 39 / 37; pooled 103 / 87, p = 0.28):
    #: half a point three slices could not establish. Two more slices, named before they ran as the test of
    #: that rule alone (worlds 4,000-4,999 / 5,000-5,999, used for nothing before): 0.845 / 0.867 against
    #: 0.833 / 0.846 (37 / 25, 41 / 20; together 78 / 45, p = 0.004). Hence "options": the draws' fewest
    #: clearance bins, then their mean, then the most options, then the map's own rank (all five slices:
    #: 0.858 against 0.848, 181 / 132, p = 0.007; a sixth, 6,000-6,999, run after it landed: 0.857 against
    #: 0.845, 30 / 18). Tried since, throwaway variants of ``Tally`` beside "options" (episodes, full profile;
    #: tuning worlds 7,000-7,999, used for nothing before, where "options" crossed 0.838, and 8,000-8,999,
    #: 0.862; won only with / only without): options before the clearance bins, again, 0.790 (56 / 104); the
    #: fewest options over the draws in place of their mean, 0.846 / 0.862 (26 / 18, 16 / 16); options
    #: counted at every step of the horizon (the states on each first primitive's safe plans, summed over
    #: its steps), 0.846 / 0.863 (33 / 25, 21 / 20), their fewest over the draws 0.865 (25 / 22) on
    #: 8,000-8,999; the draws' mean safe steps floored to eighths before the clearance, 0.837 (1 / 2) on
    #: 7,000-7,999. None is a gain two slices show. The draws' clearance bins ranked first by a quantile
    #: over the draws in place of their fewest (the lower value; with 32 draws 0.1 is the fourth fewest,
    #: 0.25 the eighth: one narrow draw no longer decides): 0.1, 0.851 / 0.869 / 0.838 on 7,000 / 8,000 /
    #: 9,000 (25 / 12, 17 / 10, 15 / 21: the last two, named as its test, 32 / 31); 0.25,
    #: 0.847 / 0.875 (24 / 15, 20 / 7), then on 9,000 / 10,000 (0.844 / 0.837), named as its test before
    #: they ran, 0.843 / 0.849 (13 / 14, 23 / 11; together 36 / 25, p = 0.20), then on 11,000 / 12,000
    #: (0.855 / 0.852), also named as its test before they ran, 0.844 / 0.853 (15 / 26, 17 / 16): on the
    #: four test slices 68 / 67 (p = 1.0), 0.847 against 0.847. Dropped: what the tie-break still holds,
    #: if anything, is below what 4,000 worlds can show
    ties: str = "options"
    #: the tracker's ``speed_sigma``. Off, with its ``samples``: with 32 draws and 0.05 (each walking
    #: scan point's error drawn on its own, not per piece) it crossed 0.752 against 0.741 on worlds 0-999
    #: of the tuning set (55 / 44, p = 0.31), at about five times the time per decision
    tracker_speed_sigma: float = 0.0
    #: the tracker's ``samples``. Off: with 16 draws it crossed 0.749 against 0.741 on worlds 0-999 of the
    #: tuning set (38 / 30), at about five times the time per decision
    tracker_samples: int = 0
    #: the disc planner keeps a disc its map drops (an image saw through or past it, and the tracks say no
    #: new disc is its cylinder) as a *ghost*: one hypothesis per walk of :attr:`hypotheses` from where its
    #: disc was last made, those an image sees through ruled out, each of ``samples``' draws standing it at
    #: one open walk drawn from the course's motion model (:mod:`~husky_course.planners.ghosts`). Chosen on
    #: episodes, full profile, tuning worlds 7,000-8,999 (``benchmarks/exp_moving_identity.py``, won only
    #: with / only without, against the planner without ghosts, 0.838 / 0.862): ghosts ended and made by
    #: the tracks' names, 0.844 / 0.870 (12 / 6, 16 / 8); ghosts ended by any new disc over an open walk
    #: (no identity), 0.838 / 0.865 (3 / 3, 7 / 4), and 21 / 19 on 9,000-12,999. The choice was tested, as
    #: written down before the test ran, on tuning worlds 9,000-12,999 (0.844 / 0.837 / 0.855 / 0.852
    #: without): 0.849 / 0.842 / 0.858 / 0.867 (11 / 6, 14 / 9, 12 / 9, 20 / 5; pooled 57 / 29, p = 0.003)
    ghosts: bool = True
    #: steps after its disc was last made that a ghost is kept: 4 and 8 won the same worlds on tuning worlds
    #: 7,000-8,999 (``benchmarks/exp_moving_doubt_memory.py``, ghosts without identity), the tie taken by 4.
    #: With the tracks' identity (the library's ghosts; ``exp_moving_variants.py --variants
    #: settings:ghost_age=6 settings:ghost_age=8``), 6 and 8 won exactly the worlds 4 won on 7,000-8,999 (our
    #: reading, not measured: a ghost older than four steps is behind the robot, or has no walk left open).
    #: Drawn besides in every draw, cylinders that no image has ruled out, from the course's own prior
    #: (``benchmarks/exp_moving_unseen.py``): at half the course's density, 55 / 33 worlds won only with /
    #: only without on 7,000-8,999, then 51 / 46 on the test, 17,000-18,999 (p = 0.69): not shown
    ghost_age: int = 4
