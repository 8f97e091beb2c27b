"""Ground clutter and multipath: calibrated sigma0, a persistent scatterer field, rough-surface
specular, target-ground ghosts and moving objects (see docs/clutter.md)."""
