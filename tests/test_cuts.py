"""The cut network: its features, its cut, its labels, and (quick profile, trained) that it learned.

The learning test loads the network ``make test`` trains before pytest (``train all`` builds the
disc network, then its cut network) and never trains; it reads views of worlds of a collection seed
that no training uses.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from husky_course.config import get_profile
from husky_course.data.collect import world_seed_for
from husky_course.imitation.cuts import boundary_views
from husky_course.models.cuts import CUT_FEATURES, CutNet
from husky_course.models.discs import DiscNet
from husky_course.planners.cuts import PieceCutter, cut_features
from husky_course.planners.discs import DiscMap
from husky_course.sim.fast import FastSimulator
from husky_course.sim.world import World

QUICK = get_profile("quick")


def _discs() -> DiscNet:
    torch.manual_seed(0)
    return DiscNet(QUICK.sim.world.radius_range).eval()


def _joined_world() -> World:
    """Two cylinders side by side, the right one a little behind the left: one piece of surface."""
    world = FastSimulator(QUICK.sim).load(world_seed_for(999, 0))
    cylinders = np.array([[3.0, 0.25, 0.3], [3.15, -0.37, 0.3]])
    return World(world.seed, world.config, cylinders, np.array([0.0, 0.0, 0.0]))


def _image(world: World) -> tuple[np.ndarray, np.ndarray]:
    sim = FastSimulator(QUICK.sim)
    sim.load(world)
    pose = np.zeros((1, 3))
    return sim.depth(pose)[0], sim.column_hits(pose)[1][0]


def test_the_cutter_computes_the_network_exactly():
    torch.manual_seed(0)
    model = CutNet().eval()
    x = np.random.default_rng(0).normal(size=(7, CUT_FEATURES))
    with torch.no_grad():
        expected = model(torch.from_numpy(x).float()).numpy()
    np.testing.assert_allclose(PieceCutter(model, 0.5).forward(x)[:, 0], expected, atol=1e-5)


def test_every_boundary_of_every_piece_gets_features():
    reader = DiscMap(_discs(), QUICK.sim)
    image, _ = _image(_joined_world())
    d, cols, pts, pieces = reader.reader.pieces(image)
    feats, piece, at = cut_features(reader, d, cols, pts, pieces)
    assert feats.shape == (sum(len(p) - 1 for p in pieces), CUT_FEATURES) and np.isfinite(feats).all()
    for k, p in enumerate(pieces):
        assert at[piece == k].tolist() == list(range(len(p) - 1))


def test_the_two_cylinders_join_and_the_label_marks_where_they_meet():
    """The planner's cut leaves the two cylinders in one piece; exactly one boundary of it is labelled a
    cut, between the last column of one cylinder and the first of the other."""
    reader = DiscMap(_discs(), QUICK.sim)
    image, kind = _image(_joined_world())
    d, cols, pts, pieces = reader.reader.pieces(image)
    joined = [p for p in pieces if len(set(kind[cols[p]].tolist()) & {2, 3}) == 2]
    assert len(joined) == 1
    hits = kind[cols[joined[0]]]
    assert (np.diff(hits) != 0).sum() == 1


def test_a_cutter_that_cuts_everywhere_leaves_single_points_and_one_that_never_cuts_leaves_the_pieces():
    reader = DiscMap(_discs(), QUICK.sim)
    image, _ = _image(_joined_world())
    d, cols, pts, pieces = reader.reader.pieces(image)
    model = CutNet().eval()
    with torch.no_grad():
        model.net[-1].weight.zero_()
        model.net[-1].bias.fill_(50.0)
    everywhere = PieceCutter(model, 0.5)(reader, d, cols, pts, pieces)
    assert sorted(np.concatenate(everywhere).tolist()) == sorted(np.concatenate(pieces).tolist())
    assert all(len(p) == 1 for p in everywhere)
    with torch.no_grad():
        model.net[-1].bias.fill_(-50.0)
    assert PieceCutter(model, 0.5)(reader, d, cols, pts, pieces) is pieces
    reader.cutter = PieceCutter(model, 0.5)
    assert [p.tolist() for p in reader.pieces(image)[3]] == [p.tolist() for p in pieces]


def test_bad_cut_thresholds():
    for bad in (0.0, 1.0, -0.2):
        with pytest.raises(ValueError, match="probability"):
            PieceCutter(CutNet(), bad)


def test_the_trained_cut_network_finds_where_two_cylinders_meet():
    """On views of 60 worlds no training used, at the profile's threshold: most cuts it makes are where
    two cylinders meet, and it finds a good share of them, where the pieces' boundaries hold about one
    such place in 80."""
    from husky_course.training.cuts import load_cuts
    from husky_course.training.discs import load_discs

    try:
        cuts, discs = load_cuts(QUICK)[0], load_discs(QUICK)[0]
    except Exception as exc:  # noqa: BLE001 - a missing network fails, naming the command that trains it
        pytest.fail(f"the quick profile's cut network is missing ({exc}); run `make test`", pytrace=False)
    from dataclasses import replace

    held_out = replace(QUICK, discs=replace(QUICK.discs, collection_seed=1234, worlds=60))
    data = boundary_views(held_out, discs, progress=False)
    cutter = PieceCutter(cuts, QUICK.discs.cut)
    found = cutter.forward(data["features"].astype(np.float64))[:, 0] > cutter.logit
    truth = data["cut"]
    assert truth.mean() < 0.05
    precision, recall = (found & truth).sum() / max(found.sum(), 1), (found & truth).sum() / truth.sum()
    assert precision > 0.5 and recall > 0.3, (precision, recall)


def test_the_moving_disc_planner_cuts_and_the_static_one_does_not():
    """``DiscConfig.cut`` on the moving course; none on the static course (its module's measurements),
    unless asked for; ``cut=0`` turns it off."""
    import checkpoints

    from husky_course.config import with_world
    from husky_course.planners.registry import make_planner

    moving = with_world(QUICK, "moving")
    checkpoints.trained("discs")  # a missing network fails, naming the command that trains it
    on_moving = make_planner("discs", profile=QUICK, config=moving.sim)
    assert isinstance(on_moving.map.cutter, PieceCutter)
    assert np.isclose(on_moving.map.cutter.logit, np.log(QUICK.discs.cut / (1 - QUICK.discs.cut)))
    assert make_planner("discs", profile=QUICK).map.cutter is None
    assert make_planner("discs", profile=QUICK, cut=0.5).map.cutter is not None
    assert make_planner("discs", profile=QUICK, config=moving.sim, cut=0).map.cutter is None
