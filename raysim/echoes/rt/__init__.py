"""Ray-traced echoes with Sionna RT: scenes, monostatic tracing, per-chirp re-projection.

Import order matters: :mod:`raysim.echoes.rt.backend` chooses the Mitsuba variant
before ``sionna.rt`` is imported. Nothing here imports Sionna at import time;
the first call that needs it configures the default backend (CPU/LLVM) unless
:func:`raysim.echoes.rt.backend.configure` was called first.

Modules: ``backend`` (variant, libLLVM check, threads, kernel cache),
``scenes`` (canonical scenes and 77 GHz materials), ``trace`` (monostatic
tracing to a :class:`~raysim.echoes.rt.trace.PathSet`), ``rough_bounces`` (Ament
factor of specular bounces on rough materials), ``reproject`` (frozen
scattering points, per-chirp and per-channel delays), ``render`` (scene to
:class:`~raysim.synthesis.frame.RadarFrame`).
"""
