"""A Gymnasium environment: drive the Husky across the course one primitive at a time.

* action: ``Discrete(25)``, the primitive index;
* observation: the onboard 50 x 50 depth image, float32 in [0, 1];
* reward: 1 for every primitive completed without collision, 0 for the colliding one, so an
  episode's return is the number of primitives survived;
* ``terminated`` on collision, ``truncated`` after ``max_primitives`` safe primitives (the course
  is crossed);
* ``info``: ``pose`` (x, y, yaw), ``collision``, ``world_seed``, ``step``, ``world``.

``reset(seed=s)`` builds the world of seed ``s`` (any seed below ``2**31`` is a valid training
world); ``reset(options={"world_seed": w})`` picks a world without touching the RNG, and
``options={"world": "moving"}`` (or ``HuskyNavEnv(world="moving")``) switches to the moving-obstacle
course (``"static"`` back): step ``k`` is time ``k`` there (see :mod:`husky_course.sim.world`).
``HuskyNavEnv(sensing="realistic")`` or ``options={"sensing": "realistic"}`` gives the robot a real
depth camera's noise and slipping wheels (chapter 11, :mod:`husky_course.config.sensing`; a
:class:`~husky_course.config.SensingConfig` is accepted too); ``"ideal"`` is the default. ``info``
then holds ``sensing``, its name.

Importing this module registers the environment as ``HuskyNav-v0`` (:func:`husky_course.register_env`),
so ``gymnasium.make("HuskyNav-v0")`` works after it.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from .. import register_env
from ..config import (
    SensingConfig,
    SensingError,
    SimConfig,
    check_world_kind,
    get_sensing,
    sim_for_world,
    world_kind,
)
from .backends import make_simulator
from .world import check_seed


def _with_sensing(config: SimConfig, sensing: str | SensingConfig) -> SimConfig:
    chosen = get_sensing(sensing) if isinstance(sensing, str) else sensing
    if not isinstance(chosen, SensingConfig):
        raise SensingError(f"sensing must be a preset name or a SensingConfig, got {sensing!r}")
    return replace(config, sensing=chosen)


class HuskyNavEnv(gym.Env):
    """The obstacle course as a Gymnasium environment (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(
        self,
        backend: str = "fast",
        config: SimConfig | None = None,
        render_mode: str | None = "rgb_array",
        world: str | None = None,
        sensing: str | SensingConfig | None = None,
    ) -> None:
        super().__init__()
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self.backend = backend
        config = config or SimConfig()
        config = config if world is None else sim_for_world(config, world)
        self.sim = make_simulator(backend, config if sensing is None else _with_sensing(config, sensing))
        cfg = self.sim.config
        size = cfg.camera.size
        self.action_space = spaces.Discrete(self.sim.library.n)
        self.observation_space = spaces.Box(0.0, 1.0, (size, size), np.float32)
        self.max_primitives = cfg.max_primitives
        self.pose = np.zeros(3)
        self.steps = 0
        self.done = True
        self.path: list[np.ndarray] = []

    @property
    def world(self) -> str:
        """``"static"`` or ``"moving"``: the course this environment drives on."""
        return world_kind(self.sim.config)

    def _obs(self) -> np.ndarray:
        return self.sim.depth(self.pose[None], self.steps)[0]

    def _info(self, collision: bool) -> dict[str, Any]:
        assert self.sim.world is not None
        return {
            "pose": self.pose.copy(),
            "collision": collision,
            "world_seed": self.sim.world.seed,
            "step": self.steps,
            "world": self.world,
            "sensing": self.sim.config.sensing.name,
        }

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        unknown = set(options or {}) - {"world_seed", "world", "sensing"}
        if unknown:
            raise ValueError(f"unknown reset options {sorted(unknown)}: use 'world_seed', 'world', 'sensing'")
        config = self.sim.config
        if options and "world" in options:
            config = sim_for_world(config, check_world_kind(options["world"]))
        if options and "sensing" in options:
            config = _with_sensing(config, options["sensing"])
        if config != self.sim.config:
            self.sim.close()
            self.sim = make_simulator(self.backend, config)
        if options and "world_seed" in options:
            world_seed = check_seed(options["world_seed"])
        elif seed is not None:
            world_seed = check_seed(seed)
        else:
            world_seed = int(self.np_random.integers(0, 2**31))
        world = self.sim.load(world_seed)
        self.pose = world.start.copy()
        self.steps = 0
        self.done = False
        self.path = [self.pose[None].copy()]
        return self._obs(), self._info(False)

    def step(self, action: int) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if self.done:
            raise RuntimeError("episode is over: call reset() before step()")
        if not self.action_space.contains(action):
            raise ValueError(
                f"invalid action {action!r}: expected an integer in 0..{self.action_space.n - 1}"
            )
        result = self.sim.apply(self.pose, int(action), self.steps)
        self.pose = result.pose
        self.path.append(result.path)
        self.steps += 1
        terminated = result.collided
        truncated = not terminated and self.steps >= self.max_primitives
        self.done = terminated or truncated
        reward = 0.0 if terminated else 1.0
        return self._obs(), reward, terminated, truncated, self._info(terminated)

    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            return None
        if self.sim.world is None:
            raise RuntimeError("call reset() before render()")
        return self.sim.rgb(self.pose, self.steps)

    def close(self) -> None:
        self.sim.close()


register_env()  # gymnasium.make("HuskyNav-v0") works once this module is imported
