"""The paper's experiments as named scenarios.

Each :class:`PaperCase` fixes the radar (Table 2), the 20 x 20 half-wavelength
virtual UPA, the platform motion, the single static target and the values the
paper reports. Motion phases are zero (every sinusoid starts at its rest
position at ``t = 0``, moving in the positive direction) and the lever arm is
:data:`DEFAULT_LEVER_ARM`; the paper states neither.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from raysim.echoes.oracle import PointTarget
from raysim.platform.motion import Trajectory, sinusoid, stationary
from raysim.radar.arrays import VirtualArray, upa
from raysim.radar.config import RadarConfig

#: Radar phase centre in the body frame [m]: 10 cm below the IMU (FRD, +Z down).
DEFAULT_LEVER_ARM = np.array([0.0, 0.0, 0.10])


@dataclass(frozen=True, eq=False)
class PaperCase:
    """One experiment of the paper.

    Attributes
    ----------
    name : str
        Identifier used on the command line.
    description : str
    config : RadarConfig
    trajectory : Trajectory
    target_range : float
        Target range from the nominal radar phase centre [m].
    target_az, target_el : float
        Target direction at the nominal attitude [rad].
    num_frames : int
        Frames accumulated (the yaw case uses 20).
    paper : dict
        Values the paper reports (pseudo-velocity m/s, widths Hz, angles deg, entropy nats).
    lever_arm : ndarray, shape ``[3]`` [m]
    """

    name: str
    description: str
    config: RadarConfig
    trajectory: Trajectory
    target_range: float
    target_az: float
    target_el: float
    num_frames: int = 1
    paper: dict = field(default_factory=dict)
    lever_arm: np.ndarray = field(default_factory=lambda: DEFAULT_LEVER_ARM.copy())

    def array(self) -> VirtualArray:
        """The 20 x 20 half-wavelength virtual UPA (x major, y minor)."""
        return upa(20, 20, wavelength=self.config.wavelength)

    def target(self) -> PointTarget:
        """The static target, placed from the nominal radar phase centre."""
        return PointTarget.at(self.target_range, self.target_az, self.target_el,
                              radar_origin=self.lever_arm)


def _deg(x: float) -> float:
    return float(np.deg2rad(x))


_R256 = RadarConfig()
_R512 = RadarConfig(num_chirps=512)

PAPER_CASES: dict[str, PaperCase] = {
    c.name: c
    for c in (
        PaperCase("stationary", "stationary platform, target 15 m, az 20, el 0", _R256,
                  stationary(), 15.0, _deg(20), 0.0),
        PaperCase("rotation_y", "pitch (about Y) 10 deg at 20 Hz, target 15 m, az 20, el 0",
                  _R256, sinusoid("pitch", _deg(10), 20.0), 15.0, _deg(20), 0.0,
                  paper={"pseudo_velocity_before": 1.037, "pseudo_velocity_after": 0.074,
                         "width_before_hz": 211.92, "width_after_hz": 154.53,
                         "width_improvement_pct": 30.4, "az_before_deg": 16.0,
                         "az_after_deg": 20.0}),
        PaperCase("yaw", "yaw 20 deg at 10 Hz, target 18 m, az 25, el 25, 20 frames",
                  _R256.with_(num_frames=20), sinusoid("yaw", _deg(20), 10.0), 18.0, _deg(25),
                  _deg(25), num_frames=20,
                  paper={"az_el_before_deg": (16.5, 31.0), "az_el_after_deg": (25.0, 25.0),
                         "entropy_before": 7.3, "entropy_after": 6.1}),
        PaperCase("translation_y", "Y translation 5 cm at 5 Hz, 512 chirps, target 15 m, "
                  "az 10, el 35", _R512, sinusoid("y", 0.05, 5.0), 15.0, _deg(10), _deg(35),
                  paper={"pseudo_velocity_before": 1.552, "pseudo_velocity_after": 0.074,
                         "width_before_hz": 120.96, "width_after_hz": 78.18,
                         "width_improvement_pct": 35.4}),
        PaperCase("translation_z", "Z translation 5 cm at 5 Hz, 512 chirps, target 15 m, "
                  "az 10, el 10", _R512, sinusoid("z", 0.05, 5.0), 15.0, _deg(10), _deg(10),
                  paper={"pseudo_velocity_before": 2.740, "pseudo_velocity_after": 0.074,
                         "width_before_hz": 171.10, "width_after_hz": 81.52,
                         "width_improvement_pct": 52.4}),
    )
}


def get_case(name: str) -> PaperCase:
    """Look up a paper case by name; raises ValueError listing the valid names."""
    try:
        return PAPER_CASES[name]
    except KeyError:
        raise ValueError(
            f"unknown paper case {name!r}; expected one of {sorted(PAPER_CASES)}"
        ) from None
