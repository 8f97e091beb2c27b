"""Generate the canonical ray-tracing scenes (Mitsuba XML + PLY + JSON sidecar).

Run from the repository root::

    python scenes/generate.py            # all scenes
    python scenes/generate.py parking_lot
    python scenes/generate.py --out /tmp/scenes   # somewhere else

Every scene is written to ``scenes/<name>/``: ``<name>.xml`` (Mitsuba 3 scene
with Sionna radio materials), ``meshes/*.ply`` (binary PLY, face normals) and
``<name>.json`` (radar hover altitude, constant-RCS sensing targets and the
materials' diffuse settings that the XML format cannot carry).

Scene frame S: east-north-up (ENU), metres, ground surface at ``z = 0``, the
radar's nominal hover point at ``(0, 0, hover_altitude)``. ``raysim.echoes.rt.scenes``
maps S to the world frame W (NED, origin at the hover point).

The output is reproducible: geometry is built with trimesh from fixed numbers
and a seeded ``numpy.random.default_rng``; PLY files are written in binary
with a fixed vertex/face order. The meshes are sized to the default radar's
range window (``max_range`` = 90 m, hover at 15 m) and kept to a few thousand
triangles so that the test suite stays fast.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import numpy as np
import trimesh

HERE = Path(__file__).resolve().parent
#: Where scenes are written (``--out`` changes it).
OUT_ROOT = HERE
#: Format version of the JSON sidecar.
SIDECAR_VERSION = 1

sys.path.insert(0, str(HERE.parent))
from raysim.echoes.rt.scenes import (  # noqa: E402
    ASPHALT,
    CONCRETE,
    DRY_SOIL,
    GLASS,
    MATERIALS,
    METAL,
    MaterialSpec,
)


def _grid(nx: int, ny: int, half_x: float, half_y: float, height=None) -> trimesh.Trimesh:
    """Regular grid of ``2 (nx-1)(ny-1)`` triangles, normals up (+z), optional heights."""
    x = np.linspace(-half_x, half_x, nx)
    y = np.linspace(-half_y, half_y, ny)
    xx, yy = np.meshgrid(x, y, indexing="ij")
    zz = np.zeros_like(xx) if height is None else height
    v = np.stack([xx.ravel(), yy.ravel(), zz.ravel()], axis=1)
    idx = np.arange(nx * ny).reshape(nx, ny)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return trimesh.Trimesh(v, faces, process=False)


def _box(size, centre) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=size,
                                transform=trimesh.transformations.translation_matrix(centre))


def _cylinder(radius: float, height: float, base, sections: int = 12) -> trimesh.Trimesh:
    m = trimesh.creation.cylinder(radius=radius, height=height, sections=sections)
    m.apply_translation(np.asarray(base, dtype=float) + [0.0, 0.0, height / 2])
    return m


def _fractal_heights(rng: np.random.Generator, n: int, spacing: float, rms: float,
                     corr_length: float) -> np.ndarray:
    """Gaussian random surface with a Gaussian spectrum, scaled to ``rms`` [m]."""
    white = rng.standard_normal((n, n))
    k = np.fft.fftfreq(n, d=spacing)
    kx, ky = np.meshgrid(k, k, indexing="ij")
    filt = np.exp(-((np.pi * corr_length) ** 2) * (kx**2 + ky**2) / 2)
    h = np.real(np.fft.ifft2(np.fft.fft2(white) * filt))
    h -= h.mean()
    return h * (rms / h.std())


def write_scene(name: str, shapes: list[tuple[str, trimesh.Trimesh, MaterialSpec]], *,
                hover_altitude: float, description: str, targets: list[dict],
                out_root: Path | None = None,
                traced_only: dict[str, trimesh.Trimesh] | None = None) -> Path:
    """Write ``<out_root>/<name>/`` and return the XML path.

    Parameters
    ----------
    shapes : list of (shape_name, mesh, material)
        Meshes in frame S [m] and their materials.
    hover_altitude : float
        Nominal radar height above ``z = 0`` [m].
    targets : list of dict
        Discrete targets: ``name``, ``position`` (S, m), ``rcs_dbsm``, optional
        ``velocity`` (S, m/s) and ``size`` (m). Geometry targets add ``shape``
        (the XML shape traced by PO + SBR instead of Sionna), ``mesh`` (its PLY)
        and ``material``.
    traced_only : dict, optional
        Meshes written to ``meshes/<name>.ply`` for geometry targets but left
        out of the XML (surfaces that Sionna already has, traced by PO + SBR for
        their multiple bounces only).
    """
    folder = (OUT_ROOT if out_root is None else Path(out_root)) / name
    (folder / "meshes").mkdir(parents=True, exist_ok=True)
    mats: dict[str, MaterialSpec] = {}
    shape_xml = []
    n_tri = 0                        # triangles Sionna traces
    geometry = set()                 # shapes traced by PO + SBR, not by Sionna
    for t in targets:
        shape = t.get("shape")
        geometry |= set() if not shape else {shape} if isinstance(shape, str) else set(shape)
    for shape_name, mesh, mat in shapes:
        mats[mat.name] = mat
        fname = f"meshes/{shape_name}.ply"
        (folder / fname).write_bytes(trimesh.exchange.ply.export_ply(mesh, encoding="binary"))
        n_tri += 0 if shape_name in geometry else len(mesh.faces)
        shape_xml.append(
            f'    <shape type="ply" id="mesh-{shape_name}">\n'
            f'        <string name="filename" value="{fname}"/>\n'
            f'        <boolean name="face_normals" value="true"/>\n'
            f'        <ref id="{mat.name}" name="bsdf"/>\n'
            f'    </shape>\n')
    written = {f"{shape_name}.ply" for shape_name, _, _ in shapes}
    for extra_name, mesh in (traced_only or {}).items():
        (folder / "meshes" / f"{extra_name}.ply").write_bytes(
            trimesh.exchange.ply.export_ply(mesh, encoding="binary"))
        written.add(f"{extra_name}.ply")
    for stale in (folder / "meshes").glob("*.ply"):      # meshes of an earlier layout
        if stale.name not in written:
            stale.unlink()
    xml = ('<scene version="2.1.0">\n<!-- generated by scenes/generate.py; frame ENU, '
           'ground at z = 0 -->\n' + "".join(m.to_xml() for m in mats.values())
           + "".join(shape_xml) + "</scene>\n")
    (folder / f"{name}.xml").write_text(xml)
    n_geo = sum(len(m.faces) for n, m, _ in shapes if n in geometry)
    sidecar = {
        "version": SIDECAR_VERSION, "name": name, "description": description,
        "frame": "ENU", "hover_altitude": hover_altitude, "num_triangles": n_tri,
        "num_geometry_triangles": n_geo,
        "targets": targets,
        "materials": {m.name: dataclasses.asdict(m) for m in mats.values()},
    }
    (folder / f"{name}.json").write_text(json.dumps(sidecar, indent=2) + "\n")
    return folder / f"{name}.xml"


def corner_reflector_rcs_dbsm(edge: float, wavelength: float = 299_792_458.0 / 77e9) -> float:
    """Peak RCS of a triangular trihedral ``4 pi a^4 / (3 lambda^2)`` [dBsm] (edge ``a`` in m)."""
    return float(10 * np.log10(4 * np.pi * edge**4 / (3 * wavelength**2)))


def trihedral_on_ground(edge: float, x: float, y: float, aim) -> tuple[trimesh.Trimesh, list]:
    """Triangular trihedral of ``edge`` [m] aimed at ``aim`` (S, m), standing on the ground.

    Its lowest corner is on ``z = 0`` and its apex above ``(x, y)``. Returns the
    mesh and the apex (its phase centre) in S [m].
    """
    from scipy.spatial.transform import Rotation

    from raysim.echoes.po.targets import trihedral

    local = trihedral(edge)                    # apex at the origin, axis +z
    apex = np.array([x, y, 0.0])
    for _ in range(3):                         # the aim depends a little on the apex height
        axis = np.asarray(aim, dtype=float) - apex
        rot, _ = Rotation.align_vectors([axis / np.linalg.norm(axis)], [[0.0, 0.0, 1.0]])
        v = rot.apply(local.vertices)
        apex = np.array([x, y, 0.0 - v[:, 2].min()])
    mesh = trimesh.Trimesh(v + apex, local.faces, process=False)
    return mesh, [float(c) for c in apex]


def flat_reflectors() -> Path:
    """Flat dry-soil ground (100 m x 100 m) plus four metal trihedral reflectors.

    The reflectors are meshes (geometry targets, traced by PO + SBR), aimed at the
    hover point and standing on a corner; their edges give the closed-form RCS
    ``4 pi a^4 / (3 lambda^2)`` recorded in the sidecar (14.4, 14.4, 21.5, 26.5 dBsm).
    """
    hover = [0.0, 0.0, 15.0]
    shapes: list[tuple[str, trimesh.Trimesh, MaterialSpec]] = [
        ("ground", _grid(11, 11, 50.0, 50.0), DRY_SOIL)]
    targets = []
    for name, edge, x, y in (("cr-nadir", 0.10, 0.0, 0.0), ("cr-east", 0.10, 8.0, 2.0),
                             ("cr-north", 0.15, -3.0, 12.0), ("cr-far", 0.20, -20.0, -15.0)):
        mesh, apex = trihedral_on_ground(edge, x, y, hover)
        shapes.append((name, mesh, METAL))
        targets.append({"name": name, "position": apex,
                        "rcs_dbsm": corner_reflector_rcs_dbsm(edge), "size": edge,
                        "shape": name, "mesh": f"meshes/{name}.ply", "material": METAL.name})
    return write_scene("flat_reflectors", shapes, hover_altitude=15.0, targets=targets,
                       description="flat dry-soil ground, four metal trihedral corner "
                                   "reflectors (meshes, traced by PO + SBR) 0-25 m from nadir")


#: Nominal RCS of a car in the sidecar [dBsm] (typical of passenger cars at 77 GHz,
#: Schipper et al. 2015, Kamel et al. 2017); informational: the traced return
#: follows from the mesh (seen from the hover point the cars give -4 to 6 dBsm).
CAR_NOMINAL_DBSM = 10.0


def car_target(name: str, x: float, y: float, length: float, width: float,
               height: float) -> tuple[list, dict]:
    """A detailed car mesh (parts of :func:`raysim.echoes.po.sedan.sedan_parts`: wheel
    houses, bumpers, plates, mirrors, rims) nose north at ``(x, y)``.

    Returns the shapes and the sidecar entry of the geometry target.
    """
    from raysim.echoes.po.sedan import sedan_parts

    rot = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])   # x forward -> north
    shapes, mats = [], []
    for part, mesh, material in sedan_parts(length, width, height):
        v = mesh.vertices @ rot.T + [x, y, 0.0]
        shapes.append((f"{name}-{part}", trimesh.Trimesh(v, mesh.faces, process=False),
                       MATERIALS[material]))
        mats.append(material)
    entry = {"name": name, "position": [x, y, 0.7], "rcs_dbsm": CAR_NOMINAL_DBSM,
             "size": length, "shape": [s[0] for s in shapes],
             "mesh": [f"meshes/{s[0]}.ply" for s in shapes], "material": mats}
    return shapes, entry


def parking_lot(seed: int = 7) -> Path:
    """Asphalt lot with six car meshes, a concrete/glass facade and a lamp post."""
    rng = np.random.default_rng(seed)
    shapes: list[tuple[str, trimesh.Trimesh, MaterialSpec]] = [
        ("ground", _grid(11, 11, 50.0, 50.0), ASPHALT)]
    targets = []
    slots = [(-9.0, -6.0), (-6.0, -6.0), (-3.0, -6.0), (3.0, -6.0), (6.0, 4.0), (9.0, 4.0)]
    for i, (x, y) in enumerate(slots):
        length, width = 4.5 + rng.uniform(-0.3, 0.3), 1.8 + rng.uniform(-0.1, 0.1)
        height = 1.45 + rng.uniform(-0.05, 0.1)
        car_shapes, entry = car_target(f"car{i}", x, y, length, width, height)
        shapes += car_shapes
        targets.append(entry)
    facade = _box((40.0, 0.4, 12.0), (0.0, 30.0, 6.0))
    shapes.append(("facade", facade, CONCRETE))
    windows = [_box((3.0, 0.05, 2.0), (x, 29.78, z)) for x in (-15, -9, -3, 3, 9, 15)
               for z in (3.0, 7.5)]
    shapes.append(("windows", trimesh.util.concatenate(windows), GLASS))
    pole = _cylinder(0.1, 6.0, (-12.0, 8.0, 0.0))
    arm = _box((1.5, 0.1, 0.1), (-11.3, 8.0, 5.95))
    shapes.append(("lamp", trimesh.util.concatenate([pole, arm]), METAL))
    targets.append({"name": "lamp-head", "position": [-10.6, 8.0, 5.85], "rcs_dbsm": 0.0,
                    "size": 0.2})
    # the facade-ground dihedral: Sionna's specular solver misses it (its specular
    # point lies on the fold), so the facade base and the asphalt in front of it are
    # traced by SBR for their double and triple bounces (their single bounce is Sionna's)
    apron = _grid(2, 2, 6.0, 1.5)
    apron.apply_translation([0.0, 29.8 - 1.5, 0.0])
    base = _grid(2, 2, 6.0, 1.0)
    base.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1.0, 0.0, 0.0]))
    base.apply_translation([0.0, 29.8, 1.0])               # normal -y: facing the lot
    # rcs_dbsm is nominal (the traced corner gives about -2 dBsm from the hover point in VV)
    targets.append({"name": "facade-corner", "position": [0.0, 29.8, 0.0], "rcs_dbsm": 0.0,
                    "size": 12.0, "mesh": ["meshes/facade-apron.ply", "meshes/facade-base.ply"],
                    "material": [ASPHALT.name, CONCRETE.name], "min_bounces": 2})
    return write_scene("parking_lot", shapes, hover_altitude=15.0, targets=targets,
                       traced_only={"facade-apron": apron, "facade-base": base},
                       description="asphalt lot, six car meshes (metal body, bumpers, plates "
                                   "and mirrors, glass windows, rubber tyres on metal rims; "
                                   "traced by PO + SBR), concrete facade "
                                   "with glass windows 30 m north, metal lamp post")


def rough_terrain(seed: int = 11) -> Path:
    """Dry-soil height-map patch (80 m x 80 m, 0.4 m RMS, 6 m correlation length)."""
    rng = np.random.default_rng(seed)
    n, half = 41, 40.0
    h = _fractal_heights(rng, n, 2 * half / (n - 1), rms=0.4, corr_length=6.0)
    ground = _grid(n, n, half, half, height=h)
    return write_scene("rough_terrain", [("terrain", ground, DRY_SOIL)], hover_altitude=15.0,
                       targets=[], description="Gaussian random height map, 0.4 m RMS, 6 m "
                                               "correlation length, dry soil")


GENERATORS = {"flat_reflectors": flat_reflectors, "parking_lot": parking_lot,
              "rough_terrain": rough_terrain}


def main(argv: list[str]) -> int:
    global OUT_ROOT
    argv = list(argv)
    if "--out" in argv:
        i = argv.index("--out")
        if i + 1 >= len(argv):
            print("--out needs a folder", file=sys.stderr)
            return 2
        OUT_ROOT = Path(argv[i + 1])
        del argv[i: i + 2]
    names = argv or list(GENERATORS)
    for name in names:
        if name not in GENERATORS:
            print(f"unknown scene {name!r}; valid: {', '.join(GENERATORS)}", file=sys.stderr)
            return 2
        print(GENERATORS[name]())
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
