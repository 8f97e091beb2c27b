"""Compiled projection kernel of :class:`compensation.realtime.RealtimeProjector` (``_ext``).

Built by ``setup.py`` (C++ on the Python C API, OpenMP, x86-64-v2 baseline
plus an AVX2+FMA copy chosen at run time); absent when built with
``RAYSIM_NO_KERNEL=1``, in which case the projector uses its NumPy engine.
"""
