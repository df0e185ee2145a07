"""How the robot senses and moves (chapter 11): ideal, as in chapters 1-10, or like a real Husky.

Two departures from the ideal simulator, both seeded (:mod:`husky_course.sim.sensing`):

* **Depth camera.** We model an active stereo depth camera of the kind mounted on Husky robots,
  the Intel RealSense D435, from its datasheet (Intel RealSense D400 Series Product Family
  Datasheet, Intel document 337029; the figures of its depth-performance table: depth RMS error
  ≤ 2% at 2 m; minimum depth 0.105 m at 848 x 480; depth in units of 1 mm; fill rate ≥ 99%).
  Stereo depth error grows with the square of the distance (it is a disparity error:
  ``dz = z**2 dd / (f b)``), so the RMS error at depth ``z`` is ``sigma_k * z**2``, with
  ``sigma_k = 0.02 * 2 / 2**2 = 0.01`` per metre: the datasheet's bound at 2 m. These pixels read
  "no reading": one closer than ``min_range``; a random share ``dropout`` (1 - fill rate); and a
  share ``edge_dropout`` of those on the far side of a depth edge (deeper than a neighbour by over
  ``edge_jump``), where stereo matching fails in the occlusion shadow (our choice: the datasheet
  gives no figure, and one of our pixels, 2.6 degrees wide, spans about 25 of the D435's at its
  87-degree, 848-pixel width). "No reading" is the course's own value for it, ``far`` (a
  normalised 1, "nothing within range"): a hole looks like open space, the danger it poses.
* **Wheels.** A skid-steered Husky's executed motion departs from the commanded one. Each
  primitive's executed path has its length scaled by ``1 + e`` (``e ~ N(0, slip_scale**2)``) and its
  heading turned gradually by ``h ~ N(0, slip_heading_deg**2)`` degrees over the primitive (our
  choice, no published Husky figure: a few percent of the distance travelled, the order of skid-steer
  odometry errors). Collisions are judged on the executed path; planners that keep a map move it by
  the primitive's nominal displacement, as a real robot's odometry would.

``ideal`` is all zeros and changes nothing (bit for bit); ``realistic`` is the figures above.
:meth:`SensingConfig.scaled` multiplies every noise figure by a factor (chapter 11's sweeps).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace


class SensingError(ValueError):
    """A sensing setting the course cannot use (a negative sigma, a rate above 1, an unknown name)."""


@dataclass(frozen=True)
class SensingConfig:
    """The depth camera's and the wheels' departures from ideal (module docstring)."""

    name: str = "ideal"
    sigma_k: float = 0.0  #: depth RMS error is sigma_k * z**2 (m, z in m)
    depth_unit: float = 0.0  #: m; depth is rounded to it (0: not rounded)
    min_range: float = 0.0  #: m; a pixel closer than this reads "no reading"
    dropout: float = 0.0  #: share of pixels that read "no reading" at random
    edge_dropout: float = 0.0  #: share of the pixels on a depth edge's far side that read "no reading"
    edge_jump: float = 0.3  #: m; a depth edge is a jump over this to a 4-neighbour
    slip_scale: float = 0.0  #: standard deviation of an executed primitive's length factor - 1
    slip_heading_deg: float = 0.0  #: standard deviation of its heading error (degrees)
    seed: int = 0  #: the sensing seed (noise is a pure function of it, the world seed, the step)

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in ("name", "seed"):
                continue
            if not isinstance(value, int | float) or not math.isfinite(value) or value < 0:
                raise SensingError(f"sensing {f.name} must be a finite number >= 0, got {value!r}")
        for rate in ("dropout", "edge_dropout"):
            if getattr(self, rate) > 1:
                raise SensingError(f"sensing {rate} must be at most 1 (a share), got {getattr(self, rate)!r}")
        if self.edge_jump <= 0:
            raise SensingError(f"sensing edge_jump must be > 0, got {self.edge_jump!r}")

    @property
    def camera_ideal(self) -> bool:
        """Whether images are exactly the renderer's."""
        return not (self.sigma_k or self.depth_unit or self.min_range or self.dropout or self.edge_dropout)

    @property
    def wheels_ideal(self) -> bool:
        """Whether every primitive is executed exactly as the library says."""
        return not (self.slip_scale or self.slip_heading_deg)

    def scaled(self, factor: float) -> SensingConfig:
        """Every noise figure times ``factor`` (rates capped at 1); ``min_range``, the depth unit
        and the edge threshold are the sensor's and stay."""
        if not math.isfinite(factor) or factor < 0:
            raise SensingError(f"a noise factor must be a finite number >= 0, got {factor!r}")
        if factor == 1:
            return self  # the same senses, the same artifacts
        return replace(
            self, name=f"{self.name} x{factor:g}", sigma_k=self.sigma_k * factor,
            dropout=min(1.0, self.dropout * factor), edge_dropout=min(1.0, self.edge_dropout * factor),
            slip_scale=self.slip_scale * factor, slip_heading_deg=self.slip_heading_deg * factor,
        )


SENSING: dict[str, SensingConfig] = {
    "ideal": SensingConfig(),
    "realistic": SensingConfig(
        name="realistic", sigma_k=0.01, depth_unit=0.001, min_range=0.105, dropout=0.01,
        edge_dropout=0.3, slip_scale=0.03, slip_heading_deg=1.5,
    ),
}


def get_sensing(name: str) -> SensingConfig:
    """The sensing preset ``name`` (``ideal`` or ``realistic``), or a clear error."""
    if name not in SENSING:
        raise SensingError(f"unknown sensing {name!r}: choose one of {', '.join(SENSING)}")
    return SENSING[name]
