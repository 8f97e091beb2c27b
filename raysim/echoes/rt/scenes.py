"""Canonical ray-tracing scenes and the radio materials they use at 77 GHz.

Scenes ship inside the package, in ``raysim/data/scenes/`` (Mitsuba XML + PLY
meshes + a JSON sidecar, written by ``raysim/data/scenes/generate.py``; the
repository's ``scenes/`` is a link to that folder), so a wheel installed
anywhere finds them. Each is exposed as a named
constant (a :class:`SceneDescriptor`, like ``sionna.rt.scene.*``) and in the
registry :data:`SCENES`; :func:`load_scene` turns a name, descriptor or XML
path into a :class:`RadarScene` ready for tracing.

Frames
------
Scene files use frame S, east-north-up (ENU) with the ground at ``z = 0``,
which is what Sionna's previewer and the usual scene tools expect. The
simulator's world frame W is north-east-down (NED) with its origin at the
radar's nominal hover point (docs/conventions.md). With the hover point at
``h_S = (0, 0, hover_altitude)`` in S::

    p_S = M p_W + h_S,    p_W = M (p_S - h_S),    M = [[0, 1, 0], [1, 0, 0], [0, 0, -1]]

``M`` is a proper rotation (det +1) and its own inverse; velocities map with
``M`` alone.

Materials
---------
Sionna's ITU-R P.2040 materials that are defined at 77 GHz are used for metal,
concrete and glass. The ITU ground types (and brick, asphalt) are not defined
above 10-40 GHz, so the ground gets custom materials, :data:`DRY_SOIL` and
:data:`ASPHALT`, with W-band values from the literature (see their docstrings).
Sionna models every surface as a slab of the given thickness; the ground slabs
are thick and lossy enough (attenuation > 40 Np/m) that their reflection
equals the half-space Fresnel coefficient.

Checks before loading
---------------------
:func:`load_scene` runs :func:`check_scene_file` before Mitsuba parses a file,
so a bad scene fails with a :class:`ValueError` naming the file instead of a
Mitsuba error: every ``ply``/``obj`` mesh must exist, be readable, have faces,
finite vertices, face indices inside the vertex list and no edge shared by
more than two faces (non-manifold). Open surfaces (a ground sheet, a facade)
are accepted: Sionna models each surface as a slab, so meshes need not be
watertight. Every ITU material must be defined at the carrier frequency.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

#: Rotation between the scene frame S (ENU) and the world frame W (NED); its own inverse.
ENU_FROM_NED = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])

#: Folder holding the generated scenes (override with ``RAYSIM_SCENES_DIR``).
SCENES_DIR = Path(os.environ.get("RAYSIM_SCENES_DIR",
                                 Path(__file__).resolve().parents[2] / "data" / "scenes"))


# --------------------------------------------------------------------------- materials
@dataclass(frozen=True)
class MaterialSpec:
    """Radio material parameters at the radar carrier, independent of any backend.

    Attributes
    ----------
    name : str
        Material id in the XML (shares Sionna's namespace with object names).
    itu_type : str or None
        ITU-R P.2040 material type for Sionna's ``ITURadioMaterial``; ``None``
        for a custom ``RadioMaterial`` given by ``relative_permittivity`` and
        ``conductivity``.
    relative_permittivity : float
        Real relative permittivity ``eps_r'`` (custom materials).
    conductivity : float
        Conductivity ``sigma`` [S/m] (custom materials); ``eps_r'' = sigma / (omega eps_0)``.
    thickness : float
        Slab thickness [m].
    scattering_coefficient : float
        Share ``S`` of the reflected field amplitude that is scattered diffusely
        (Lambertian), in [0, 1].
    xpd_coefficient : float
        Cross-polarisation discrimination ``K_x`` of the diffuse part, in [0, 1].
    color : tuple of float
        RGB for previews.
    """

    name: str
    itu_type: str | None = None
    relative_permittivity: float = 1.0
    conductivity: float = 0.0
    thickness: float = 0.1
    scattering_coefficient: float = 0.0
    xpd_coefficient: float = 0.0
    color: tuple[float, float, float] = (0.5, 0.5, 0.5)

    def __post_init__(self) -> None:
        if self.itu_type is None and self.relative_permittivity < 1.0:
            raise ValueError(
                f"relative_permittivity must be >= 1, got {self.relative_permittivity!r}")
        if self.conductivity < 0:
            raise ValueError(f"conductivity must be >= 0 S/m, got {self.conductivity!r}")
        if self.thickness <= 0:
            raise ValueError(f"thickness must be > 0 m, got {self.thickness!r}")
        for name in ("scattering_coefficient", "xpd_coefficient"):
            v = getattr(self, name)
            if not 0.0 <= v <= 1.0:
                raise ValueError(f"{name} must lie in [0, 1], got {v!r}")

    def complex_permittivity(self, frequency: float) -> complex:
        """Complex relative permittivity ``eps_r' - j sigma / (2 pi f eps_0)`` (custom only)."""
        if self.itu_type is not None:
            raise ValueError(f"material {self.name!r} is ITU type {self.itu_type!r}; ask "
                             "Sionna's itu_material() for its parameters")
        eps0 = 8.8541878128e-12
        return complex(self.relative_permittivity,
                       -self.conductivity / (2 * math.pi * frequency * eps0))

    def to_xml(self) -> str:
        """Mitsuba ``<bsdf>`` element for this material."""
        if self.itu_type is not None:
            head = f'    <bsdf type="itu-radio-material" id="{self.name}">\n'
            body = f'        <string name="type" value="{self.itu_type}"/>\n'
        else:
            head = f'    <bsdf type="radio-material" id="{self.name}">\n'
            body = (f'        <float name="relative_permittivity" '
                    f'value="{self.relative_permittivity}"/>\n'
                    f'        <float name="conductivity" value="{self.conductivity}"/>\n')
        body += (f'        <float name="thickness" value="{self.thickness}"/>\n'
                 f'        <float name="scattering_coefficient" '
                 f'value="{self.scattering_coefficient}"/>\n'
                 f'        <float name="xpd_coefficient" value="{self.xpd_coefficient}"/>\n'
                 f'        <rgb name="color" value="{" ".join(f"{c:g}" for c in self.color)}"/>\n')
        return head + body + "    </bsdf>\n"


DRY_SOIL = MaterialSpec("dry-soil", relative_permittivity=3.0, conductivity=0.43,
                        thickness=1.0, scattering_coefficient=0.5,
                        color=(0.55, 0.45, 0.30))
"""Dry sandy/loamy soil at 77 GHz: ``eps_r = 3.0 - j 0.10``.

Dry soils at 35-94 GHz measure ``eps_r' = 2.5-3.5`` and ``eps_r'' = 0.05-0.3``
(Ulaby, Moore & Fung, *Microwave Remote Sensing* Vol. III, App. E; Hallikainen
et al., IEEE TGRS 23(1), 1985, extrapolated). ``eps_r'' = 0.10`` at 77 GHz is a
conductivity ``sigma = eps_r'' omega eps_0 = 0.43 S/m``. Roughness: a few
millimetres RMS height (``k s ~ 1-3`` at 77 GHz), so a large diffuse share
``S = 0.5`` (Lambertian). Normal-incidence Fresnel reflection ``|Gamma| = -11.4 dB``;
Sionna keeps ``sqrt(1 - S^2)`` of the reflected amplitude specular (-1.25 dB).
"""

ASPHALT = MaterialSpec("asphalt-77ghz", relative_permittivity=3.18, conductivity=0.43,
                       thickness=0.5, scattering_coefficient=0.3,
                       color=(0.25, 0.25, 0.27))
"""Dry asphalt road surface at 77 GHz: ``eps_r = 3.18 - j 0.10``.

From W-band road-surface measurements (Sarabandi, Li & Nashashibi, "Modeling
and measurements of scattering from road surfaces at millimeter-wave
frequencies", IEEE TAP 45(11), 1997: ``eps_r ~ 3.18 - j 0.1`` at 94 GHz),
``sigma = 0.43 S/m`` at 77 GHz. RMS height about 0.5-1 mm (``k s ~ 0.8-1.6``)
gives a moderate diffuse share ``S = 0.3``. Normal-incidence Fresnel
reflection ``|Gamma| = -11.0 dB``; Sionna keeps ``sqrt(1 - S^2)`` of it specular.
"""

METAL = MaterialSpec("metal", itu_type="metal", thickness=0.01, scattering_coefficient=0.2,
                     color=(0.7, 0.7, 0.75))
"""ITU-R P.2040 metal (``sigma = 1e7 S/m``, valid 1-100 GHz) with ``S = 0.2``.

Used for car bodies and the lamp post. Flat metal facets give no specular
backscatter between co-located radios unless they face the radar exactly, so
their diffuse share and separate scattering centres carry the return.
"""

CONCRETE = MaterialSpec("concrete", itu_type="concrete", thickness=0.3,
                        scattering_coefficient=0.3, color=(0.6, 0.6, 0.6))
"""ITU-R P.2040 concrete (``eps_r' = 5.24``, ``sigma = 0.0462 f_GHz^0.7822``, valid 1-100 GHz)."""

GLASS = MaterialSpec("glass", itu_type="glass", thickness=0.01, scattering_coefficient=0.0,
                     color=(0.6, 0.8, 0.9))
"""ITU-R P.2040 glass (``eps_r' = 6.31``, ``sigma = 0.0036 f_GHz^1.3394``, valid 0.1-100 GHz)."""

RUBBER = MaterialSpec("rubber", relative_permittivity=3.0, conductivity=0.6, thickness=0.02,
                      color=(0.1, 0.1, 0.1))
"""Tyre rubber at 77 GHz: ``eps_r = 3.0 - j 0.14`` (loss tangent 0.05), an assumed value
typical of carbon-black-filled elastomers at W band; used for the cars' tyres."""

PLASTIC = MaterialSpec("plastic", relative_permittivity=2.3, conductivity=0.005, thickness=0.003,
                       color=(0.15, 0.15, 0.15))
"""Polypropylene-like car plastic at 77 GHz: ``eps_r = 2.3 - j 0.0012`` (loss tangent 5e-4),
an assumed value typical of unfilled polyolefins at W band; normal-incidence Fresnel
reflection ``|Gamma| = -13.8 dB``. Used for the sedan's grille ducts and lamp housings."""

#: Every material above by name.
MATERIALS = {m.name: m for m in (DRY_SOIL, ASPHALT, METAL, CONCRETE, GLASS, RUBBER, PLASTIC)}


# ----------------------------------------------------------------------------- targets
@dataclass(frozen=True)
class SceneTarget:
    """A discrete target: a constant-RCS point, or a geometry target traced by PO + SBR.

    Without ``mesh`` the target is a constant-RCS point scatterer (Sionna
    ``ConstantRCSSensingTarget``-like). With ``mesh`` it is a scene object whose
    return the tracer computes from its geometry (:mod:`raysim.echoes.po.paths`);
    ``position`` is then its reference point (phase centre) and ``rcs_dbsm``
    its nominal RCS (closed form), kept for reports and checks only.

    Attributes
    ----------
    name : str
        Unique object name.
    position : ndarray, shape ``[3]``
        Scattering-point position in the world frame W (NED) [m].
    rcs_dbsm : float
        Monostatic radar cross-section [dBsm].
    velocity : ndarray, shape ``[3]``
        Constant velocity in W [m/s].
    size : float
        Edge of the cube that represents the target for occlusion [m].
    mesh : str, tuple of str, or None
        Mesh file(s) of a geometry target (frame S, as in the scene XML), or
        ``None``; several files are parts traced together.
    material : str or tuple of str
        Scene material of a geometry target's mesh, or one per part.
    min_bounces : int
        Smallest bounce count traced for a geometry target: 2 keeps only its
        multiple bounces, for surfaces whose single bounce Sionna already traces.
    diffraction : bool
        Add the edge diffraction (PTD fringe wave) of a geometry target's sharp
        edges (scene metadata key ``"diffraction"``, default false).
    """

    name: str
    position: np.ndarray
    rcs_dbsm: float = 10.0
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    size: float = 0.2
    mesh: str | tuple[str, ...] | None = None
    material: str | tuple[str, ...] = "metal"
    min_bounces: int = 1
    diffraction: bool = False

    @property
    def is_geometry(self) -> bool:
        """Whether the tracer computes this target from its mesh."""
        return self.mesh is not None

    def __post_init__(self) -> None:
        for attr in ("position", "velocity"):
            v = np.asarray(getattr(self, attr), dtype=float)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise ValueError(f"target {self.name!r}: {attr} must be 3 finite numbers, "
                                 f"got {getattr(self, attr)!r}")
            object.__setattr__(self, attr, v)
        if not math.isfinite(self.rcs_dbsm):
            raise ValueError(f"target {self.name!r}: rcs_dbsm must be finite, "
                             f"got {self.rcs_dbsm!r}")
        if not self.size > 0:
            raise ValueError(f"target {self.name!r}: size must be > 0 m, got {self.size!r}")
        if self.min_bounces not in (1, 2, 3):
            raise ValueError(f"target {self.name!r}: min_bounces must be 1, 2 or 3, "
                             f"got {self.min_bounces!r}")
        if not isinstance(self.diffraction, (bool, np.bool_)):
            raise ValueError(f"target {self.name!r}: diffraction must be true or false, "
                             f"got {self.diffraction!r}")


# ------------------------------------------------------------------------------ scenes
@dataclass(frozen=True)
class SceneDescriptor:
    """A scene on disk.

    Attributes
    ----------
    name : str
        Registry name.
    path : pathlib.Path
        Mitsuba XML file.
    description : str
        One line on what the scene holds.
    """

    name: str
    path: Path
    description: str = ""

    @property
    def sidecar(self) -> Path:
        """JSON sidecar with hover altitude, targets and materials."""
        return self.path.with_suffix(".json")

    def metadata(self) -> dict:
        """Sidecar contents (empty dict when the scene has none)."""
        return json.loads(self.sidecar.read_text()) if self.sidecar.exists() else {}


def _descriptor(name: str, description: str) -> SceneDescriptor:
    return SceneDescriptor(name, SCENES_DIR / name / f"{name}.xml", description)


FLAT_REFLECTORS = _descriptor(
    "flat_reflectors", "flat dry-soil ground 100 m x 100 m, four trihedral reflector meshes")
"""Flat dry-soil ground (100 m x 100 m, 200 triangles) and four metal trihedral
corner reflectors (meshes of edge 0.10-0.20 m traced by PO + SBR, closed-form
RCS 14.4-26.5 dBsm, aimed at the hover point) 0-25 m from nadir. Hover
altitude 15 m. For amplitude and geometry calibration."""

PARKING_LOT = _descriptor(
    "parking_lot", "asphalt lot, six car meshes, concrete/glass facade, lamp post")
"""Asphalt ground 100 m x 100 m, six car meshes (traced by PO + SBR), a 40 m x
12 m concrete facade with glass windows 30 m north of the hover point (its
dihedral with the ground traced by SBR over the facade base and an apron) and a
6 m metal lamp post. Hover altitude 15 m."""

ROUGH_TERRAIN = _descriptor(
    "rough_terrain", "dry-soil height map 80 m x 80 m, 0.4 m RMS")
"""Gaussian random height map (80 m x 80 m, 3,200 triangles, 0.4 m RMS height,
6 m correlation length, seed 11) of dry soil, no discrete targets. Hover
altitude 15 m. Distributed clutter only."""

#: Registry of the canonical scenes, name -> descriptor.
SCENES: dict[str, SceneDescriptor] = {d.name: d for d in (FLAT_REFLECTORS, PARKING_LOT,
                                                           ROUGH_TERRAIN)}


def get_scene(scene: str | os.PathLike | SceneDescriptor) -> SceneDescriptor:
    """Resolve a registry name, descriptor or XML path to a :class:`SceneDescriptor`.

    Raises
    ------
    ValueError
        For a name that is neither registered nor an existing ``.xml`` file; the
        message lists the valid names.
    """
    if isinstance(scene, SceneDescriptor):
        return scene
    text = os.fspath(scene)
    if text in SCENES:
        return SCENES[text]
    path = Path(text)
    if path.suffix == ".xml" and path.exists():
        return SceneDescriptor(path.stem, path.resolve(), "scene file")
    raise ValueError(
        f"unknown scene {text!r}: expected one of {', '.join(sorted(SCENES))} or the path of "
        f"an existing Mitsuba .xml file"
    )


@dataclass(eq=False)
class RadarScene:
    """A loaded Sionna scene placed in the world frame, plus its discrete targets.

    Attributes
    ----------
    descriptor : SceneDescriptor
    sionna_scene : sionna.rt.Scene
        The loaded scene (frame S, ENU); radios and targets are added by the tracer.
    hover_altitude : float
        Height of the world origin (nominal hover point) above the scene's
        ``z = 0`` [m].
    targets : list of SceneTarget
        Constant-RCS targets, positions and velocities in W.
    """

    descriptor: SceneDescriptor
    sionna_scene: object
    hover_altitude: float
    targets: list[SceneTarget]

    @property
    def name(self) -> str:
        """Scene name."""
        return self.descriptor.name

    @property
    def hover_point_scene(self) -> np.ndarray:
        """World origin in frame S, shape ``[3]`` [m]."""
        return np.array([0.0, 0.0, self.hover_altitude])

    def to_scene(self, p_world: np.ndarray) -> np.ndarray:
        """World (NED) points ``[..., 3]`` to scene (ENU) points [m]."""
        return np.asarray(p_world, dtype=float) @ ENU_FROM_NED.T + self.hover_point_scene

    def to_world(self, p_scene: np.ndarray) -> np.ndarray:
        """Scene (ENU) points ``[..., 3]`` to world (NED) points [m]."""
        return (np.asarray(p_scene, dtype=float) - self.hover_point_scene) @ ENU_FROM_NED.T

    def vector_to_scene(self, v_world: np.ndarray) -> np.ndarray:
        """Rotate world vectors ``[..., 3]`` (velocities, directions) into S."""
        return np.asarray(v_world, dtype=float) @ ENU_FROM_NED.T


# ---------------------------------------------------------------------- scene checks
#: Mitsuba shape plugins whose ``filename`` is a mesh that :func:`check_scene_file` reads.
MESH_SHAPE_TYPES = ("ply", "obj")


def _scene_xml(path: Path):
    """Parsed XML root of a scene file, with its ``<default>`` parameters."""
    import xml.etree.ElementTree as ET

    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError) as exc:
        raise ValueError(f"scene file {str(path)!r} is not readable Mitsuba XML: {exc}") from None
    defaults = {d.get("name"): d.get("value", "") for d in root.iter("default")}
    return root, defaults


def _substitute(value: str, defaults: dict) -> str:
    for name, v in defaults.items():
        value = value.replace(f"${name}", v)
    return value


def check_mesh(path: str | os.PathLike, *, scene_file: str | os.PathLike | None = None) -> int:
    """Check one mesh file before Mitsuba loads it.

    Parameters
    ----------
    path : path-like
        ``.ply`` or ``.obj`` mesh.
    scene_file : path-like, optional
        XML file that references the mesh (named in the error messages).

    Returns
    -------
    int
        Number of triangles.

    Raises
    ------
    ValueError
        If the file is missing or unreadable, has no faces, has non-finite
        vertices, face indices beyond its vertex list, or edges shared by more
        than two faces (non-manifold). The message names the mesh file.
    """
    import trimesh

    path = Path(path)
    where = f" (referenced by {str(scene_file)!r})" if scene_file is not None else ""
    if not path.is_file():
        raise ValueError(f"mesh file {str(path)!r}{where} does not exist")
    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many types for a bad file
        raise ValueError(f"mesh file {str(path)!r}{where} is not a readable mesh: "
                         f"{type(exc).__name__}: {exc}") from None
    vertices = np.asarray(mesh.vertices, dtype=float)
    faces = np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 3)
    if faces.shape[0] == 0:
        raise ValueError(f"{path.name}: no faces; mesh file {str(path)!r}{where} has "
                         f"{vertices.shape[0]} vertices and 0 faces, expected at least one "
                         f"triangle (remove the shape or fix the export)")
    bad = ~np.all(np.isfinite(vertices), axis=1)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{path.name}: {int(bad.sum())} of {vertices.shape[0]} vertices are not "
                         f"finite (first: vertex {first} = {vertices[first].tolist()}) in mesh "
                         f"file {str(path)!r}{where}; expected finite coordinates in metres")
    if faces.min() < 0 or faces.max() >= vertices.shape[0]:
        raise ValueError(f"{path.name}: face indices span [{int(faces.min())}, "
                         f"{int(faces.max())}] in mesh file {str(path)!r}{where}, expected "
                         f"[0, {vertices.shape[0] - 1}] ({vertices.shape[0]} vertices)")
    edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    keys, counts = np.unique(edges[:, 0] * vertices.shape[0] + edges[:, 1], return_counts=True)
    over = counts > 2
    if over.any():
        k = int(keys[np.argmax(over)])
        edge = (k // vertices.shape[0], k % vertices.shape[0])
        raise ValueError(f"{path.name}: non-manifold mesh, {int(over.sum())} edge(s) shared by "
                         f"more than two faces (first: vertices {edge}, {int(counts.max())} "
                         f"faces) in mesh file {str(path)!r}{where}; expected each edge in at "
                         f"most two faces (split the mesh into separate shapes)")
    return int(faces.shape[0])


def _itu_types(root, defaults: dict) -> list[tuple[str, str]]:
    """``(bsdf id, ITU type)`` of every ``itu-radio-material`` in the scene XML."""
    out = []
    for bsdf in root.iter("bsdf"):
        if bsdf.get("type") != "itu-radio-material":
            continue
        for child in bsdf.findall("string"):
            if child.get("name") == "type":
                out.append((bsdf.get("id", "?"), _substitute(child.get("value", ""), defaults)))
    return out


def itu_materials_at(frequency: float) -> list[str]:
    """Sionna's ITU-R P.2040 material types defined at ``frequency`` [Hz]."""
    from sionna.rt.radio_materials.itu import ITU_MATERIALS_PROPERTIES

    f_ghz = float(frequency) / 1e9
    return [name for name, ranges in ITU_MATERIALS_PROPERTIES.items()
            if any(lo <= f_ghz <= hi for lo, hi in ranges)]


def _check_itu_materials(path: Path, root, defaults: dict, frequency: float) -> None:
    from sionna.rt.radio_materials.itu import ITU_MATERIALS_PROPERTIES

    defined = itu_materials_at(frequency)
    for bsdf_id, itu in _itu_types(root, defaults):
        if "$" in itu:
            continue  # left to Mitsuba: a parameter without a default
        if itu not in ITU_MATERIALS_PROPERTIES:
            raise ValueError(
                f"scene file {str(path)!r}: material {bsdf_id!r} has unknown ITU type {itu!r}; "
                f"expected one of {', '.join(ITU_MATERIALS_PROPERTIES)}")
        if itu not in defined:
            ranges = ", ".join(f"{lo:g}-{hi:g} GHz" for lo, hi in ITU_MATERIALS_PROPERTIES[itu])
            raise ValueError(
                f"scene file {str(path)!r}: ITU material {itu!r} (bsdf {bsdf_id!r}) is not "
                f"defined at the carrier frequency {frequency / 1e9:g} GHz (defined at "
                f"{ranges}); ITU materials defined at {frequency / 1e9:g} GHz: "
                f"{', '.join(defined) or 'none'}. For ground use a custom radio-material "
                f"(relative_permittivity, conductivity), e.g. raysim.echoes.rt.scenes.DRY_SOIL")


def check_scene_file(path: str | os.PathLike, *, frequency: float | None = None) -> int:
    """Check a Mitsuba XML scene and its meshes before Mitsuba loads them.

    Parameters
    ----------
    path : path-like
        Scene XML; mesh ``filename`` values are relative to its folder.
    frequency : float, optional
        Carrier frequency [Hz]; when given, every ITU material must be
        defined at it (imports Sionna RT).

    Returns
    -------
    int
        Number of triangles of all checked meshes.

    Raises
    ------
    ValueError
        Unreadable XML, a bad mesh (see :func:`check_mesh`) or an ITU material
        undefined at ``frequency``; the message names the file.
    """
    path = Path(path)
    root, defaults = _scene_xml(path)
    total = 0
    for shape in root.iter("shape"):
        if shape.get("type") not in MESH_SHAPE_TYPES:
            continue
        for child in shape.findall("string"):
            if child.get("name") != "filename":
                continue
            name = _substitute(child.get("value", ""), defaults)
            if "$" not in name:
                total += check_mesh(path.parent / name, scene_file=path)
    if frequency is not None:
        _check_itu_materials(path, root, defaults, float(frequency))
    return total


def drop_geometry_shapes(sionna_scene, descriptor: SceneDescriptor) -> list[str]:
    """Remove the shapes of the sidecar's geometry targets from a loaded Sionna scene.

    Geometry targets are traced by PO + SBR (:mod:`raysim.echoes.po.paths`), not by
    Sionna's geometric optics, so that nothing is counted twice. Returns the removed names.
    """
    shapes = []
    for t in descriptor.metadata().get("targets", []):
        shape = t.get("shape")
        shapes += [] if not shape else [shape] if isinstance(shape, str) else list(shape)
    present = [n for n in shapes if n in sionna_scene.objects]
    if present:
        sionna_scene.edit(remove=present)
    return present


def load_scene(scene: str | os.PathLike | SceneDescriptor = "flat_reflectors", *,
               frequency: float = 77e9, hover_altitude: float | None = None,
               targets: list[SceneTarget] | None = None, extra_targets=(),
               include_targets: bool = True) -> RadarScene:
    """Load a scene for tracing.

    Parameters
    ----------
    scene : str, path-like or SceneDescriptor
        Registry name (see :data:`SCENES`), descriptor, or XML path.
    frequency : float
        Carrier frequency [Hz]; ITU materials are evaluated at it.
    hover_altitude : float, optional
        Nominal radar height above ground [m]; default from the sidecar (15 m
        when there is none).
    targets : list of SceneTarget, optional
        Replace the sidecar's targets (positions in W).
    extra_targets : sequence of SceneTarget
        Added to the sidecar's (or ``targets``) list.
    include_targets : bool
        Drop all discrete targets when False.

    Returns
    -------
    RadarScene

    Raises
    ------
    ValueError
        Unknown scene name, missing scene file (run ``python raysim/data/scenes/generate.py``),
        a non-positive frequency or hover altitude, a bad mesh or an ITU material
        undefined at ``frequency`` (see :func:`check_scene_file`).
    """
    from raysim.echoes.rt.backend import sionna_rt

    desc = get_scene(scene)
    if not desc.path.exists():
        raise ValueError(f"scene file {desc.path} is missing; run "
                         f"`python {SCENES_DIR / 'generate.py'}`")
    try:
        f_hz = float(frequency)
    except (TypeError, ValueError):
        f_hz = math.nan
    if not (math.isfinite(f_hz) and f_hz > 0):
        raise ValueError(f"frequency must be a positive carrier frequency in Hz, got "
                         f"{frequency!r}")
    check_scene_file(desc.path)  # meshes first: no Sionna import for a broken file
    meta = desc.metadata()
    altitude = float(meta.get("hover_altitude", 15.0) if hover_altitude is None
                     else hover_altitude)
    if not math.isfinite(altitude) or altitude <= 0:
        raise ValueError(f"hover_altitude must be a positive height in metres, got {altitude!r}")
    rt = sionna_rt()
    root, defaults = _scene_xml(desc.path)
    _check_itu_materials(desc.path, root, defaults, f_hz)
    sc = rt.load_scene(str(desc.path), merge_shapes=False)
    sc.frequency = f_hz
    drop_geometry_shapes(sc, desc)
    placed = RadarScene(desc, sc, altitude, [])
    if targets is None:
        targets = []
        for t in meta.get("targets", []):
            mesh, material = t.get("mesh"), t.get("material", "metal")
            if mesh is not None:
                files = [mesh] if isinstance(mesh, str) else list(mesh)
                files = [str(desc.path.parent / f) for f in files]
                for f in files:
                    if not Path(f).is_file():
                        raise ValueError(f"scene {desc.name!r}: target {t['name']!r} mesh {f} "
                                         "is missing")
                mesh = files[0] if isinstance(t["mesh"], str) else tuple(files)
                material = material if isinstance(material, str) else tuple(material)
            targets.append(SceneTarget(
                t["name"], placed.to_world(np.asarray(t["position"], dtype=float)),
                float(t["rcs_dbsm"]),
                np.asarray(t.get("velocity", [0.0, 0.0, 0.0]), dtype=float) @ ENU_FROM_NED.T,
                float(t.get("size", 0.2)), mesh, material, int(t.get("min_bounces", 1)),
                t.get("diffraction", False)))
    all_targets = list(targets) + list(extra_targets)
    names = [t.name for t in all_targets]
    if len(set(names)) != len(names):
        raise ValueError(f"target names must be unique, got {names}")
    placed.targets = all_targets if include_targets else []
    return placed
