r"""Users' own geometry: mesh files turned into a scene Sionna RT / Mitsuba loads.

A user scene is one or several mesh files (OBJ, STL, PLY, OFF, glTF/GLB, 3MF,
COLLADA; read with ``trimesh``), each with a radio material (or one per named part of a glTF or
OBJ file) and a placement in the world frame W (docs/conventions.md):

.. math::  p_W = T + R_{ZYX}(\psi, \theta, \phi)\, M_{up}\, (s\, p_{mesh})

with ``T`` the position [m], ``(yaw, pitch, roll)`` Z-Y-X Euler angles [rad],
``s`` a unit scale and ``M_up`` the mesh's own axes into forward-right-down:
``up="z"`` (x forward, y left, z up: the usual CAD / OBJ / STL / PLY export)
or ``up="y"`` (glTF 2.0: +y up, +z forward, +x left). The scene frame S is
ENU with the ground at ``z = 0``; W's origin (the hover point) sits
``hover_altitude`` above it.

:func:`convert_meshes` writes binary PLY files, the Mitsuba XML and its JSON
sidecar into an output folder (each file atomically; the user's files are only
read) and checks every mesh, saying what it fixed or refused
(:class:`ConvertedScene.notes`):

* **units**: the unit a file declares (3MF, COLLADA, glTF) is its scale unless
  ``scale`` is given; in a file that declares none, a bounding box larger than
  :data:`MM_EXTENT_M` looks like millimetres and is refused; one smaller than
  :data:`TINY_EXTENT_M` is warned about;
* **normals**: face winding made consistent (outward for closed meshes) with
  ``trimesh.repair.fix_normals``; the number of flipped faces is reported
  (Sionna reflects on either side, but SBR and PO need outward normals);
* **watertightness** where it matters: a mesh marked ``closed`` (a solid
  object for shooting-and-bouncing rays) must be watertight; small holes are
  filled (``trimesh.repair.fill_holes``), otherwise it is refused;
* **facet size**: edge lengths against the wavelength ``lambda`` and the
  monostatic first Fresnel zone radius ``r_F = sqrt(lambda R / 2)`` at the stated
  range ``R``: facets under ``lambda / 4`` are many per wavelength (costly,
  ray optics treats each as a mirror), facets beyond ``r_F`` on a curved
  surface make faceting glints (refine the mesh).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from raysim.echoes.rt.scenes import ENU_FROM_NED, MATERIALS
from raysim.io.files import atomic_write_bytes, atomic_write_json, atomic_write_text
from raysim.io.mesh_files import MESH_SUFFIXES, declared_scale, read_mesh_file
from raysim.radar.config import SPEED_OF_LIGHT

#: Largest bounding-box extent taken as metres [m]; beyond, the file is taken for millimetres.
MM_EXTENT_M = 500.0
#: Smallest plausible extent in metres [m] (below: a mesh in kilometres, or a typo in scale).
TINY_EXTENT_M = 1e-3
#: Edges below ``lambda / 4``: many facets per wavelength.
SMALL_FACET_WAVELENGTHS = 0.25
#: Curvature test: neighbouring faces bent by more than ``CURVED_FACE_ANGLE`` and less
#: than ``CURVED_MAX_ANGLE`` [rad] sample a smooth curved surface (sharper bends are edges).
CURVED_FACE_ANGLE = math.radians(1.0)
CURVED_MAX_ANGLE = math.radians(30.0)
#: Axes of the mesh's own frame into forward-right-down, by its up axis.
UP_AXES = {"z": np.diag([1.0, -1.0, -1.0]),
           "y": np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])}


@dataclass(frozen=True)
class UserMesh:
    """One mesh file and where it goes.

    Attributes
    ----------
    file : pathlib.Path
        OBJ, STL, PLY, glTF or GLB file (only read).
    material : str or None
        Radio material of the whole mesh (a name of :data:`raysim.echoes.rt.scenes.MATERIALS`),
        and of parts not named in ``materials``.
    materials : dict
        Part name -> material, for named parts (glTF nodes, OBJ objects).
    position_w : ndarray, shape ``[3]``
        Placement of the mesh origin in W (NED) [m].
    yaw, pitch, roll : float
        Z-Y-X Euler angles of the mesh in W [rad].
    scale : float or None
        Metres per file unit (e.g. 0.001 for millimetres); ``None`` = metres, checked.
    up : {"z", "y"}
        The mesh's up axis (see the module docstring).
    closed : bool
        A solid object: must be watertight (holes filled when possible).
    """

    file: Path
    material: str | None = None
    materials: dict = field(default_factory=dict)
    position_w: np.ndarray = field(default_factory=lambda: np.zeros(3))
    yaw: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0
    scale: float | None = None
    up: str = "z"
    closed: bool = False

    def __post_init__(self) -> None:
        path = Path(self.file)
        object.__setattr__(self, "file", path)
        if path.suffix.lower() not in MESH_SUFFIXES:
            raise ValueError(f"mesh file {str(path)!r}: expected one of "
                             f"{', '.join(MESH_SUFFIXES)}, got suffix {path.suffix!r}")
        if not path.is_file():
            raise ValueError(f"mesh file {str(path)!r} does not exist")
        for m in [self.material, *self.materials.values()]:
            if m is not None and m not in MATERIALS:
                raise ValueError(f"mesh file {path.name}: material {m!r} is unknown, expected "
                                 f"one of {', '.join(sorted(MATERIALS))}")
        if self.material is None and not self.materials:
            raise ValueError(f"mesh file {path.name}: give material (or materials per part)")
        pos = np.asarray(self.position_w, dtype=float)
        if pos.shape != (3,) or not np.all(np.isfinite(pos)):
            raise ValueError(f"mesh file {path.name}: position must be 3 finite numbers [m], "
                             f"got {self.position_w!r}")
        object.__setattr__(self, "position_w", pos)
        for name in ("yaw", "pitch", "roll"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"mesh file {path.name}: {name} must be finite [rad], "
                                 f"got {getattr(self, name)!r}")
        if self.scale is not None and not (math.isfinite(self.scale) and self.scale > 0):
            raise ValueError(f"mesh file {path.name}: scale must be a positive number of "
                             f"metres per file unit, got {self.scale!r}")
        if self.up not in UP_AXES:
            raise ValueError(f"mesh file {path.name}: up must be one of {sorted(UP_AXES)}, "
                             f"got {self.up!r}")

    def to_world(self) -> np.ndarray:
        """``4 x 4`` homogeneous transform of file coordinates into W (scale included)."""
        rot = Rotation.from_euler("ZYX", [self.yaw, self.pitch, self.roll]).as_matrix()
        out = np.eye(4)
        out[:3, :3] = rot @ UP_AXES[self.up] * (1.0 if self.scale is None else self.scale)
        out[:3, 3] = self.position_w
        return out


@dataclass(frozen=True)
class ConvertedScene:
    """What :func:`convert_meshes` wrote and found.

    Attributes
    ----------
    xml_path : pathlib.Path
        Mitsuba XML scene (load with :func:`raysim.echoes.rt.scenes.load_scene`).
    notes : tuple of str
        One line per fix or warning, naming the mesh (and part).
    num_triangles : int
        Triangles written.
    """

    xml_path: Path
    notes: tuple
    num_triangles: int

    def summary(self) -> str:
        """Human-readable account of the conversion."""
        head = f"user scene {self.xml_path}: {self.num_triangles} triangles"
        return "\n".join([head] + [f"  - {n}" for n in self.notes])


def with_declared_scale(spec: UserMesh, loaded) -> UserMesh:
    """``spec`` with the unit its file declares (``loaded``: the file read) as its scale
    where it gives none (:func:`raysim.io.mesh_files.declared_scale`)."""
    if spec.scale is not None:
        return spec
    scale = declared_scale(loaded, spec.file)[0]
    return spec if scale is None else replace(spec, scale=scale)


def _parts(spec: UserMesh) -> tuple[list[tuple[str, object]], UserMesh]:
    """``(part name, trimesh.Trimesh)`` of a file, each in the file's own coordinates,
    and ``spec`` with the unit the file declares (:func:`with_declared_scale`)."""
    import trimesh

    loaded = read_mesh_file(spec.file, process=False, **(
        {"split_object": True, "group_material": False}
        if spec.file.suffix.lower() == ".obj" else {}))
    scaled = with_declared_scale(spec, loaded)
    if isinstance(loaded, trimesh.Trimesh):
        return [(spec.file.stem, loaded)], scaled
    if not isinstance(loaded, trimesh.Scene):
        raise ValueError(f"mesh file {str(spec.file)!r} holds no triangle mesh "
                         f"(got {type(loaded).__name__})")
    parts = []
    for node in loaded.graph.nodes_geometry:
        transform, geom = loaded.graph[node]
        mesh = loaded.geometry[geom]
        if isinstance(mesh, trimesh.Trimesh) and len(mesh.faces):
            parts.append((str(node), mesh.copy().apply_transform(transform)))
    if not parts:
        raise ValueError(f"mesh file {str(spec.file)!r} holds no triangles")
    return parts, scaled


def _check_part(label: str, mesh, spec: UserMesh, wavelength: float, range_m: float,
                notes: list[str]):
    """Units, normals, watertightness and facet size of one part; fixes in place."""
    import trimesh

    extent = float(np.max(mesh.extents)) if len(mesh.vertices) else 0.0
    if spec.scale is None and extent > MM_EXTENT_M:
        raise ValueError(f"{label}: bounding box {extent:g} units across looks like "
                         f"millimetres (over {MM_EXTENT_M:g} m); set scale = 0.001 (metres "
                         f"per file unit) or the file's true unit")
    size = extent * (1.0 if spec.scale is None else spec.scale)
    if 0 < size < TINY_EXTENT_M:
        notes.append(f"{label}: warning: only {size:g} m across; check scale")
    mesh.merge_vertices()
    mesh.update_faces(mesh.nondegenerate_faces())
    before = mesh.face_normals.copy()
    trimesh.repair.fix_normals(mesh)
    flipped = int(np.sum(np.einsum("ij,ij->i", before, mesh.face_normals) < 0))
    if flipped:
        notes.append(f"{label}: fixed the winding of {flipped} of {len(mesh.faces)} faces "
                     f"(consistent{', outward' if mesh.is_watertight else ''} normals)")
    if spec.closed and not mesh.is_watertight:
        trimesh.repair.fill_holes(mesh)
        if not mesh.is_watertight:
            raise ValueError(f"{label}: marked closed (a solid for shooting-and-bouncing rays) "
                             f"but not watertight after filling holes; close the mesh or "
                             f"set closed = false")
        notes.append(f"{label}: filled holes; now watertight")
    edges = mesh.edges_unique_length * (1.0 if spec.scale is None else spec.scale)
    fresnel = math.sqrt(wavelength * range_m / 2.0)
    small = float(np.mean(edges < SMALL_FACET_WAVELENGTHS * wavelength))
    if small > 0.5:
        notes.append(f"{label}: {small:.0%} of the edges are under lambda/4 "
                     f"({SMALL_FACET_WAVELENGTHS * wavelength * 1e3:.2f} mm): costly, and ray "
                     f"optics treats each facet as a mirror")
    # a smooth curved surface shows as gentle bends between neighbours; its facet
    # width across the bend is the distance of the two face centres
    if len(mesh.faces) > 1:
        bend = mesh.face_adjacency_angles
        gentle = (bend > CURVED_FACE_ANGLE) & (bend < CURVED_MAX_ANGLE)
        pairs = mesh.face_adjacency[gentle]
        width = np.linalg.norm(mesh.triangles_center[pairs[:, 0]]
                               - mesh.triangles_center[pairs[:, 1]], axis=1)
        width = width * (1.0 if spec.scale is None else spec.scale)
        if width.size and float(width.max()) > fresnel:
            notes.append(f"{label}: warning: facets up to {float(width.max()):.3g} m wide on a "
                         f"curved surface exceed the Fresnel zone radius {fresnel:.3g} m at "
                         f"{range_m:g} m (faceting glints); refine the mesh")


def convert_meshes(meshes, out_dir: str | os.PathLike, *, frequency: float = 77e9,
                   range_m: float | None = None, hover_altitude: float = 15.0,
                   name: str = "user_scene") -> ConvertedScene:
    """Convert users' meshes into a Mitsuba XML scene with PLY meshes.

    Parameters
    ----------
    meshes : sequence of UserMesh
    out_dir : path-like
        Output folder (created); ``<name>.xml``, ``<name>.json`` and ``meshes/*.ply``
        are written atomically, nothing else is touched.
    frequency : float
        Carrier [Hz] (wavelength of the facet-size check).
    range_m : float, optional
        Radar range [m] of the Fresnel-zone check; default each part's distance
        from the hover point (W's origin) to its bounding-box centre, at least 1 m.
    hover_altitude : float
        Height of W's origin above the scene's ground ``z = 0`` [m].
    name : str
        Scene name (file stem).

    Returns
    -------
    ConvertedScene

    Raises
    ------
    ValueError
        An unreadable or empty file, a material or part that does not exist,
        units that look like millimetres, or a closed mesh that is not watertight.
    """
    meshes = list(meshes)
    if not meshes or not all(isinstance(m, UserMesh) for m in meshes):
        raise ValueError(f"meshes must be a non-empty sequence of UserMesh, got {meshes!r}")
    for label, v in (("frequency", frequency), ("range_m", 1.0 if range_m is None else range_m),
                     ("hover_altitude", hover_altitude)):
        if not (math.isfinite(v) and v > 0):
            raise ValueError(f"{label} must be a positive number, got {v!r}")
    wavelength = SPEED_OF_LIGHT / frequency
    out = Path(out_dir)
    (out / "meshes").mkdir(parents=True, exist_ok=True)
    to_scene = np.eye(4)
    to_scene[:3, :3] = ENU_FROM_NED
    to_scene[2, 3] = hover_altitude
    notes: list[str] = []
    shapes, used = [], set()
    total = 0
    for i, spec in enumerate(meshes):
        parts, scaled = _parts(spec)
        if scaled.scale not in (spec.scale, 1.0):
            notes.append(f"{spec.file.name}: declares its unit; read at {scaled.scale:g} m "
                         f"per unit")
            spec = scaled
        elif scaled.scale is None:    # the assumption said, with the size it gives
            lo = np.min([m.bounds[0] for _, m in parts], axis=0)
            hi = np.max([m.bounds[1] for _, m in parts], axis=0)
            size = " x ".join(f"{d:.3g}" for d in hi - lo)
            notes.append(f"{spec.file.name}: declares no unit; read as metres, {size} m "
                         f"across (set scale, metres per file unit, if it is drawn in "
                         f"millimetres, inches, ...)")
        names = {p for p, _ in parts}
        unknown = set(spec.materials) - names
        if unknown:
            raise ValueError(f"mesh file {spec.file.name}: parts {sorted(unknown)} not found; "
                             f"its parts are {sorted(names)}")
        for part, mesh in parts:
            label = f"{spec.file.name}" + (f" part {part!r}" if len(parts) > 1 else "")
            material = spec.materials.get(part, spec.material)
            if material is None:
                raise ValueError(f"{label}: no material (give material or materials.{part})")
            placed = mesh.copy().apply_transform(spec.to_world())
            dist = max(1.0, float(np.linalg.norm(placed.bounds.mean(axis=0))))
            _check_part(label, mesh, spec, wavelength, dist if range_m is None else range_m,
                        notes)
            mesh.apply_transform(to_scene @ spec.to_world())
            if np.linalg.det(to_scene[:3, :3] @ spec.to_world()[:3, :3]) < 0:
                mesh.invert()        # a mirroring placement would turn the normals inwards
            stem = "".join(c if c.isalnum() or c in "-_" else "_" for c in f"{i}-{part}")
            ply = f"meshes/{stem}.ply"
            atomic_write_bytes(out / ply, mesh.export(file_type="ply"))
            shapes.append((stem, ply, material))
            used.add(material)
            total += len(mesh.faces)
    xml = ['<scene version="2.1.0">\n<!-- converted by raysim.echoes.rt.user_meshes; frame ENU, '
           'ground at z = 0 -->\n']
    xml += [MATERIALS[m].to_xml() for m in sorted(used)]
    for stem, ply, material in shapes:
        xml.append(f'    <shape type="ply" id="mesh-{stem}">\n'
                   f'        <string name="filename" value="{ply}"/>\n'
                   f'        <boolean name="face_normals" value="true"/>\n'
                   f'        <ref id="{material}" name="bsdf"/>\n    </shape>\n')
    xml.append("</scene>\n")
    xml_path = atomic_write_text(out / f"{name}.xml", "".join(xml))
    atomic_write_json(out / f"{name}.json", {
        "version": 1, "name": name, "description": "converted from users' meshes",
        "frame": "ENU", "hover_altitude": hover_altitude, "num_triangles": total,
        "targets": [], "sources": [str(m.file) for m in meshes], "notes": notes})
    return ConvertedScene(Path(xml_path), tuple(notes), total)


def convert_user_meshes(placements, *, frequency: float = 77e9,
                        root: str | os.PathLike | None = None) -> ConvertedScene:
    """Convert ``UserMesh`` keyword dicts into the :func:`cache_folder` of their content.

    What was fixed is warned about (``UserWarning``, one message with every note);
    what cannot be used raises ``ValueError``.
    """
    import shutil
    import warnings

    from raysim.io.files import MANIFEST

    meshes = [UserMesh(**p) for p in placements]
    folder = cache_folder(meshes, root, frequency=frequency)
    if folder.is_dir() and not (folder / MANIFEST).is_file():
        shutil.rmtree(folder)         # a cache of a raysim that kept no list of its outputs
    out = convert_meshes(meshes, folder, frequency=frequency)
    if out.notes:
        warnings.warn(out.summary(), UserWarning, stacklevel=2)
    return out


def cache_folder(meshes, root: str | os.PathLike | None = None, **options) -> Path:
    """A folder under ``root`` (default ``~/.cache/raysim/user_scenes``) keyed by the inputs.

    The key hashes every file's bytes and the placements and options, so a
    changed mesh or placement gets a new folder and an unchanged one is reused.
    """
    root = Path(root) if root is not None else Path(
        os.environ.get("RAYSIM_CACHE_DIR", Path.home() / ".cache" / "raysim")) / "user_scenes"
    h = hashlib.sha256()
    for m in meshes:
        h.update(m.file.read_bytes())
        h.update(json.dumps([m.material, sorted(m.materials.items()), m.position_w.tolist(),
                             m.yaw, m.pitch, m.roll, m.scale, m.up, m.closed]).encode())
    h.update(json.dumps(sorted(options.items())).encode())
    return root / h.hexdigest()[:16]
