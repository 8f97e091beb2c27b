"""One name and one definition for every chain, map, axis and metric.

Every command, JSON file, table and figure of raysim takes its names from
here; nothing else defines them. ``docs/conventions.md`` gives the maths.

Chains
------
``none``
    No compensation: a conventional beamformer on the recorded data.
``paper``
    The published joint spatial-temporal chain (slow-time phase per chirp,
    element-wise tilt phase, chirp-wise yaw beam projection). Its rotation
    phase is an option: ``integrated`` (the lever-arm displacement, default)
    or ``published`` (the paper's ``v_r(nT) nT``). The variant with the
    published phase is written ``paper:published``.
``exact``
    Rigid-body projection with all six degrees of freedom per chirp.
``dpca``
    Displaced phase centre (:func:`compensation.dpca_projection`): per chirp
    the sub-aperture whose phase centre stays fixed in the world (Lagrange
    interpolation between neighbouring sub-apertures), each projected as
    ``exact`` does. It undoes what a horizontal displacement does to the
    clutter inside a beam, at the price of aperture (resolution and gain,
    :class:`compensation.DPCAPlan`). Not in the default chain lists
    (:data:`CHAINS`): ask for it by name (``--chains none,exact,dpca``).

A *stationary* result (the same scene with the platform at rest) is a
reference, not a chain: it is reported under ``reference``.

Maps
----
``rd`` range-Doppler, ``ra`` range-azimuth, ``re`` range-elevation, ``ae``
azimuth-elevation (keys lower case, titles upper case). :data:`MAPS` gives a
map's dimensions in array order; :data:`FIGURE_AXES` which one is x and which
y in every figure: azimuth is on x wherever a map has it, range on y.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "CHAINS", "CHAIN_NAMES", "CHAIN_KEYS", "ROTATION_PHASES", "ChainSpec", "parse_chain",
    "parse_chains", "chain_order", "chain_label",
    "MAPS", "FIGURE_AXES", "MAP_TITLES", "AXIS_LABELS", "AXIS_UNITS", "METRICS", "metric_unit",
    "REFERENCE",
]

#: The chains every command evaluates by default, in table order.
CHAINS = ("none", "paper", "exact")

#: Every chain name, in the order every table and figure shows them: the
#: defaults (:data:`CHAINS`), then the chains evaluated only when named
#: (``dpca``: it costs a stencil of sub-aperture projections per chirp and fails
#: for a displacement larger than the spare aperture).
CHAIN_NAMES = CHAINS + ("dpca",)

#: Rotation-phase forms of the ``paper`` chain (first is the default).
ROTATION_PHASES = ("integrated", "published")

#: The keys of the default chains, options included, in table order (``paper`` then
#: ``paper:published``): the chain lists of the studies.
CHAIN_KEYS = tuple(k for n in CHAINS
                   for k in ((n, f"{n}:{ROTATION_PHASES[1]}") if n == "paper" else (n,)))

#: Key of the stationary-platform reference in results (not a chain).
REFERENCE = "stationary"


@dataclass(frozen=True)
class ChainSpec:
    """A chain and its options.

    Attributes
    ----------
    name : {"none", "paper", "exact", "dpca"}
    rotation_phase : {"integrated", "published"}
        Rotation phase of the ``paper`` chain (ignored by the others).
    """

    name: str
    rotation_phase: str = "integrated"

    def __post_init__(self) -> None:
        if self.name not in CHAIN_NAMES:
            raise ValueError(f"chain: got {self.name!r}, expected one of {list(CHAIN_NAMES)} "
                             f"(the paper chain with the published rotation phase is "
                             f"'paper:published')")
        if self.rotation_phase not in ROTATION_PHASES:
            raise ValueError(f"rotation_phase: got {self.rotation_phase!r}, expected one of "
                             f"{list(ROTATION_PHASES)}")

    @property
    def key(self) -> str:
        """The name used in results (``paper:published`` for that variant, else the name)."""
        if self.name == "paper" and self.rotation_phase != ROTATION_PHASES[0]:
            return f"paper:{self.rotation_phase}"
        return self.name

    @property
    def compensated(self) -> bool:
        """True for the chains that need the platform motion."""
        return self.name != "none"

    def __str__(self) -> str:
        return self.key


def parse_chain(text: str | ChainSpec) -> ChainSpec:
    """``"paper:published"`` -> ``ChainSpec("paper", "published")``; errors name the value."""
    if isinstance(text, ChainSpec):
        return text
    if not isinstance(text, str):
        raise ValueError(f"chain: got {text!r}, expected a name from {list(CHAIN_NAMES)}")
    name, _, option = text.strip().partition(":")
    if option and name != "paper":
        raise ValueError(f"chain: got {text!r}; only the paper chain takes an option "
                         f"(paper:published)")
    return ChainSpec(name, option or ROTATION_PHASES[0])


def chain_order(spec: ChainSpec | str) -> tuple[int, str]:
    """Sort key of a chain: its place in :data:`CHAIN_NAMES`, then its key."""
    spec = parse_chain(spec)
    return CHAIN_NAMES.index(spec.name), spec.key


def parse_chains(items) -> tuple[ChainSpec, ...]:
    """A comma list (``"none,paper,exact"``) or a sequence of names -> chain specs."""
    if isinstance(items, str):
        items = [s for s in items.split(",") if s.strip()]
    specs = tuple(parse_chain(s) for s in items)
    if not specs:
        raise ValueError(f"chains: got {items!r}, expected at least one of "
                         f"{list(CHAIN_NAMES)}")
    keys = [s.key for s in specs]
    if len(set(keys)) != len(keys):
        raise ValueError(f"chains: got {keys}, each chain may appear once")
    return specs


def chain_label(key: str) -> str:
    """Human label of a chain key for tables and legends."""
    return {"none": "none (uncompensated)", "paper": "paper",
            "paper:published": "paper, published rotation phase", "exact": "exact",
            "dpca": "dpca (displaced phase centre)", REFERENCE: "stationary platform"}.get(key, key)


#: Map name -> dimensions of its :class:`~raysim.processing.maps.Map` in array order.
MAPS = {
    "rd": ("range", "doppler"),
    "ra": ("range", "azimuth"),
    "re": ("range", "elevation"),
    "ae": ("azimuth", "elevation"),
}

#: Map name -> (x axis, y axis) of its figures.
FIGURE_AXES = {"rd": ("doppler", "range"), "ra": ("azimuth", "range"),
               "re": ("elevation", "range"), "ae": ("azimuth", "elevation")}

#: Map name -> title of its figures.
MAP_TITLES = {"rd": "RD (range-Doppler)", "ra": "RA (range-azimuth)",
              "re": "RE (range-elevation)", "ae": "AE (azimuth-elevation)"}

#: Axis name -> unit of its coordinate as shown (angles in degrees, Doppler as range rate).
AXIS_UNITS = {"range": "m", "doppler": "m/s", "azimuth": "deg", "elevation": "deg",
              "chirp": "", "channel": "", "sample": "", "frame": ""}

#: Axis name -> label of a figure axis.
AXIS_LABELS = {"range": "range [m]", "doppler": "range rate [m/s]",
               "azimuth": "azimuth [deg]", "elevation": "elevation [deg]"}

#: Metric name -> (unit, definition). Every result that reports one of these
#: quantities uses exactly this name; ``docs/conventions.md`` has the maths and the
#: parameters, :mod:`raysim.measure.point` measures the point metrics.
METRICS = {
    "range_m": ("m", "range of the target peak (parabola on the dB range profile)"),
    "az_deg": ("deg", "azimuth of the interpolated peak of the single-chirp angle map"),
    "el_deg": ("deg", "elevation of the interpolated peak of the single-chirp angle map"),
    "angle_error_deg": ("deg", "angle between the interpolated peak of the single-chirp "
                               "angle map (chirp N/2 - 1, the paper's chirp 128) and the truth"),
    "angle_error_worst_deg": ("deg", "largest single-chirp angle error over chirps spread "
                                     "over the frame and its extreme attitudes"),
    "map_az_deg": ("deg", "azimuth of the interpolated peak of the accumulated AE map"),
    "map_el_deg": ("deg", "elevation of the interpolated peak of the accumulated AE map"),
    "map_angle_error_deg": ("deg", "angle between the peak of the accumulated AE map and "
                                   "the truth"),
    "pseudo_velocity_mps": ("m/s", "range rate at the Doppler-spectrum peak of a static "
                                   "target (Hann, 16x zero padding)"),
    "pseudo_velocity_bins": ("bins", "pseudo-velocity in Doppler velocity bins"),
    "doppler_width_hz": ("Hz", "-3 dB width of that Doppler power spectrum"),
    "doppler_width_bins": ("bins", "Doppler width in Doppler bins 1 / (N T_rep)"),
    "entropy_ae_nats": ("nats", "image entropy of the accumulated AE map: beams summed "
                                "coherently over each frame's chirps (zero-Doppler beam), "
                                "power summed over frames"),
    "entropy_rd_nats": ("nats", "image entropy of the RD map of the beam towards the "
                                "target (frame 0, all range bins)"),
    "scene_entropy_rd_nats": ("nats", "image entropy of a scene's RD map: Hann Doppler power "
                                      "summed over every beam of the global grid, range "
                                      "window"),
    "scene_entropy_ra_nats": ("nats", "image entropy of a scene's RA map: coherent "
                                      "(zero-Doppler) beam power summed over elevation, "
                                      "range window"),
    "scene_entropy_ae_nats": ("nats", "image entropy of a scene's AE map: coherent "
                                      "(zero-Doppler) beam power summed over the range "
                                      "window"),
    "peak_power_db": ("dB(W)", "received power at the target's range peak"),
    "ridge_leakage_db": ("dB", "power of a scene's RD map outside the zero-Doppler ridge "
                               "(Doppler bins -1..+1) relative to the map's total"),
    "beam_angle_error_deg": ("deg", "azimuth error of the zero-Doppler peak of a compensated "
                                    "beam cube (raysim.measure.beams)"),
    "beam_pseudo_velocity_bins": ("bins", "pseudo-velocity of the slow-time signal at that "
                                          "peak, in Doppler velocity bins"),
    "doppler_leakage_db": ("dB", "power of that signal's Hann Doppler spectrum outside the "
                                 "peak bin and its neighbours, over the total"),
    "width_improvement_pct": ("%", "Doppler width reduction against chain none: "
                                   "100 (w_none - w) / w_none"),
    "width_vs_stationary": ("1", "Doppler width over that of the stationary reference"),
    "entropy_vs_stationary": ("nats", "entropy_ae_nats minus that of the stationary reference"),
}


def metric_unit(name: str) -> str:
    """Unit of a metric; errors name the metric and the known ones."""
    if name.endswith("_std") and name[:-4] in METRICS:
        name = name[:-4]
    try:
        return METRICS[name][0]
    except KeyError:
        raise ValueError(f"metric: got {name!r}, expected one of {sorted(METRICS)}") from None
