r"""Internal clutter motion (ICM): the Doppler spectrum of wind-blown vegetation.

Model
-----
Billingsley's exponential model (Billingsley, *Low-Angle Radar Land
Clutter*, 2002, ch. 3; Billingsley & Larrabee, MIT Lincoln Laboratory; Billingsley,
IEEE Trans. AES 35(3), 1999; restated by Richards, *Fundamentals of Radar Signal
Processing*, 2nd ed., eqs. 2.70-2.73): the power spectrum of the echo of
wind-blown vegetation over radial velocity ``v`` [m/s] is a zero-Doppler (DC)
line plus an exponential (AC) part,

.. math::

    P(v) = \frac{r}{r + 1}\,\delta(v) + \frac{1}{r + 1}\,\frac{\beta}{2} e^{-\beta |v|},

with both parts of unit area, so the total is the clutter's mean power
(``sigma0``). The shape factor ``beta`` [s/m] depends on the wind speed ``w``
only and the DC/AC ratio ``r`` on the wind and the carrier ``f0``:

.. math::

    \beta^{-1} = 0.1048\,(\log_{10} w + 0.4147)\ \mathrm{m/s},\qquad
    r = 489.8\, w^{-1.55} f_0^{-1.21}

with ``w`` in statute miles per hour and ``f0`` in GHz (mixed units, as
published). Measured from VHF to X band (0.17-9.2 GHz) in winds up to gale; at
76-81 GHz both are **extrapolations**: ``r`` is the fitted power law taken beyond
the measured band, ``beta`` is taken as frequency-independent as it was within
it. ``beta`` is defined here for ``w`` of at least :data:`MIN_WIND_MPH` (the
formula's ``1/beta`` reaches 0 at 0.38 mph).

Process
-------
Each vegetation scatterer ``i`` of a clutter field gets a complex modulation of
its fixed amplitude, a function of time ``t`` [s]:

.. math::

    m_i(t) = \sqrt{\frac{r}{r+1}} + \sqrt{\frac{1}{r+1}}
             \sum_{k=1}^{K} n_{ik} \sqrt{\frac{2 v_{max}}{K (1 - \epsilon)}\,
             \frac{\beta}{2} e^{-\beta |v_{ik}|}}\; e^{j 4\pi v_{ik} t / \lambda},
    \qquad n_{ik} \sim \mathcal{CN}(0, 1),\quad v_{ik} \sim U(-v_{max}, v_{max}):

seeded complex Gaussian noise shaped by the square root of the AC spectrum,
at random frequencies spread evenly over the band ``|v| < v_max`` where the
shape keeps all but ``epsilon`` = :data:`ICM_TAIL` of its power
(``v_max = ln(1 / epsilon) / beta``), the random-frequency spectral
representation of a stationary process (Shinozuka & Deodatis, Appl. Mech. Rev.
44(4), 1991). Its expected power spectrum is ``P(v)`` within the band and
``E|m_i|^2 = 1`` (``sigma0`` unchanged); given the frequencies each scatterer's
AC part is complex Gaussian, and the many scatterers of a cell make its sum
Gaussian. Tones spread evenly over the band, not drawn from the shape, keep
the exponential tails populated. Being a function of time, not a sequence
restarted per frame, it is continuous across the frames of a record (gaps
included), costs ``O(scatterer x K x chirp)`` per frame and keeps no state over
the record. A field built again (the radar moved beyond its re-use distance)
draws new scatterers and new processes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["MPH", "MIN_WIND_MPH", "ICM_TONES", "ICM_TAIL", "ac_shape_factor", "dc_ac_ratio",
           "icm_spectrum", "IcmProcess"]

#: One statute mile per hour [m/s].
MPH = 0.44704
#: Smallest wind speed of the model [mph] (0.5 mph, 0.22 m/s: light air); below it, no ICM.
MIN_WIND_MPH = 0.5
#: Tones per scatterer of the spectral representation (see the module notes).
ICM_TONES = 16
#: Share of the AC power beyond the band the tones cover, ``epsilon`` (sets ``v_max``).
ICM_TAIL = 1e-4
#: Scatterers whose modulation is evaluated at once (bounds memory: ``x K x chirp``).
ICM_CHUNK = 4096


def _wind_mph(wind_mps) -> float:
    w = float(wind_mps)
    if not (math.isfinite(w) and w >= MIN_WIND_MPH * MPH):
        raise ValueError(f"wind_mps must be >= {MIN_WIND_MPH * MPH:.3f} m/s "
                         f"({MIN_WIND_MPH} mph), got {wind_mps!r}")
    return w / MPH


def ac_shape_factor(wind_mps: float) -> float:
    """Billingsley's exponential shape factor ``beta`` [s/m] at wind speed ``wind_mps`` [m/s]."""
    return 1.0 / (0.1048 * (math.log10(_wind_mph(wind_mps)) + 0.4147))


def dc_ac_ratio(wind_mps: float, carrier_frequency: float) -> float:
    """Billingsley's DC/AC power ratio ``r`` (linear) at ``wind_mps`` [m/s] and a carrier [Hz]."""
    f = float(carrier_frequency)
    if not (math.isfinite(f) and f > 0):
        raise ValueError(f"carrier_frequency must be > 0 Hz, got {carrier_frequency!r}")
    return 489.8 * _wind_mph(wind_mps) ** -1.55 * (f / 1e9) ** -1.21


def icm_spectrum(velocity, wind_mps: float, carrier_frequency: float):
    """The AC part's density over radial velocity and the DC share.

    Parameters
    ----------
    velocity : array_like
        Radial velocities [m/s].

    Returns
    -------
    ac : ndarray, shape of ``velocity``
        ``(1 / (r + 1)) (beta / 2) exp(-beta |v|)`` [s/m] (power per m/s).
    dc : float
        ``r / (r + 1)``, the power of the zero-Doppler line.
    """
    beta = ac_shape_factor(wind_mps)
    r = dc_ac_ratio(wind_mps, carrier_frequency)
    v = np.asarray(velocity, dtype=float)
    return 0.5 * beta * np.exp(-beta * np.abs(v)) / (r + 1.0), r / (r + 1.0)


@dataclass(frozen=True, eq=False)
class IcmProcess:
    """Seeded ICM modulation of a set of scatterers (build with :meth:`draw`).

    Attributes
    ----------
    velocity : ndarray, shape ``[scatterer, tone]``
        Radial velocities of the tones [m/s].
    weight : ndarray, complex128, shape ``[scatterer, tone]``
        Tone amplitudes (Gaussian noise times the square root of the AC
        spectrum, see the module notes).
    dc : float
        DC amplitude ``sqrt(r / (r + 1))``.
    wavelength : float
        Carrier wavelength [m] (``f = 2 v / lambda``).
    wind_mps : float
    """

    velocity: np.ndarray
    weight: np.ndarray
    dc: float
    wavelength: float
    wind_mps: float

    @classmethod
    def draw(cls, num_scatterers: int, wind_mps: float, carrier_frequency: float, *,
             seed: int = 0, tones: int = ICM_TONES) -> IcmProcess:
        """Tones of ``num_scatterers`` processes for a wind [m/s] and a carrier [Hz]."""
        if int(num_scatterers) != num_scatterers or num_scatterers < 0:
            raise ValueError(f"num_scatterers must be an integer >= 0, got {num_scatterers!r}")
        if int(tones) != tones or tones < 1:
            raise ValueError(f"tones must be an integer >= 1, got {tones!r}")
        beta = ac_shape_factor(wind_mps)
        r = dc_ac_ratio(wind_mps, carrier_frequency)
        rng = np.random.default_rng([int(seed), 0x1C3])
        shape = (int(num_scatterers), int(tones))
        v_max = math.log(1.0 / ICM_TAIL) / beta
        v = rng.uniform(-v_max, v_max, shape)
        n = (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)) / math.sqrt(2)
        density = 0.5 * beta * np.exp(-beta * np.abs(v))               # AC shape [s/m]
        scale = 2.0 * v_max / (tones * (1.0 - ICM_TAIL) * (r + 1.0))
        return cls(v, n * np.sqrt(density * scale), math.sqrt(r / (r + 1.0)),
                   299792458.0 / float(carrier_frequency), float(wind_mps))

    @property
    def num_scatterers(self) -> int:
        """Number of scatterers."""
        return int(self.velocity.shape[0])

    def modulation(self, times, rows=None) -> np.ndarray:
        """Complex modulation ``m_i(t)`` of scatterers ``rows`` at ``times``.

        Parameters
        ----------
        times : array_like, shape ``[time]``
            Absolute instants [s] (e.g. chirp start times).
        rows : array_like of int, shape ``[n]``, optional
            Scatterers (default all).

        Returns
        -------
        ndarray, complex128, shape ``[n, time]``
        """
        t = np.atleast_1d(np.asarray(times, dtype=float))
        if t.ndim != 1 or not np.all(np.isfinite(t)):
            raise ValueError(f"times must be finite with shape [time] [s], got shape {t.shape}")
        rows = np.arange(self.num_scatterers) if rows is None else np.asarray(rows)
        out = np.empty((rows.size, t.size), dtype=np.complex128)
        step = t[1] - t[0] if t.size > 1 else 0.0
        uniform = t.size > 3 and np.allclose(np.diff(t), step, rtol=1e-9, atol=0.0)
        for a in range(0, rows.size, ICM_CHUNK):
            sel = rows[a:a + ICM_CHUNK]
            om = 4.0 * math.pi / self.wavelength * self.velocity[sel]          # [n, K] rad/s
            g = self.weight[sel]
            if uniform:
                # t = t0 + (i B + j) step: exp(j om t) = outer[i] inner[j], both powers of one
                # phasor (chirps of a frame are uniform); the tone sum in complex64, the
                # cube's own precision
                b = math.isqrt(t.size - 1) + 1
                nb = -(-t.size // b)
                inner = np.empty(om.shape + (b,), dtype=np.complex128)            # [n, K, B]
                inner[..., 0] = 1.0
                inner[..., 1:] = np.exp(1j * om * step)[..., None]
                np.cumprod(inner, axis=-1, out=inner)
                outer = np.empty((sel.size, nb) + om.shape[1:], dtype=np.complex128)  # [n, I, K]
                outer[:, 0] = np.exp(1j * om * t[0]) * g
                outer[:, 1:] = np.exp(1j * om * (b * step))[:, None, :]
                np.cumprod(outer, axis=1, out=outer)
                ac = np.matmul(outer.astype(np.complex64), inner.astype(np.complex64)).reshape(
                    sel.size, nb * b)[:, :t.size]
            else:
                ac = np.matmul(g[:, None, :], np.exp(1j * om[:, :, None] * t))[:, 0]
            out[a:a + sel.size] = self.dc + ac
        return out
