"""The reference backend: PyBullet in DIRECT mode with its TinyRenderer camera.

The scene holds the ground plane, the Husky from ``pybullet_data``, two side walls and the 20
cylinders. Each cylinder's collision shape is PyBullet's exact ``GEOM_CYLINDER``; what the camera
sees is the 20-sided prism of :func:`husky_course.sim.world.obstacle_outline`, given to TinyRenderer as
an explicit mesh. PyBullet's own cylinder visual is a convex hull built from the same 20 rim points
with a 1 mm margin, and its outline changes with height (measured at the camera's height: up to
8 mm inside the prism for a 0.3 m cylinder), so a silhouette within a few hundredths of a pixel of
a sample point can land one column off; ``native_cylinders=True`` draws it anyway, for comparison.

The Husky is moved kinematically with ``resetBasePositionAndOrientation``. Its collision shape for
the course is a vertical cylinder of radius ``robot_radius`` (a collision-only body that follows
the robot during checks and is parked far below the ground otherwise); contact means
``getClosestPoints`` reports a distance <= 0 to an obstacle or a wall.

On the moving course the moving cylinders are bodies too, moved with
``resetBasePositionAndOrientation`` to where :meth:`husky_course.sim.world.World.obstacles_at` puts
them before every image (at its time) and every recorded sample of a contact check (at the sample's
time): PyBullet renders and tests the scene as it is at that moment.
"""

from __future__ import annotations

import atexit
import contextlib
import ctypes
import functools
import os
import shutil
import sys
import tempfile
from collections.abc import Iterator

import numpy as np


def _flush_c_stdio() -> None:
    """Flush the C library's stdio buffers where that library can be found (POSIX); else nothing."""
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, TypeError, AttributeError):  # Windows has no CDLL(None): nothing to flush there
        pass


@contextlib.contextmanager
def _quiet_c_stdout() -> Iterator[None]:
    """Silence the URDF importer's C-level warnings (the Husky URDF has links without inertia)."""
    try:
        sys.stdout.flush()
        fd = os.dup(1)
    except (OSError, ValueError):
        yield
        return
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), 1)
            yield
            _flush_c_stdio()  # C stdio buffers: flush them while they still go to /dev/null
    finally:
        os.dup2(fd, 1)
        os.close(fd)


with _quiet_c_stdout():  # pybullet prints its build time on import
    import pybullet as p
import pybullet_data  # noqa: E402

from ..config import SimConfig  # noqa: E402
from .base import Simulator  # noqa: E402
from .camera import camera_positions, linearize_depth_buffer, normalize_depth  # noqa: E402
from .world import World, obstacle_outline, pose_times, sample_times  # noqa: E402

_PARK = (0.0, 0.0, -100.0)


@functools.cache
def unit_prism_obj() -> str:
    """Path of a Wavefront file holding the unit obstacle prism, written once per process.

    The prism has radius 1 and height 1, centred on its mid-height: one quad (two triangles) per
    edge of :func:`~husky_course.sim.world.obstacle_outline` and triangle-fan caps, wound
    counter-clockwise seen from outside. Obstacles load it with ``meshScale = (r, r, height)``. A
    file, not ``vertices=``: PyBullet keeps every in-memory mesh after ``resetSimulation`` (about
    10 kB per obstacle, 190 MiB per 1,000 worlds), while a file is read once and shared.
    """
    ring = obstacle_outline()
    m = len(ring)
    lines = [f"v {x:.17g} {y:.17g} {z:.17g}" for z in (-0.5, 0.5) for x, y in ring]
    faces = []  # 1-based vertex numbers: 1..m the bottom ring, m+1..2m the top ring
    for k in range(m):
        a0, a1 = k + 1, (k + 1) % m + 1
        faces += [(a0, a1, a1 + m), (a0, a1 + m, a0 + m)]
    for k in range(1, m - 1):
        faces += [(m + 1, m + k + 1, m + k + 2), (1, k + 2, k + 1)]  # top, bottom
    lines += [f"f {a} {b} {c}" for a, b, c in faces]
    folder = tempfile.mkdtemp(prefix="husky_prism_")
    atexit.register(shutil.rmtree, folder, True)
    path = os.path.join(folder, "obstacle_prism.obj")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return path


class PyBulletSimulator(Simulator):
    """Simulator backed by a private PyBullet DIRECT client (closed by :meth:`close`).

    Parameters
    ----------
    config : SimConfig, optional
        World, camera and primitive settings (the defaults if omitted).
    native_cylinders : bool
        Draw obstacles with PyBullet's own ``GEOM_CYLINDER`` visual instead of the explicit
        20-sided prism mesh (see the module docstring). Collisions are the same either way.
    """

    name = "pybullet"

    def __init__(self, config: SimConfig | None = None, native_cylinders: bool = False) -> None:
        super().__init__(config)
        self.native_cylinders = native_cylinders
        with _quiet_c_stdout():  # connect prints the build time
            self.client: int | None = p.connect(p.DIRECT)
        cam = self.config.camera
        self._proj = p.computeProjectionMatrixFOV(cam.fov_deg, 1.0, cam.near, cam.far)
        self._bodies: list[int] = []
        self.husky = -1
        self.proxy = -1

    def _cid(self) -> int:
        if self.client is None:
            raise RuntimeError("this PyBullet simulator is closed")
        return self.client

    def _load(self, world: World) -> None:
        cid = self._cid()
        p.resetSimulation(physicsClientId=cid)
        p.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=cid)
        with _quiet_c_stdout():
            p.loadURDF("plane.urdf", physicsClientId=cid)
            self.husky = p.loadURDF("husky/husky.urdf", [0, 0, 0], physicsClientId=cid)
        wcfg = world.config
        height = wcfg.obstacle_height
        bodies = []
        x0, x1 = wcfg.wall_x_range
        half = np.array([(x1 - x0) / 2, wcfg.wall_thickness / 2, height / 2])
        for side in (-1.0, 1.0):
            col = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=cid)
            vis = p.createVisualShape(
                p.GEOM_BOX, halfExtents=half, rgbaColor=[0.6, 0.6, 0.65, 1], physicsClientId=cid
            )
            y = side * (world.wall_y + wcfg.wall_thickness / 2)
            bodies.append(p.createMultiBody(0, col, vis, [(x0 + x1) / 2, y, height / 2], physicsClientId=cid))
        for x, y, r in world.obstacles:
            col = p.createCollisionShape(p.GEOM_CYLINDER, radius=r, height=height, physicsClientId=cid)
            colour = [0.85, 0.45, 0.2, 1]
            if self.native_cylinders:
                vis = p.createVisualShape(
                    p.GEOM_CYLINDER, radius=r, length=height, rgbaColor=colour, physicsClientId=cid
                )
            else:
                vis = p.createVisualShape(
                    p.GEOM_MESH,
                    fileName=unit_prism_obj(),
                    meshScale=[r, r, height],
                    rgbaColor=colour,
                    physicsClientId=cid,
                )
            bodies.append(p.createMultiBody(0, col, vis, [x, y, height / 2], physicsClientId=cid))
        self._bodies = bodies
        self._placed_at: float | None = 0.0  # time the moving cylinders stand at
        col = p.createCollisionShape(
            p.GEOM_CYLINDER, radius=wcfg.robot_radius, height=0.5, physicsClientId=cid
        )
        self.proxy = p.createMultiBody(0, col, -1, _PARK, physicsClientId=cid)
        self._place_husky(world.start)

    def _place_husky(self, pose: np.ndarray) -> None:
        quat = p.getQuaternionFromEuler([0, 0, float(pose[2])])
        p.resetBasePositionAndOrientation(
            self.husky, [float(pose[0]), float(pose[1]), 0.0], quat, physicsClientId=self._cid()
        )

    def _place_obstacles(self, t: float) -> None:
        """Move the moving cylinders to where they are at time ``t`` (nothing on the static course)."""
        world = self._require_world()
        if not len(world.moving) or self._placed_at == t:
            return
        height = world.config.obstacle_height
        for i, (x, y, _) in zip(world.moving, world.obstacles_at(t)[world.moving], strict=True):
            p.resetBasePositionAndOrientation(
                self._bodies[2 + i], [x, y, height / 2], [0, 0, 0, 1], physicsClientId=self._cid()
            )
        self._placed_at = t

    def _render(self, pose: np.ndarray, flags: int = 0, t: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        cid = self._cid()
        self._require_world()
        self._place_obstacles(float(t))
        pose = np.asarray(pose, float)
        self._place_husky(pose)
        eye = camera_positions(self.config.camera, pose[None])[0]
        fwd = np.array([np.cos(pose[2]), np.sin(pose[2]), 0.0])
        view = p.computeViewMatrix(eye.tolist(), (eye + fwd).tolist(), [0, 0, 1])
        size = self.config.camera.size
        _, _, rgb, depth, _ = p.getCameraImage(
            size,
            size,
            view,
            self._proj,
            renderer=p.ER_TINY_RENDERER,
            flags=flags,
            physicsClientId=cid,
        )
        rgb = np.asarray(rgb, np.uint8).reshape(size, size, 4)[..., :3]
        depth = np.asarray(depth, np.float64).reshape(size, size)
        return rgb, depth

    def _depth(self, poses: np.ndarray, t: np.ndarray | float = 0.0) -> np.ndarray:
        poses = np.asarray(poses, float).reshape(-1, 3)
        times = pose_times(t, len(poses))
        cam = self.config.camera
        out = np.empty((len(poses), cam.size, cam.size), np.float32)
        for b, pose in enumerate(poses):
            _, buf = self._render(pose, t=float(times[b]))
            out[b] = normalize_depth(linearize_depth_buffer(buf, cam), cam)
        return out

    def rgb(self, pose: np.ndarray, t: float = 0.0) -> np.ndarray:
        return self._render(pose, t=t)[0].copy()

    def contact_along(self, path: np.ndarray, t: float = 0.0) -> int:
        cid = self._cid()
        world = self._require_world()
        path = np.asarray(path, float)
        times = sample_times(t, len(path))
        # Broad phase (conservative): only bodies whose footprint comes near the path's bounds
        # (a moving cylinder's grown by how far it can walk during the path).
        reach = world.config.robot_radius + 0.05
        lo, hi = path[:, :2].min(0) - reach, path[:, :2].max(0) + reach
        obs = world.obstacles_at(float(times[0]))
        walk = 0.0 if world.speeds is None else np.abs(world.speeds) * float(times[-1] - times[0])
        size = obs[:, 2] + walk
        near = (
            (obs[:, 0] + size >= lo[0])
            & (obs[:, 0] - size <= hi[0])
            & (obs[:, 1] + size >= lo[1])
            & (obs[:, 1] - size <= hi[1])
        )
        candidates = [self._bodies[0], self._bodies[1]] + [self._bodies[2 + i] for i in np.flatnonzero(near)]
        hit = -1
        for k, (x, y, _) in enumerate(path):
            self._place_obstacles(float(times[k]))
            p.resetBasePositionAndOrientation(self.proxy, [x, y, 0.25], [0, 0, 0, 1], physicsClientId=cid)
            if any(
                pt[8] <= 0.0
                for body in candidates
                for pt in p.getClosestPoints(self.proxy, body, 0.0, physicsClientId=cid)
            ):
                hit = k
                break
        p.resetBasePositionAndOrientation(self.proxy, _PARK, [0, 0, 0, 1], physicsClientId=cid)
        return hit

    def close(self) -> None:
        if self.client is not None:
            try:
                p.disconnect(physicsClientId=self.client)
            finally:
                self.client = None

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:
            pass
