"""Scene registry, scene generator, materials and backend selection."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_registry_and_unknown_name():
    from raysim.echoes.rt.scenes import FLAT_REFLECTORS, SCENES, get_scene

    assert set(SCENES) >= {"flat_reflectors", "parking_lot", "rough_terrain"}
    for desc in SCENES.values():
        assert desc.path.exists(), desc.path
        meta = desc.metadata()
        assert meta["name"] == desc.name and meta["frame"] == "ENU"
        assert 0 < meta["num_triangles"] < 5000
    assert get_scene("flat_reflectors") is FLAT_REFLECTORS
    assert get_scene(FLAT_REFLECTORS.path).path == FLAT_REFLECTORS.path
    with pytest.raises(ValueError, match="flat_reflectors, parking_lot, rough_terrain"):
        get_scene("parking-lot")


def test_generator_is_reproducible(tmp_path):
    """Regenerating every scene gives byte-identical files to the committed ones."""
    # generate into tmp_path through the public entry of each scene
    out = subprocess.run([sys.executable, str(ROOT / "scenes" / "generate.py"), "--out",
                          str(tmp_path)], capture_output=True, text=True, check=True)
    written = out.stdout.split()
    assert len(written) == 3
    files = sorted(p for p in tmp_path.rglob("*") if p.is_file())
    assert len(files) > 6
    for path in files:
        ref = ROOT / "scenes" / path.relative_to(tmp_path)
        assert_same_scene_file(ref, path)


#: Relative tolerance of regenerated numbers: libm may differ in the last digit.
GENERATOR_RTOL = 1e-12


def _numbers_and_words(text: str):
    import re

    tokens = re.split(r"(-?\d+\.?\d*(?:[eE][-+]?\d+)?)", text)
    return tokens[0::2], np.array([float(x) for x in tokens[1::2]])


def assert_same_scene_file(ref: Path, path: Path) -> None:
    """Same text up to numbers equal within GENERATOR_RTOL; meshes vertex by vertex."""
    if path.suffix == ".ply":
        import trimesh

        a, b = trimesh.load(ref, process=False), trimesh.load(path, process=False)
        np.testing.assert_array_equal(a.faces, b.faces, err_msg=str(ref))
        np.testing.assert_allclose(a.vertices, b.vertices, rtol=GENERATOR_RTOL, atol=1e-12,
                                   err_msg=str(ref))
        return
    words_a, nums_a = _numbers_and_words(ref.read_text())
    words_b, nums_b = _numbers_and_words(path.read_text())
    assert words_a == words_b, ref
    np.testing.assert_allclose(nums_a, nums_b, rtol=GENERATOR_RTOL, atol=1e-12, err_msg=str(ref))


def test_materials_at_77ghz():
    """Ground materials give the normal-incidence reflection stated in their docstrings."""
    from raysim.echoes.rt.scenes import ASPHALT, DRY_SOIL, MATERIALS, MaterialSpec

    for mat, gamma_db in ((DRY_SOIL, -11.4), (ASPHALT, -11.0)):
        n = np.sqrt(mat.complex_permittivity(77e9))
        assert 20 * np.log10(abs((1 - n) / (1 + n))) == pytest.approx(gamma_db, abs=0.1)
    assert {"metal", "concrete", "glass"} <= set(MATERIALS)
    with pytest.raises(ValueError, match="scattering_coefficient"):
        MaterialSpec("bad", scattering_coefficient=1.5)
    with pytest.raises(ValueError, match="ITU type"):
        MATERIALS["metal"].complex_permittivity(77e9)


def test_backend_validation():
    from raysim.echoes.rt import backend

    assert backend.resolve_variant("cpu") == backend.CPU_VARIANT
    assert backend.resolve_variant("gpu") == backend.GPU_VARIANT
    with pytest.raises(ValueError, match="variant"):
        backend.resolve_variant("scalar_rgb")
    with pytest.raises(ValueError, match="threads"):
        backend.configure("cpu", threads=0)


@pytest.mark.sionna
def test_backend_llvm_is_recent(rt_backend):
    assert rt_backend.variant == "llvm_ad_mono_polarized"
    assert rt_backend.llvm_version >= (16, 0, 0)
    assert rt_backend.threads >= 1


@pytest.mark.sionna
def test_scene_frames_and_targets(warm_kernels):
    from raysim.echoes.rt.scenes import ENU_FROM_NED, load_scene

    np.testing.assert_allclose(ENU_FROM_NED @ ENU_FROM_NED, np.eye(3))
    assert np.linalg.det(ENU_FROM_NED) == pytest.approx(1.0)
    scene = load_scene("parking_lot")
    assert scene.hover_altitude == 15.0
    # the facade is 30 m north in ENU, i.e. +x (north) in NED; ground is 15 m below (+z)
    assert {t.name for t in scene.targets} >= {"car0", "lamp-head"}
    assert ([t.name for t in scene.targets if t.is_geometry]
            == [f"car{i}" for i in range(6)] + ["facade-corner"])
    np.testing.assert_allclose(scene.to_world([0.0, 30.0, 0.0]), [30.0, 0.0, 15.0])
    np.testing.assert_allclose(scene.to_scene(scene.to_world([1.0, 2.0, 3.0])), [1, 2, 3])


@pytest.mark.gpu
@pytest.mark.sionna
def test_gpu_variant_traces_like_cpu():
    """The CUDA variant gives the same target amplitude (own process: variants cannot mix)."""
    from raysim.echoes.rt.backend import cuda_available

    if not cuda_available():
        pytest.skip("no CUDA device")
    code = ("from raysim.echoes.rt import backend; backend.configure('gpu');"
            "from raysim.radar.config import RadarConfig;"
            "from raysim.echoes.rt.scenes import load_scene;"
            "from raysim.echoes.rt.trace import MonostaticTracer;"
            "p = MonostaticTracer(specular=False, diffuse=False)(load_scene('flat_reflectors'),"
            " RadarConfig());"
            "import json, numpy as np; print(json.dumps(np.abs(p.amplitude).tolist()))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd=ROOT, check=True)
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.radar.config import RadarConfig

    cpu = MonostaticTracer(specular=False, diffuse=False)(load_scene("flat_reflectors"),
                                                           RadarConfig())
    gpu = np.array(json.loads(out.stdout.strip().splitlines()[-1]))
    np.testing.assert_allclose(gpu, np.abs(cpu.amplitude), rtol=1e-4)
