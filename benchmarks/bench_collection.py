"""Collection speed: the fast backend vs PyBullet, measured side by side in one run.

Run: ``python benchmarks/bench_collection.py [--videos 10000] [--ref-videos 200] [--workers 2]``.
The fast backend collects all ``--videos`` (the paper's 10,000 by default); PyBullet, whose
renderer is the bottleneck, collects ``--ref-videos`` of the same videos, and its time is
extrapolated per video. Prints seconds, videos per second and the ratio.
"""

from __future__ import annotations

import argparse
import tempfile
import time

from husky_course.config import get_profile
from husky_course.data.collect import collect
from husky_course.data.dataset import load_dataset, stats


def timed(videos: int, backend: str, workers: int) -> tuple[float, dict]:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        out = collect(
            tmp + "/d",
            get_profile("full"),
            videos=videos,
            seed=0,
            workers=workers,
            backend=backend,
            progress=False,
        )
        elapsed = time.perf_counter() - t0
        return elapsed, stats(load_dataset(out))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--videos", type=int, default=10_000)
    ap.add_argument("--ref-videos", type=int, default=200)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    t_fast, s_fast = timed(args.videos, "fast", args.workers)
    t_ref, s_ref = timed(args.ref_videos, "pybullet", args.workers)
    per_fast, per_ref = t_fast / args.videos, t_ref / args.ref_videos
    print(
        f"fast     : {args.videos:6d} videos, {s_fast['images']:6d} images in {t_fast:7.1f} s "
        f"({1 / per_fast:8.1f} videos/s); mean {s_fast['mean_primitives_per_video']:.3f} primitives/video"
    )
    print(
        f"pybullet : {args.ref_videos:6d} videos, {s_ref['images']:6d} images in {t_ref:7.1f} s "
        f"({1 / per_ref:8.1f} videos/s)"
    )
    print(f"pybullet extrapolated to {args.videos} videos: {per_ref * args.videos:.0f} s")
    print(f"ratio fast/pybullet (per video): {per_ref / per_fast:.1f}x")


if __name__ == "__main__":
    main()
