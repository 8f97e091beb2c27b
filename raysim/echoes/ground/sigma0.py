r"""Backscatter coefficient ``sigma0`` of ground materials at 76-81 GHz, and rough-surface specular.

Model
-----
The normalised radar cross-section of a rough ground surface is the sum of an
incoherent volume/roughness term and a quasi-specular (Kirchhoff, geometric
optics) term:

.. math::

    \sigma^0(\theta) = \gamma \cos\theta
        + \bigl(1 - e^{-g(\theta)}\bigr)
          \frac{|\Gamma(0)|^2}{2 m^2 \cos^4\theta} e^{-\tan^2\theta / (2 m^2)},
    \qquad g = (2 k s \cos\theta)^2

* ``gamma cos(theta)`` is the constant-gamma model (Nathanson, *Radar Design
  Principles*, 2nd ed., sec. 7.2; Billingsley, *Low-Angle Radar Land
  Clutter*, 2002, ch. 2), with ``theta`` the incidence angle from the local
  normal. It has no Fresnel factor, hence no Brewster-angle collapse, which
  W-band measurements of rough surfaces do not show (Ulaby & Dobson,
  *Handbook of Radar Scattering Statistics for Terrain*, Artech House 1989).
* The quasi-specular term is the Kirchhoff stationary-phase (geometric optics)
  backscatter of a Gaussian rough surface of rms slope ``m`` (Ulaby, Moore &
  Fung, *Microwave Remote Sensing* Vol. II, eq. 12.53; Beckmann & Spizzichino
  1963), weighted by the incoherent share ``1 - exp(-g)`` of the reflected power
  so that it carries exactly the power the Ament factor removes from the
  coherent reflection (a smooth surface keeps a mirror and no lobe).

Polarisation
------------
The model above is the ``VV`` channel. The other channels scale its
incoherent ``gamma cos(theta)`` term only; the quasi-specular (geometric optics)
term is the same for ``VV`` and ``HH`` and has no cross-polarised part in
backscatter (Ulaby, Moore & Fung Vol. II, sec. 12-5: the Kirchhoff
stationary-phase ``sigma0_hv`` is zero):

.. math::

    \sigma^0_{HH} = \gamma\cos\theta\; 10^{-\Delta_{co}\sin^2\theta / 10} + \sigma^0_{qs},
    \qquad
    \sigma^0_{HV} = \gamma\cos\theta\; 10^{-\Delta_{x} / 10}

``Delta_co`` [dB] is the measured ``VV / HH`` ratio of the material towards grazing
incidence; ``sin^2(theta)`` takes it to 0 at nadir, where ``HH`` and ``VV`` are the
same channel by symmetry. ``Delta_x`` [dB] is the measured co- to cross-polarised
ratio ``VV / HV``. Values (:data:`CLUTTER_MATERIALS`, docs/clutter.md): roads
(asphalt, concrete) from Sarabandi, Li & Nashashibi 1997 (35/60/94 GHz:
``VV`` above ``HH`` by a few dB at large incidence, cross-pol about 10 dB under
``VV``); bare soil from Nashashibi, Sarabandi & Ulaby's 35/94 GHz soil
measurements (IGARSS 1994); grass from Ulaby et al., IEEE TAP 46(1), 1998 (95 GHz
near grazing: co-pol channels within about 1 dB, cross-pol about 6 dB under:
volume scattering by leaves depolarises most). These ratios are recalled from
the published curves to about +-2 dB, not fits, and were not read again: the
stored copies of these sources give only titles and abstracts (Li & Sarabandi's
94 GHz road-surface abstract confirms polarimetric measurements of asphalt and
concrete at 70-88 deg incidence, Ulaby et al. 1998 95 GHz terrain at 70-90 deg),
no ratio (docs/clutter.md, Polarisation, lists what was read).

Coherent specular reflection of a rough surface (Ament, J. Appl. Phys. 24, 1953;
Beckmann & Spizzichino 1963, eq. 5.29), amplitude factor:

.. math::

    \chi(\theta) = \exp\bigl(-2 (k s \cos\theta)^2\bigr)

Material values
---------------
``gamma`` is a constant-gamma fit, to about +-3 dB, of measured W-band
(77-95 GHz) backscatter; ``s`` and ``m`` are the rms height and rms slope used
by the same measurements:

* asphalt: Sarabandi, Li & Nashashibi, IEEE TAP 45(11), 1997 (94 GHz road
  surfaces, ``s`` 0.2-1 mm, ``sigma0`` falling from about -15 dB near 30 deg
  to about -30 dB at grazing);
* concrete: Sarabandi et al. 1997 and ITU-R P.2040 permittivity (also the
  walls' material: no 76-81 GHz wall backscatter could be read, docs/clutter.md);
* dry soil and grass: Ulaby & Dobson 1989 (95 GHz soil and grass statistics),
  Ulaby, Moore & Fung Vol. III App. E (permittivity).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["ClutterMaterial", "CLUTTER_MATERIALS", "POLARISATIONS", "sigma0", "ament_factor",
           "fresnel_coefficient", "clutter_material"]

#: Channels the model gives (transmit-receive; see the module notes).
POLARISATIONS = ("VV", "HH", "HV")


@dataclass(frozen=True)
class ClutterMaterial:
    """Scattering parameters of one ground material at 76-81 GHz.

    Attributes
    ----------
    name : str
        Material id (the scene's ``bsdf`` id).
    gamma_db : float
        Constant-gamma coefficient ``10 log10(gamma)`` [dB].
    rms_height : float
        RMS surface height ``s`` [m].
    rms_slope : float
        RMS surface slope ``m`` (dimensionless, > 0).
    permittivity : complex
        Complex relative permittivity ``eps' - j eps''`` at 77 GHz.
    vv_hh_db : float
        ``VV / HH`` ratio of the incoherent term towards grazing, ``Delta_co`` [dB].
    vv_hv_db : float
        Co- to cross-polarised ratio ``VV / HV`` of the incoherent term, ``Delta_x`` [dB].
    vegetation : bool
        The surface is vegetation that moves in the wind (internal clutter
        motion, :mod:`raysim.echoes.ground.icm`).
    """

    name: str
    gamma_db: float
    rms_height: float
    rms_slope: float
    permittivity: complex
    vv_hh_db: float = 0.0
    vv_hv_db: float = 10.0
    vegetation: bool = False

    def __post_init__(self) -> None:
        if not math.isfinite(self.gamma_db):
            raise ValueError(f"gamma_db must be finite [dB], got {self.gamma_db!r}")
        if not self.rms_height >= 0:
            raise ValueError(f"rms_height must be >= 0 m, got {self.rms_height!r}")
        if not self.rms_slope > 0:
            raise ValueError(f"rms_slope must be > 0, got {self.rms_slope!r}")
        for name in ("vv_hh_db", "vv_hv_db"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) >= 0):
                raise ValueError(f"{name} must be a finite ratio >= 0 dB, "
                                 f"got {getattr(self, name)!r}")
        if not complex(self.permittivity).real >= 1.0:
            raise ValueError(f"permittivity must have a real part >= 1, "
                             f"got {self.permittivity!r}")


#: Ground materials by scene material id (see the module notes for the sources).
CLUTTER_MATERIALS = {m.name: m for m in (
    ClutterMaterial("asphalt-77ghz", gamma_db=-17.0, rms_height=0.7e-3, rms_slope=0.12,
                    permittivity=3.18 - 0.10j, vv_hh_db=3.0, vv_hv_db=10.0),
    ClutterMaterial("concrete", gamma_db=-20.0, rms_height=0.4e-3, rms_slope=0.08,
                    permittivity=5.24 - 0.32j, vv_hh_db=3.0, vv_hv_db=10.0),
    ClutterMaterial("dry-soil", gamma_db=-13.0, rms_height=3e-3, rms_slope=0.25,
                    permittivity=3.0 - 0.10j, vv_hh_db=2.0, vv_hv_db=8.0),
    ClutterMaterial("grass", gamma_db=-10.0, rms_height=10e-3, rms_slope=0.5,
                    permittivity=5.0 - 1.5j, vv_hh_db=1.0, vv_hv_db=6.0, vegetation=True),
)}


def clutter_material(material: str | ClutterMaterial) -> ClutterMaterial:
    """The :class:`ClutterMaterial` of a name in :data:`CLUTTER_MATERIALS` (or itself)."""
    if isinstance(material, ClutterMaterial):
        return material
    try:
        return CLUTTER_MATERIALS[material]
    except (KeyError, TypeError):
        raise ValueError(f"material must be one of {sorted(CLUTTER_MATERIALS)} or a "
                         f"ClutterMaterial, got {material!r}") from None


def _cos_incidence(incidence) -> np.ndarray:
    theta = np.asarray(incidence, dtype=float)
    if not np.all(np.isfinite(theta)) or np.any((theta < 0) | (theta >= math.pi / 2)):
        raise ValueError(f"incidence must lie in [0, pi/2) rad, got values from "
                         f"{np.min(theta)!r} to {np.max(theta)!r}")
    return np.cos(theta)


def fresnel_coefficient(material: str | ClutterMaterial, cos_i, polarisation: str = "VV"):
    """Fresnel reflection coefficient of the material's half-space (Balanis eqs. 5-24, 5-33).

    ``"HH"`` is the TE (perpendicular) coefficient, ``"VV"`` the TM (parallel)
    one in the convention that makes both equal at normal incidence; ``"HV"``
    is 0 (a plane interface does not couple TE and TM in the plane of incidence).

    Parameters
    ----------
    cos_i : array_like
        Cosine of the incidence angle, in ``[0, 1]``.

    Returns
    -------
    ndarray, complex128, shape of ``cos_i``
    """
    m = clutter_material(material)
    _check_pol(polarisation)
    c = np.clip(np.asarray(cos_i, dtype=float), 0.0, 1.0)
    eps = complex(m.permittivity)
    root = np.sqrt(eps - (1.0 - c**2) + 0j)
    if polarisation == "HV":
        return np.zeros_like(root)
    if polarisation == "HH":
        return (c - root) / (c + root)
    return -(eps * c - root) / (eps * c + root)


def _check_pol(polarisation: str) -> None:
    if polarisation not in POLARISATIONS:
        raise ValueError(f"polarisation must be one of {POLARISATIONS}, got {polarisation!r}")


def ament_factor(material: str | ClutterMaterial, incidence, wavelength: float) -> np.ndarray:
    """Ament amplitude factor ``exp(-2 (k s cos theta)^2)`` of the coherent reflection.

    Parameters
    ----------
    incidence : array_like
        Incidence angle from the mean-surface normal [rad], in ``[0, pi/2)``.
    wavelength : float
        Carrier wavelength [m].
    """
    m = clutter_material(material)
    if not wavelength > 0:
        raise ValueError(f"wavelength must be > 0 m, got {wavelength!r}")
    k = 2 * math.pi / wavelength
    return np.exp(-2.0 * (k * m.rms_height * _cos_incidence(incidence)) ** 2)


def sigma0(incidence, material: str | ClutterMaterial, polarisation: str = "VV", *,
           wavelength: float = 299792458.0 / 77e9) -> np.ndarray:
    """Backscatter coefficient ``sigma0`` [m^2/m^2, linear] (model in the module notes).

    Parameters
    ----------
    incidence : array_like
        Incidence angle from the local surface normal [rad], in ``[0, pi/2)``.
    material : str or ClutterMaterial
        A key of :data:`CLUTTER_MATERIALS` or a material.
    polarisation : {"VV", "HH", "HV"}
        Channel (transmit-receive).
    wavelength : float
        Carrier wavelength [m] (sets ``k s`` of the incoherent share).

    Returns
    -------
    ndarray, shape of ``incidence``
    """
    m = clutter_material(material)
    _check_pol(polarisation)
    if not wavelength > 0:
        raise ValueError(f"wavelength must be > 0 m, got {wavelength!r}")
    c = _cos_incidence(incidence)
    k = 2 * math.pi / wavelength
    g = (2.0 * k * m.rms_height * c) ** 2
    gamma = 10.0 ** (m.gamma_db / 10.0)
    if polarisation == "HV":                     # the geometric-optics lobe does not depolarise
        return gamma * c * 10.0 ** (-m.vv_hv_db / 10.0)
    r0 = abs(fresnel_coefficient(m, 1.0)) ** 2
    tan2 = (1.0 - c**2) / c**2
    qs = -np.expm1(-g) * r0 * np.exp(-tan2 / (2 * m.rms_slope**2)) / (2 * m.rms_slope**2 * c**4)
    if polarisation == "HH":
        return gamma * c * 10.0 ** (-m.vv_hh_db * (1.0 - c**2) / 10.0) + qs
    return gamma * c + qs
