"""The memory student's network: the current depth image and a map of everything seen so far.

Two inputs, one output per primitive:

* the current depth image through the paper's :class:`~husky_course.models.paper.Encoder` (the
  perception the course has studied since chapter 3), giving the latent;
* the egocentric occupancy map (:meth:`husky_course.planners.perception.EgoMap.raster`), a small
  image of every obstacle point seen so far in the robot's frame, through two convolutions;

concatenated and mapped to the predicted steps (out of ``horizon``) that the best continuation
starting with each primitive survives, the oracle's own survival labels. Memory lives in the map,
not in a recurrent state: the map is what lets a planner remember an obstacle beside the robot,
and it costs one small convolution per decision.

On the moving course (chapter 10) the map walks (:class:`husky_course.planners.motion.WalkingMap`:
each point carries the lateral speed inferred from successive scans) and has three more channels
(:func:`map_channels`, :data:`MOVING_INPUTS`): the map's points where they will be one step later,
where they will be when the robot reaches them, if they keep walking, and the points whose speed
is not known yet (seen by one image only), which the network learns how far to fear.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import Tensor, nn

from ..config import ModelDims, SimConfig, world_kind
from .base import DEFAULT_DIMS, make_spec, mlp
from .paper import Encoder

#: what the moving-course student's four channels hold: see
#: :meth:`husky_course.planners.memory.MemoryPlanner.prepare`
MOVING_INPUTS = (
    "walking map (tracked fitted circles, weighted line over four looks, judged against the motion "
    "model); map one step ahead; map at the robot's arrival (x / advance steps); points seen once"
)


def map_channels(sim: SimConfig) -> int:
    """Map channels the student reads: 1 (everything seen) on the static course, 4 on the moving one
    (the walking map now, one step ahead, at the robot's arrival, and its points seen only once)."""
    return 4 if world_kind(sim) == "moving" else 1


class MemoryNet(nn.Module):
    """Encoder(depth) + CNN(map) -> survival of every primitive (see the module docstring)."""

    HIDDEN = (16, 32, 64)  #: map channels, map channels, joint hidden width

    def __init__(
        self, horizon: int, map_cells: int, dims: ModelDims = DEFAULT_DIMS, channels: int = 1
    ) -> None:
        super().__init__()
        c1, c2, hidden = self.HIDDEN
        self.spec = make_spec("memory", dims, (*self.HIDDEN, map_cells, horizon, channels))
        self.horizon, self.map_cells, self.channels = int(horizon), int(map_cells), int(channels)
        self.encoder = Encoder(dims)
        self.map_net = nn.Sequential(
            nn.Conv2d(self.channels, c1, kernel_size=5, stride=2, padding=2),
            nn.ELU(),
            nn.Conv2d(c1, c2, kernel_size=3, stride=2, padding=1),
            nn.ELU(),
            nn.Flatten(),
        )
        side = (map_cells + 1) // 2
        side = (side + 1) // 2
        self.head = mlp([dims.latent + c2 * side * side, hidden, hidden, dims.n_primitives])

    def hidden(self, image: Tensor, grid: Tensor) -> Tensor:
        """What the output layer sees: the head's last hidden activations ``(B, hidden)``."""
        if grid.dim() == 3:
            grid = grid.unsqueeze(1)
        return self.head[:-1](torch.cat([self.encoder(image), self.map_net(grid.float())], dim=1))

    def logits(self, image: Tensor, grid: Tensor) -> Tensor:
        """Pre-sigmoid survival fractions ``(B, n_primitives)``."""
        return self.head[-1](self.hidden(image, grid))

    def survival(self, image: Tensor, grid: Tensor) -> Tensor:
        """Predicted steps survived ``(B, n_primitives)`` in ``[0, horizon]``."""
        return torch.sigmoid(self.logits(image, grid)) * self.horizon

    def loss(self, batch: dict[str, Tensor]) -> Tensor:
        """BCE between the predicted and the simulator's survival fraction, every primitive."""
        target = batch["survival"].float() / self.horizon
        return F.binary_cross_entropy_with_logits(self.logits(batch["image"], batch["map"]), target)


def last_layer(model: MemoryNet) -> nn.Linear:
    """The student's output layer (hidden -> one value per primitive), what the certificate randomises."""
    layer = model.head[-1]
    assert isinstance(layer, nn.Linear)
    return layer


def get_last_layer(model: MemoryNet) -> Tensor:
    """The output layer's weights then biases as one flat float32 vector (a copy)."""
    layer = last_layer(model)
    return torch.cat([layer.weight.detach().reshape(-1), layer.bias.detach()]).float().cpu().clone()


@torch.no_grad()
def set_last_layer(model: MemoryNet, w: Tensor) -> None:
    """Write a flat vector from :func:`get_last_layer` back into the output layer."""
    layer = last_layer(model)
    n_w = layer.weight.numel()
    size = n_w + layer.bias.numel()
    if w.shape != (size,):
        raise ValueError(f"expected a vector of {size} values, got shape {tuple(w.shape)}")
    layer.weight.copy_(w[:n_w].view_as(layer.weight))
    layer.bias.copy_(w[n_w:])

