"""IMU-driven motion compensation for FMCW MIMO radar cubes.

Independent of :mod:`raysim`: inputs are plain arrays (cube, element
positions, timing, IMU samples), so recorded data can be compensated directly.
"""

__version__ = "0.1.0"
