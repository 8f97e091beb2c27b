"""``[[scene.meshes]]`` of scenario files: users' own mesh files and their placement.

Each entry names a mesh file (OBJ, STL, PLY, glTF/GLB; relative to the
scenario file), its radio material (or ``materials`` per named part), its
placement in the world frame W (``position_m``, ``yaw_deg``, ``pitch_deg``,
``roll_deg``: Z-Y-X Euler angles), ``scale`` (metres per file unit, e.g. 0.001
for millimetres), ``up`` (``"z"``: CAD, OBJ, STL, PLY; ``"y"``: glTF) and
``closed`` (a solid object that must be watertight). The pipeline converts
them with :func:`raysim.echoes.rt.user_meshes.convert_meshes`.
"""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, field_validator

from raysim.scenario.radar import _Section

__all__ = ["MeshSpec", "MESH_MATERIALS"]

#: Radio materials a mesh may use (the scene registry ``raysim.echoes.rt.scenes.MATERIALS``).
MESH_MATERIALS = ("asphalt-77ghz", "concrete", "dry-soil", "glass", "metal")


def _material(v: str | None) -> str | None:
    if v is not None and v not in MESH_MATERIALS:
        raise ValueError(f"a radio material, one of {', '.join(MESH_MATERIALS)}")
    return v


class MeshSpec(_Section):
    """One ``[[scene.meshes]]`` entry (see the module docstring)."""

    file: str
    material: str | None = None
    materials: dict[str, str] = Field(default_factory=dict)
    position_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    yaw_deg: float = 0.0
    pitch_deg: float = 0.0
    roll_deg: float = 0.0
    scale: float | None = Field(None, gt=0)
    up: Literal["z", "y"] = "z"
    closed: bool = False

    _one = field_validator("material")(_material)
    _parts = field_validator("materials")(
        lambda v: {k: _material(m) for k, m in v.items()})

    def placement(self) -> dict:
        """Keyword arguments of :class:`raysim.echoes.rt.user_meshes.UserMesh` (SI)."""
        return {"file": self.file, "material": self.material, "materials": dict(self.materials),
                "position_w": self.position_m, "yaw": math.radians(self.yaw_deg),
                "pitch": math.radians(self.pitch_deg), "roll": math.radians(self.roll_deg),
                "scale": self.scale, "up": self.up, "closed": self.closed}
