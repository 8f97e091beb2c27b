"""Ground meshes and signal helpers of the clutter tests (plain NumPy)."""

from __future__ import annotations

import numpy as np

from raysim.echoes.po.mesh import TriangleMesh


def grid_ground(size: float, n: int, depth: float, *, height=None, flip: bool = False,
                centre=(0.0, 0.0)) -> TriangleMesh:
    """A square ``size`` [m] ground in W at ``z = depth`` [m], ``n x n`` cells, two triangles each.

    ``height(x, y)`` adds a relief (metres, up positive); ``flip`` cuts every
    cell along the other diagonal (a second triangulation of the same surface).
    """
    x = np.linspace(-size / 2, size / 2, n + 1)
    gx, gy = np.meshgrid(x + centre[0], x + centre[1], indexing="ij")
    z = np.full(gx.shape, depth) - (0.0 if height is None else height(gx, gy))
    v = np.stack([gx.ravel(), gy.ravel(), z.ravel()], axis=1)
    faces = []
    for i in range(n):
        for j in range(n):
            a = i * (n + 1) + j
            b, c = a + 1, a + n + 1
            d = c + 1
            faces += [[a, c, d], [a, d, b]] if flip else [[a, c, b], [b, c, d]]
    return TriangleMesh(v, np.array(faces))


def tone_frequency(signal: np.ndarray, sample_interval: float, *, pad: int = 64) -> float:
    """Frequency [Hz] of the strongest tone: zero-padded FFT peak, parabolic in log power.

    A single complex tone with a rectangular window peaks at its frequency; the
    padding and the interpolation leave an error far below 0.01 bin.
    """
    n = signal.size * pad
    p = np.abs(np.fft.fft(signal, n)) ** 2
    j = int(np.argmax(p))
    a, b, c = (np.log(p[(j + k) % n] + 1e-300) for k in (-1, 0, 1))
    frac = (j + 0.5 * (a - c) / (a - 2 * b + c)) / n
    return float(((frac + 0.5) % 1.0 - 0.5) / sample_interval)


def range_profile(cube: np.ndarray) -> np.ndarray:
    """Hann-windowed range FFT over the last axis (no normalisation)."""
    return np.fft.fft(cube * np.hanning(cube.shape[-1]), axis=-1)


def write_flat_scene(folder, material, size: float = 60.0, n: int = 6) -> str:
    """A Mitsuba scene of one flat ground of ``material`` (a MaterialSpec) in ``folder``.

    Frame S (ENU, ground at ``z = 0``) as the bundled scenes; returns the XML path.
    """
    import trimesh

    mesh = grid_ground(size, n, 0.0)
    (folder / "meshes").mkdir(exist_ok=True)
    trimesh.Trimesh(mesh.vertices, mesh.faces[:, ::-1], process=False).export(
        folder / "meshes" / "ground.ply")
    xml = ('<scene version="2.1.0">\n' + material.to_xml()
           + '    <shape type="ply" id="mesh-ground">\n'
           '        <string name="filename" value="meshes/ground.ply"/>\n'
           '        <boolean name="face_normals" value="true"/>\n'
           f'        <ref id="{material.name}" name="bsdf"/>\n'
           '    </shape>\n</scene>\n')
    path = folder / "ground.xml"
    path.write_text(xml)
    return str(path)
