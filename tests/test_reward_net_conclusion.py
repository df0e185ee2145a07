"""Chapter 4's conclusion, pinned on the quick profile: the faithful reward net learns, and of the
pipeline slips the chapter tries, exactly the ones named here make it fail.

The numbers come from the library functions the chapter uses (the stored reward net of
:func:`husky_course.training.builders.get_reward_net`,
:func:`husky_course.course.diagnosis.run_reward_variant` and the chapter's criterion
:func:`husky_course.course.diagnosis.failed`); the variants are trained again here (seconds each),
so a change to the code that trains them is caught, not only a stale cache.
They need the quick profile's dataset and encoder (``make test`` builds them first); a missing one is a
failure naming the command that builds it.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from husky_course.config import get_profile
from husky_course.course import diagnosis
from husky_course.data.io import DatasetError
from husky_course.data.splits import reward_set
from husky_course.data.store import load_profile_dataset
from husky_course.evaluation.metrics import classification
from husky_course.training import builders, datasets, inference
from husky_course.training.trainer import CheckpointError

QUICK = get_profile("quick")
FAILING = {"labels off by one"}  #: the slips that make the quick profile's reward net fail (chapter 4)


@pytest.fixture(scope="module")
def parts():
    try:
        ds = load_profile_dataset(QUICK)
        ed, rn = builders.load("encoder_decoder", QUICK), builders.load("reward_net", QUICK)
    except (CheckpointError, DatasetError) as exc:  # each names the command that builds what is missing
        pytest.fail(f"chapter 4's quick models are missing ({exc}); build them with "
                    "`python -m husky_course train all --profile quick`", pytrace=False)
    d = QUICK.data
    rs = reward_set(ds, d.seed, d.reward_safe_fraction, d.val_fraction)
    return ds, rs, ed.model, rn.model


def test_the_faithful_reward_net_learns(parts):
    """The chapter's first verdict: the reward net of the faithful pipeline does not fail."""
    ds, rs, ed, rn = parts
    latents = inference.encode(ed.encoder, datasets.images_tensor(ds))
    with torch.no_grad():
        p = rn(torch.from_numpy(latents[rs.val]))[:, 0].numpy()
    q = classification(ds.labels[rs.val], p)
    assert not diagnosis.failed(q), q
    assert q.auc > diagnosis.MIN_AUC + 0.15 and q.accuracy > q.majority + 0.1, q  # not a near miss


@pytest.fixture(scope="module")
def variants(parts):
    """Every variant trained as :func:`~husky_course.course.diagnosis.get_diagnosis` trains it: one torch
    thread (many small batches: more threads only contend, and the numbers are those of the store)."""
    ds, rs, ed, _ = parts
    images, threads = datasets.images_tensor(ds), torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        return [diagnosis.run_reward_variant(v, ds, rs.train, rs.val, ed.encoder, QUICK.train.reward_net,
                                             images, QUICK.sim.camera) for v in diagnosis.VARIANTS]
    finally:
        torch.set_num_threads(threads)


def test_exactly_the_named_slips_make_it_fail(variants):
    """Cause 4's verdict, retrained now: the faithful variant learns, the named slips fail, no other does."""
    faithful, *slips = variants
    assert faithful.variant == diagnosis.RewardVariant("faithful (ours)")
    assert not diagnosis.failed(faithful.quality), faithful.quality
    assert {r.variant.name for r in slips if diagnosis.failed(r.quality)} == FAILING, [
        (r.variant.name, round(r.quality.auc, 3), round(r.quality.accuracy, 3)) for r in slips]


def test_the_chapters_stored_verdict_is_the_code_of_today(variants):
    """Chapter 4 reads the variants from the artifact store: they agree with the ones trained here."""
    stored = diagnosis.get_diagnosis(QUICK, progress=False).variants
    assert [r.variant for r in stored] == [r.variant for r in variants]
    assert [diagnosis.failed(r.quality) for r in stored] == [diagnosis.failed(r.quality) for r in variants]
    np.testing.assert_allclose([r.quality.auc for r in stored], [r.quality.auc for r in variants], atol=0.01)
