"""Two readings of the paper's data policy, "a policy with random weights" (Section 3.2).

The paper's data come from "a policy with random weights (used to randomly determine which
primitive to apply at each step)"; its introduction calls it "a policy based on the PAC-Bayes
framework that uses a set of random weights". The words allow two policies:

* **uniform**: every primitive is drawn independently and uniformly at random, whatever the image
  shows. This is the policy of the course's dataset
  (:func:`~husky_course.data.collect.play_video`), and the calibration of the obstacle radii
  assumes it.
* **random network**: a network with freshly drawn weights looks at each depth image and applies
  the primitive it scores highest, as the lab's PAC-Bayes planners draw a policy's weights from a
  prior and then act deterministically on the image. Our network is the paper's encoder
  (:class:`~husky_course.models.paper.Encoder`, depth image -> 15 numbers) followed by one fully
  connected layer to one score per primitive; PyTorch's default initialisation draws its weights,
  one fresh network per video, seeded by the video. The head is our choice: the paper's networks
  predict images and collision, not primitives.

:func:`policy_lengths` plays both on the same worlds (those of collection ``seed``) and returns the
primitives applied per video, the colliding one counted as in the dataset. (The module sits with
the course's analyses rather than in :mod:`husky_course.data`: it builds a network, and the data
stage comes before the models.)
"""

from __future__ import annotations

import numpy as np
import torch
from torch import Tensor, nn

from ..checks import check_int
from ..config import Profile, SimConfig, model_dims
from ..data.collect import play_video, world_seed_for
from ..models.base import check_images
from ..models.paper import Encoder
from ..sim.base import Simulator
from ..sim.fast import FastSimulator

#: videos per reading in chapter 2's comparison, by profile.  # TODO(config): move to config
POLICY_VIDEOS = {"quick": 300, "full": 2_000}
#: the policies :func:`policy_lengths` knows
POLICIES = ("uniform", "random network")
#: separates the networks' seeds from the uniform policy's ``default_rng([seed, video])``
_NETWORK_STREAM = 7


class RandomPolicyNet(nn.Module):
    """The paper's encoder and a linear head: depth image -> one score per primitive."""

    def __init__(self, config: SimConfig) -> None:
        super().__init__()
        dims = model_dims(config)
        self.encoder = Encoder(dims)
        self.head = nn.Linear(dims.latent, dims.n_primitives)

    def forward(self, images: Tensor) -> Tensor:
        """Scores ``(B, n_primitives)`` for depth images ``(B, size, size)`` in [0, 1].

        The encoder's layers run in the default memory layout: its ``channels_last`` inference path
        pays a weight reordering per new network, which a network used for one video never recovers.
        """
        x = check_images(images, self.encoder.size)
        return self.head(self.encoder.fc(self.encoder.features(x)))


def network_seed(seed: int, video: int) -> int:
    """The torch seed of video ``video``'s network in collection ``seed`` (one network per video)."""
    return int(np.random.SeedSequence([seed, video, _NETWORK_STREAM]).generate_state(1, np.uint64)[0] >> 1)


def random_network(config: SimConfig, seed: int, video: int) -> RandomPolicyNet:
    """A freshly initialised :class:`RandomPolicyNet` for one video, in evaluation mode.

    The weights are PyTorch's default initialisation under :func:`network_seed`; the global torch
    random state is left as it was.
    """
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(network_seed(seed, video))
        net = RandomPolicyNet(config)
    return net.eval()


def play_network_video(sim: Simulator, seed: int, video: int, max_primitives: int) -> np.ndarray:
    """The primitives a fresh random network applies in video ``video`` of collection ``seed``.

    Same world as :func:`~husky_course.data.collect.play_video`'s video; the network sees the depth
    image at each step and applies its highest-scoring primitive, until a collision (that
    primitive included) or ``max_primitives``. Returns the applied primitives ``(n,)``.
    """
    world = sim.load(world_seed_for(seed, video))
    net = random_network(sim.config, seed, video)
    pose, applied = world.start.copy(), []
    for step in range(max_primitives):
        image = torch.from_numpy(sim.depth(pose[None], step).astype(np.float32))
        with torch.no_grad():
            action = int(net(image)[0].argmax())
        applied.append(action)
        result = sim.apply(pose, action, step)
        if result.collided:
            break
        pose = result.pose
    return np.asarray(applied, np.int16)


def policy_lengths(
    config: SimConfig, policy: str, videos: int, seed: int
) -> tuple[np.ndarray, list[np.ndarray]]:
    """Play ``videos`` videos of ``policy`` in the worlds of collection ``seed``.

    Returns the primitives applied per video ``(videos,)`` (the colliding one counted, as in the
    dataset) and each video's applied primitives. ``"uniform"`` gives exactly the videos
    :func:`~husky_course.data.collect.collect` records for that seed.
    """
    if policy not in POLICIES:
        raise ValueError(f"unknown policy {policy!r}; choose one of {POLICIES}")
    videos = check_int(videos, "the number of videos", 1)
    world_seed_for(check_int(seed, "the collection seed", 0), videos - 1)  # range check
    sim = FastSimulator(config)
    if policy == "uniform":
        played = [
            play_video(sim, seed, v, config.max_primitives, render=False)["applied"] for v in range(videos)
        ]
    else:
        played = [play_network_video(sim, seed, v, config.max_primitives) for v in range(videos)]
    return np.array([len(p) for p in played]), played


def policy_videos(profile: Profile) -> int:
    """Videos per reading for ``profile`` (:data:`POLICY_VIDEOS`; unknown profiles get the quick number)."""
    return POLICY_VIDEOS.get(profile.name, POLICY_VIDEOS["quick"])
