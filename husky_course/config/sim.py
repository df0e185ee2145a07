"""The simulator's configuration: the course (static or moving), the camera, the primitive library.

Geometry conventions:

* world frame: ``x`` forward along the course (the robot starts at ``x = 0`` and has crossed the
  course at ``x = 10``), ``y`` to the robot's left, ``z`` up; units are metres and radians;
* a robot pose is ``(x, y, yaw)``; ``yaw = 0`` faces along ``+x``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from .sensing import SENSING, SensingConfig


class ConfigError(ValueError):
    """A configuration value, profile or world name that the course cannot use."""


@dataclass(frozen=True)
class WorldConfig:
    """The obstacle course (paper, Section 3.1.1), with the calibrated values we chose.

    The paper fixes the area (10 x 10 m), the number of cylinders (20) and their height
    (100 x robot_height); it samples positions and radii uniformly but does not print the ranges.
    The radius range below was calibrated so that the random policy survives 4.4 primitives per
    video on average, as the paper reports: :func:`husky_course.data.calibration.calibrate`
    reruns the sweep (:class:`CalibrationConfig`), chapter 2 shows it.
    """

    length: float = 10.0  #: forward extent of the course, obstacles have x in [obstacle_x_min, length]
    width: float = 10.0  #: lateral extent; side walls stand at y = +-width/2
    n_obstacles: int = 20
    robot_height: float = 0.075  #: the paper's scale constant
    obstacle_height_factor: float = 100.0  #: obstacle height = factor x robot_height = 7.5 m
    radius_range: tuple[float, float] = (0.15, 0.35)  #: uniform obstacle radius range (m)
    obstacle_x_min: float = 2.0  #: obstacles stand in x in [2, 10]: the first 2 m are a start zone
    start_half_width: float = 2.0  #: the start y is uniform in [-start_half_width, start_half_width]
    robot_radius: float = 0.45  #: the robot's collision shape: a vertical cylinder of this radius
    start_clearance: float = 0.25  #: free margin around the start disc (obstacles are redrawn)
    wall_thickness: float = 0.2
    wall_x_range: tuple[float, float] = (-10.0, 25.0)  #: walls extend beyond the course (for views)

    @property
    def obstacle_height(self) -> float:
        """Height of every cylinder and wall (m)."""
        return self.obstacle_height_factor * self.robot_height


WORLD_KINDS = ("static", "moving")


@dataclass(frozen=True)
class MovingWorldConfig(WorldConfig):
    """The moving course (chapter 10): the static course of the same seed, some cylinders walking
    across it (along ``y``), bouncing off the walls; time counts steps (:func:`.sim.world.make_world`).
    Cylinders do not collide with one another: a walker passes through a standing cylinder, or another
    walker, in its way (only the robot collides), so the course's layout never changes but by walking."""

    moving_fraction: float = 0.4
    speed_range: tuple[float, float] = (0.2, 0.6)  #: m per step; the robot advances 1 m per step


@dataclass(frozen=True)
class CameraConfig:
    """The onboard depth camera, mounted rigidly on the chassis (not on a joint).

    The camera looks straight ahead (no pitch); ``fov_deg`` is both the vertical and horizontal
    field of view (square image). Depth is the distance along the view axis (metres), clipped to
    ``[near, far]`` and normalised to ``(z - near) / (far - near)`` in [0, 1].
    """

    size: int = 50
    fov_deg: float = 130.0  #: our choice (the paper gives none); chapter 1 shows why 90 is too narrow
    near: float = 0.02
    far: float = 5.0
    mount_forward: float = 0.45  #: m ahead of the base centre, on the collision cylinder, behind the bumper
    mount_height: float = 0.40  #: m above the ground


@dataclass(frozen=True)
class PrimitiveConfig:
    """The 25-primitive library (paper, Section 2.1): smooth forward S-curves.

    Every primitive advances ``advance`` metres along the course and shifts the robot sideways by
    one of ``n`` evenly spaced offsets in ``[-lateral_spread, lateral_spread]``; it starts and ends
    at the same heading. Ten primitives cross the 10 m course.
    """

    n: int = 25
    advance: float = 1.0
    lateral_spread: float = 0.8
    samples: int = 101  #: recorded poses per primitive (chapter 1 measures their spacing)


@dataclass(frozen=True)
class SimConfig:
    """World, camera and primitive library together: everything that defines the simulator."""

    world: WorldConfig = field(default_factory=WorldConfig)
    camera: CameraConfig = field(default_factory=CameraConfig)
    primitives: PrimitiveConfig = field(default_factory=PrimitiveConfig)
    max_primitives: int = 10  #: a video (episode) ends after this many primitives
    sensing: SensingConfig = field(default_factory=SensingConfig)  #: ideal, or a real robot's (chapter 11)


def check_world_kind(kind: str) -> str:
    """Return ``kind`` if it is one of :data:`WORLD_KINDS`, else raise :class:`ConfigError`."""
    if kind not in WORLD_KINDS:
        raise ConfigError(f"unknown world {kind!r}: choose one of {', '.join(WORLD_KINDS)}")
    return kind


def world_kind(sim: SimConfig) -> str:
    """``"moving"`` if ``sim``'s world has moving obstacles, else ``"static"``."""
    return "moving" if isinstance(sim.world, MovingWorldConfig) else "static"


def world_flag(sim: SimConfig) -> str:
    """The command-line flags that select ``sim``'s course and senses (empty for the defaults, the
    static course and ideal senses; no ``--sensing`` for senses that are not a preset)."""
    flag = " --world moving" if world_kind(sim) == "moving" else ""
    preset = [name for name, cfg in SENSING.items() if cfg == sim.sensing]
    return flag + (f" --sensing {preset[0]}" if preset and preset[0] != "ideal" else "")


def sim_for_world(sim: SimConfig, kind: str) -> SimConfig:
    """``sim`` on the static or the moving course (everything else the same)."""
    if world_kind(sim) == check_world_kind(kind):
        return sim
    base = {f: getattr(sim.world, f) for f in WorldConfig.__dataclass_fields__}
    return replace(sim, world=MovingWorldConfig(**base) if kind == "moving" else WorldConfig(**base))
