"""raysim: ray-traced FMCW mmWave MIMO radar simulation for hovering drones.

Submodules are imported lazily; Sionna RT / Mitsuba are only loaded by
``raysim.echoes.rt`` and only after the variant has been chosen explicitly.
"""

__version__ = "0.1.0"
