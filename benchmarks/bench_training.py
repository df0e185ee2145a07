"""Training time of every model the course trains (chapters 3-8), per model and in total.

Run: ``python benchmarks/bench_training.py [--profile full] [--fresh]``.

Without ``--fresh`` it trains into the normal artifact store (``artifacts/<profile>/``) so the
book reuses the result; a model that is already there is not retrained and its time is read from
the training history stored in its checkpoint. With ``--fresh`` everything is trained in a
temporary artifact store (the dataset is copied in) and nothing is reused. Prints one line per
model (the RNN, the survival labels, the distilled planner and the memory student's DAgger rounds
included), the total, the memory student's own time against its 15-minute target, and the
validation AUC of the paper's reward net and of the joint model.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time

import numpy as np
import torch


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="full")
    parser.add_argument("--fresh", action="store_true", help="train everything in a temporary store")
    args = parser.parse_args()

    from husky_course.config import get_profile

    profile = get_profile(args.profile)
    tmp = None
    if args.fresh:
        from husky_course.data.store import dataset_dir

        src = dataset_dir(profile)
        tmp = tempfile.mkdtemp(prefix="husky-bench-")
        os.environ["HUSKY_ARTIFACTS"] = tmp
        if (src / "meta.json").is_file():
            shutil.copytree(src, dataset_dir(profile))

    from husky_course.course import diagnosis
    from husky_course.data.splits import reward_set
    from husky_course.data.store import get_dataset
    from husky_course.evaluation.metrics import classification
    from husky_course.imitation.dagger import get_memory
    from husky_course.training import builders, datasets, inference

    t0 = time.perf_counter()
    ds = get_dataset(profile)
    rows: list[tuple[str, float, str]] = [("dataset (collect or load)", time.perf_counter() - t0, "")]

    def timed(name: str, fn):
        start = time.perf_counter()
        out = fn()
        wall = time.perf_counter() - start
        hist = getattr(out, "history", None)
        trained = hist is not None and wall > 0.5 * hist.seconds
        secs = wall if trained or hist is None else hist.seconds
        note = "" if trained or hist is None else "(loaded; time from its checkpoint)"
        if hist is not None:
            note = f"{len(hist.train_loss)} epochs {note}"
        rows.append((name, secs, note))
        return out

    ed = timed("encoder + decoder", lambda: builders.get_encoder_decoder(profile))
    _, rn = timed("reward net (paper)", lambda: builders.get_reward_net(profile))
    rows[-1] = ("reward net (paper)", rn.history.seconds, f"{len(rn.history.train_loss)} epochs")
    img = timed("safety CNN, image only", lambda: builders.get_safety_net(False, profile))
    prim = timed("safety CNN, image + primitive", lambda: builders.get_safety_net(True, profile))
    joint = timed("joint model", lambda: builders.get_joint(profile))

    start = time.perf_counter()
    diagnosis.get_diagnosis(profile)  # chapter 4's 6 reward-net variants and 3 probes, one artifact
    wall = time.perf_counter() - start
    rows.append(
        ("chapter 4 variants and probes", wall, "" if wall > 1 else "(already built: --fresh times it)")
    )
    timed("RNN look-ahead", lambda: builders.get_rnn(profile))
    start = time.perf_counter()
    builders.get_survival_labels(profile)
    wall = time.perf_counter() - start
    rows.append(("simulator survival labels", wall, "" if wall > 1 else "(already built: --fresh times it)"))
    timed("distilled planner", lambda: builders.get_distilled(profile))
    start = time.perf_counter()
    student = get_memory(profile)
    memory_wall = time.perf_counter() - start
    rounds = ", ".join(f"{r['states']} states" for r in student.rounds)
    rows.append(("memory student (DAgger, all rounds)", memory_wall, f"{len(student.rounds)} rounds: {rounds}"
                 + ("" if memory_wall > 5 else " (already built: --fresh times it)")))
    rs = reward_set(ds, seed=profile.data.seed)
    images = datasets.images_tensor(ds)

    total = sum(s for name, s, _ in rows[1:])
    print(f"profile {profile.name}: {len(ds)} images, torch threads {torch.get_num_threads()}")
    for name, secs, note in rows:
        print(f"  {name:38s} {secs:8.1f} s  {note}")
    print(f"  {'total training':38s} {total:8.1f} s  = {total / 60:.1f} min")
    print(f"  memory student alone: {memory_wall / 60:.1f} min (target <= 15 min on 2 cores)")

    y = ds.labels[rs.val]
    z = inference.encode(ed.model.encoder, images[torch.from_numpy(rs.val)])
    with torch.no_grad():
        p_paper = rn.model(torch.from_numpy(z))[:, 0].numpy()
    p_joint = inference.collision_probs(joint.model, ds.images[rs.val])[
        np.arange(len(rs.val)), ds.applied[rs.val]
    ]
    d = datasets.safety_data(ds, rs.val)
    with torch.no_grad():
        p_img = torch.sigmoid(img.model.logit(d["image"])).numpy()
        p_prim = torch.sigmoid(prim.model.logit(d["image"], d["prim"])).numpy()
    for name, p in [
        ("paper reward net", p_paper),
        ("CNN image only", p_img),
        ("CNN image+prim", p_prim),
        ("joint model", p_joint),
    ]:
        c = classification(y, p)
        print(f"  {name:20s} AUC {c.auc:.3f}  accuracy {c.accuracy:.3f}  majority {c.majority:.3f}  n {c.n}")
    if tmp:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
