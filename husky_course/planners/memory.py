"""The memory student: a learned planner that remembers what earlier images showed.

It sees what every unprivileged planner sees (depth images, the primitives it applied, its own
library). It keeps the mapping planner's egocentric map (:class:`~husky_course.planners.perception.EgoMap`;
on the moving course a :class:`~husky_course.planners.motion.WalkingMap`, whose points carry the
velocities read off successive scans), rasterises it, and lets
:class:`~husky_course.models.memory.MemoryNet` predict how long the best continuation starting
with each primitive survives; it applies the primitive predicted to survive
longest (:func:`~husky_course.planners.base.survival_scores`). The network is trained by
:mod:`husky_course.imitation.dagger` from the oracle as a privileged teacher.
"""

from __future__ import annotations

import numpy as np
import torch

from ..config import MemoryConfig, SimConfig
from ..models.memory import MemoryNet, map_channels
from ..training.inference import model_device, single_thread
from .base import EpisodeStart, Planner, check_observation, survival_scores
from .motion import WalkingMap
from .perception import DepthScan, EgoMap, raster


class MemoryPlanner(Planner):
    """The memory student (see the module docstring).

    ``prepare`` / ``choose`` / ``observe`` split one decision so the DAgger driver can record the
    student's inputs and let the teacher act instead (round 0).
    """

    name = "memory"

    def __init__(
        self,
        model: MemoryNet | None,
        config: SimConfig | None = None,
        memory: MemoryConfig | None = None,
        smooth: int = 2,
    ) -> None:
        super().__init__()
        self.model = model.eval() if model is not None else None
        self.config, self.memory = config or SimConfig(), memory or MemoryConfig()
        cfg, mem = self.config, self.memory
        self.smooth = int(smooth)
        self.channels = map_channels(cfg)
        # the moving course's map walks (its points carry the velocities inferred from successive scans)
        walks = self.channels > 1
        self.map = WalkingMap(cfg, mem.map_behind) if walks else EgoMap(DepthScan(cfg), mem.map_behind)
        self._advance = cfg.primitives.advance  # m forward per step, whatever the primitive
        self._library = None
        self.last_input: tuple[np.ndarray, np.ndarray] | None = None

    def reset(self, start: EpisodeStart) -> None:
        super().reset(start)
        self.map.reset()
        self._library = start.library

    def prepare(self, obs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Add ``obs`` to the map; return the network's inputs ``(image, map raster)``.

        The raster is ``(cells, cells)``, or ``(4, cells, cells)`` on the moving course, where the
        map walks (:class:`~husky_course.planners.motion.WalkingMap`: every point carries the
        lateral speed inferred from successive scans, standing still until a second image has
        seen it): the map now, the map one step ahead, then each point where it will be when the
        robot reaches its forward distance ``x``: every primitive advances the same distance per
        step at a constant forward speed, so that is ``x / advance`` steps from now, and the moving
        course seen this way is a static one (up to the bounces and the cylinders' own width);
        last, the points seen by one image only, whose speed is not known yet (standing still in the
        other channels): the network learns from its labels how much room they need.
        """
        image = check_observation(obs, self.config.camera.size)
        self.map.add(image)
        m = self.memory
        cells = (m.map_cells, m.map_behind, m.map_ahead, m.map_half_width)
        grid = raster(self.map.points, *cells)
        if isinstance(self.map, WalkingMap):
            arrival = self.map.at(np.maximum(self.map.points[:, 0], 0.0) / self._advance)
            once = raster(self.map.points[self.map.fresh], *cells)
            grid = np.stack([grid, raster(self.map.at(1.0), *cells), raster(arrival, *cells), once])
        self.last_input = (image, grid)
        return self.last_input

    @torch.no_grad()
    def choose(self, image: np.ndarray, grid: np.ndarray) -> int:
        """The primitive predicted to survive longest (sets ``last_scores``)."""
        if self.model is None:
            raise RuntimeError("this MemoryPlanner has no trained network")
        with single_thread():
            dev = model_device(self.model)  # the CPU unless `evaluate --device` moved it
            x, g = torch.from_numpy(image)[None].to(dev), torch.from_numpy(grid)[None].to(dev)
            s = self.model.survival(x, g)[0].cpu().numpy()
        self.last_scores = survival_scores(s, self.smooth)
        return int(np.argmin(self.last_scores))

    def act(self, obs: np.ndarray, pose: np.ndarray | None = None) -> int:
        return self.choose(*self.prepare(obs))

    def observe(self, action: int, obs_next: np.ndarray | None) -> None:
        """Dead reckoning: move the map by the applied primitive's known displacement."""
        if self._library is None:
            raise RuntimeError("call reset(start) before observe()")
        end = self._library.local_paths[action, -1]
        self.map.move(float(end[0]), float(end[1]))
