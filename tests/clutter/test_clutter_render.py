"""The clutter field inside ``render_scene``, against Sionna's diffuse clutter."""

from __future__ import annotations

import numpy as np
import pytest
from clutter_grounds import write_flat_scene
from scipy import stats

from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

pytestmark = pytest.mark.sionna

#: Kolmogorov-Smirnov significance of the Rayleigh test.
KS_ALPHA = 0.05
#: Rendered vs image-method Doppler [bins] (the brief's 0.1 bin).
BIN_TOL = 0.1
#: Independent realisations (field seeds / Sionna ray seeds).
NUM_SEEDS = 8
#: Range bins of the test band (about 16-24 m, all on the ground), every other one: the
#: Hann window correlates neighbours, cells two bins apart are nearly independent.
BAND = slice(107, 160, 2)


@pytest.fixture(scope="module")
def scene(clutter_backend):
    from raysim.echoes.rt.scenes import load_scene

    return load_scene("flat_reflectors")


@pytest.fixture(scope="module")
def asphalt(clutter_backend, tmp_path_factory):
    """Uniform terrain: a flat asphalt ground, 15 m below the radar."""
    from raysim.echoes.rt.scenes import ASPHALT, load_scene

    path = write_flat_scene(tmp_path_factory.mktemp("asphalt"), ASPHALT)
    return load_scene(path, hover_altitude=15.0)


def _normalised_cells(cubes: list[np.ndarray]) -> np.ndarray:
    """Range-angle cell powers over realisations, each divided by its mean over them."""
    p = []
    for cube in cubes:
        y = np.fft.fft(cube[0] * np.hanning(cube.shape[-1]), axis=-1).reshape(4, 4, -1)
        p.append(np.abs(np.fft.fft2(y, axes=(0, 1))[:, :, BAND]) ** 2)
    p = np.stack(p)
    mean = p.mean(axis=0, keepdims=True)
    return (p / np.where(mean > 0, mean, 1.0)).ravel()


def _ks_rayleigh(x: np.ndarray, n: int) -> float:
    """KS p-value of Rayleigh cells: ``|Y|^2 / mean_n`` of ``n`` iid Exp is ``n Beta(1, n-1)``."""
    return float(stats.kstest(x, stats.beta(1, n - 1, scale=n).cdf).pvalue)


def test_field_is_rayleigh_where_sionna_clutter_is_not(asphalt):
    """Uniform asphalt: the field's cells are Rayleigh; Sionna's planned diffuse clutter is not.

    Sionna keeps a ground hit as a diffuse path with probability ``S^2`` (0.09 on
    asphalt), so the planner's rays per cell leave most cells with no scatterer.
    """
    import dataclasses

    from raysim.echoes.ground.field import FieldSettings
    from raysim.echoes.rt.render import render_scene
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.echoes.scene_clutter import SceneClutter

    config = RadarConfig(num_chirps=1)
    array = upa(4, 4, wavelength=config.wavelength)
    planned = MonostaticTracer.for_scene(asphalt, config, array, targets=False, specular=False,
                                         max_depth=1)
    old, new = [], []
    for seed in range(NUM_SEEDS):
        tracer = dataclasses.replace(planned, seed=seed)
        old.append(render_scene(asphalt, config, array, tracer=tracer, clutter="sionna").data)
        model = SceneClutter(FieldSettings(seed=seed), ghosts=False)
        new.append(render_scene(asphalt, config, array, tracer=tracer, clutter=model).data)
    p_old = _ks_rayleigh(_normalised_cells(old), NUM_SEEDS)
    p_new = _ks_rayleigh(_normalised_cells(new), NUM_SEEDS)
    print(f"KS Rayleigh p-value: Sionna diffuse clutter {p_old:.2e}, clutter field {p_new:.3f}; "
          f"field: {model.summary()['num_scatterers']} scatterers")
    assert p_new > KS_ALPHA
    assert p_old < KS_ALPHA


def test_render_replaces_ground_mirror_and_reports(scene):
    """Default render: one rough ground mirror, field paths, targets kept, report in truth."""
    from raysim.echoes.po.paths import PO_CENTRE
    from raysim.echoes.rt.render import render_scene
    from raysim.echoes.rt.trace import DIFFUSE, SENSING, SPECULAR, MonostaticTracer

    config = RadarConfig(num_chirps=2)
    array = upa(2, 2, wavelength=config.wavelength)
    tracer = MonostaticTracer(samples_per_src=5_000, max_depth=1)
    frame = render_scene(scene, config, array, tracer=tracer)
    paths = frame.truth["paths"]
    spec = (paths.kind == SPECULAR) & (paths.depth == 1)
    assert spec.sum() == 1                                    # the mean-plane mirror only
    n_diffuse = np.count_nonzero(paths.kind & DIFFUSE)      # field paths only (Sionna's off)
    assert 0.8 * frame.truth["clutter"]["num_scatterers"] < n_diffuse
    assert n_diffuse <= frame.truth["clutter"]["num_scatterers"]
    # point targets give one SENSING path each, geometry targets (meshes) PO centres
    points = [t for t in scene.targets if not t.is_geometry]
    assert np.count_nonzero(paths.kind & SENSING) == len(points)
    assert np.count_nonzero(paths.kind & PO_CENTRE) >= len(scene.targets) - len(points)
    assert frame.truth["clutter"]["builds"] == 1
    with pytest.raises(ValueError, match="clutter"):
        render_scene(scene, config, array, tracer=tracer, clutter="lambert")


def test_rendered_rising_target_ghost_doppler(clutter_backend, tmp_path):
    """Through render_scene: Sionna's direct path and the added ghosts of a target rising at
    2 m/s over asphalt have the image-method Doppler ``L' / lambda_c`` within 0.1 bin."""
    from clutter_grounds import range_profile, tone_frequency

    from raysim.echoes.rt.render import render_scene
    from raysim.echoes.rt.scenes import ASPHALT, SceneTarget, load_scene
    from raysim.echoes.rt.trace import MonostaticTracer

    height = 10.0
    p = np.array([3.0, 2.0, 5.0])
    v = np.array([0.5, 0.0, -2.0])
    scene = load_scene(write_flat_scene(tmp_path, ASPHALT), hover_altitude=height,
                       targets=[SceneTarget("riser", p, 10.0, v)])
    config = RadarConfig(num_chirps=64)
    array = upa(1, 1, wavelength=config.wavelength)
    frame = render_scene(scene, config, array, tracer=MonostaticTracer(diffuse=False,
                                                                        max_depth=1))
    y = range_profile(frame.data[:, 0])
    r_bins = config.bin_ranges(config.num_samples)
    image = p * np.array([1, 1, -1]) + np.array([0, 0, 2 * height])
    t_mid = 0.5 * config.frame_duration
    bin_hz = config.doppler_resolution
    for name, a, b in (("direct", p, p), ("ghost", p, image), ("double", image, image)):
        va = v if a is p else v * np.array([1, 1, -1])
        vb = v if b is p else v * np.array([1, 1, -1])
        length = np.linalg.norm(a + va * t_mid) + np.linalg.norm(b + vb * t_mid)
        rate = (a + va * t_mid) @ va / np.linalg.norm(a + va * t_mid) + (
            b + vb * t_mid) @ vb / np.linalg.norm(b + vb * t_mid)
        k = int(np.argmin(np.abs(r_bins - 0.5 * length)))
        f_meas = tone_frequency(y[:, k], config.chirp_interval)
        f_true = rate / config.center_wavelength
        print(f"{name}: {f_meas / bin_hz:+.4f} bins rendered, {f_true / bin_hz:+.4f} image method")
        assert abs(f_meas - f_true) / bin_hz < BIN_TOL
