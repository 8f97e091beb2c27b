"""Compiled projection kernel of :class:`compensation.realtime.RealtimeProjector` (``_ext``).

Built by ``setup.py`` (C++ on the Python C API, threads started per call,
x86-64-v2 baseline plus AVX2+FMA and AVX-512 copies chosen at run time);
absent when built with
``RAYSIM_NO_KERNEL=1``, in which case the projector uses its NumPy engine.
"""
