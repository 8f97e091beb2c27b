"""Explicit choice of the Mitsuba / Dr.Jit backend used by Sionna RT.

``import sionna.rt`` silently picks a Mitsuba variant (CUDA if it can, else
LLVM) as an import side effect. This module makes that choice explicit and
overridable, and checks the prerequisites with messages that say what to do:

* the variant is set **before** ``sionna.rt`` is imported;
* the LLVM backend needs libLLVM >= 16 (with Debian's libLLVM 15 every
  ``PathSolver`` call aborts the process with ``LLVM ERROR: Cannot select``);
* the Dr.Jit thread count is set with ``drjit.set_thread_count`` (the
  ``DRJIT_NUM_THREADS`` environment variable is ignored);
* compiled kernels are cached on disk; the directory can be chosen.

Call :func:`configure` once (every other ``raysim.echoes.rt`` module calls
:func:`sionna_rt`, which configures with the defaults if nobody did).

Environment overrides (read by :func:`configure` when its argument is
``None``): ``RAYSIM_RT_VARIANT`` (a Mitsuba variant name or ``"cpu"`` /
``"gpu"``), ``RAYSIM_RT_THREADS`` (int), ``DRJIT_CACHE_DIR`` (path).
"""

from __future__ import annotations

import importlib
import os
import sys
from dataclasses import dataclass
from pathlib import Path

#: Variant used on CPU (Dr.Jit LLVM backend, polarised, monochromatic).
CPU_VARIANT = "llvm_ad_mono_polarized"
#: Variant used on an NVIDIA GPU (Dr.Jit CUDA backend).
GPU_VARIANT = "cuda_ad_mono_polarized"
#: Oldest libLLVM the Dr.Jit 1.5 LLVM backend runs Sionna's kernels with.
MIN_LLVM_VERSION = (16, 0, 0)

_ALIASES = {"cpu": CPU_VARIANT, "llvm": CPU_VARIANT, "gpu": GPU_VARIANT, "cuda": GPU_VARIANT}


class BackendError(RuntimeError):
    """The requested ray-tracing backend cannot run on this machine."""


@dataclass(frozen=True)
class BackendInfo:
    """What :func:`configure` selected.

    Attributes
    ----------
    variant : str
        Active Mitsuba variant.
    llvm_version : tuple of int or None
        libLLVM version found by Dr.Jit (``None`` for the CUDA backend).
    threads : int
        Dr.Jit worker threads.
    cache_dir : str
        Kernel cache directory.
    """

    variant: str
    llvm_version: tuple | None
    threads: int
    cache_dir: str


_INFO: BackendInfo | None = None


def resolve_variant(variant: str | None) -> str:
    """Map ``None``, ``"cpu"``/``"llvm"``, ``"gpu"``/``"cuda"`` or a variant name to a variant.

    ``None`` reads ``RAYSIM_RT_VARIANT`` and falls back to :data:`CPU_VARIANT`.
    """
    if variant is None:
        variant = os.environ.get("RAYSIM_RT_VARIANT", CPU_VARIANT)
    name = _ALIASES.get(str(variant).lower(), str(variant))
    if not name.endswith("_mono_polarized"):
        raise ValueError(
            f"variant must be 'cpu', 'gpu', {CPU_VARIANT!r} or {GPU_VARIANT!r} (Sionna RT needs "
            f"a *_mono_polarized variant), got {variant!r}"
        )
    return name


def _check_llvm() -> tuple:
    import drjit as dr

    try:
        version = tuple(int(v) for v in dr.detail.llvm_version())
    except Exception as err:  # Dr.Jit raises when no libLLVM can be loaded
        raise BackendError(
            "Dr.Jit could not load libLLVM for the CPU ray tracer. Install it with "
            "`apt-get install -y libllvm19` (or point DRJIT_LIBLLVM_PATH at libLLVM.so >= 16)."
        ) from err
    if version < MIN_LLVM_VERSION:
        raise BackendError(
            f"Dr.Jit found libLLVM {'.'.join(map(str, version))}, but Sionna RT on the LLVM "
            f"backend needs libLLVM >= {MIN_LLVM_VERSION[0]} (older versions abort with "
            "'LLVM ERROR: Cannot select'). Install it with `apt-get install -y libllvm19`, or "
            "set DRJIT_LIBLLVM_PATH to a libLLVM.so of version >= 16."
        )
    return version


def configure(variant: str | None = None, *, threads: int | None = None,
              cache_dir: str | os.PathLike | None = None) -> BackendInfo:
    """Select the Mitsuba variant and Dr.Jit settings, then import Sionna RT.

    Parameters
    ----------
    variant : str, optional
        ``"cpu"`` (:data:`CPU_VARIANT`), ``"gpu"`` (:data:`GPU_VARIANT`) or a
        full ``*_mono_polarized`` variant name. Default: ``RAYSIM_RT_VARIANT``
        or the CPU variant.
    threads : int, optional
        Dr.Jit worker threads (LLVM backend). Default: ``RAYSIM_RT_THREADS`` or
        Dr.Jit's own choice (all cores).
    cache_dir : path-like, optional
        Kernel cache directory; sets ``DRJIT_CACHE_DIR`` before Dr.Jit starts.
        Has no effect once Dr.Jit has been initialised in this process.

    Returns
    -------
    BackendInfo

    Raises
    ------
    ValueError
        For an unknown variant name or a non-positive thread count.
    BackendError
        When the variant cannot run: libLLVM older than 16, no CUDA device, or
        Sionna RT already imported with another variant.
    """
    global _INFO
    name = resolve_variant(variant)
    if threads is None and os.environ.get("RAYSIM_RT_THREADS"):
        threads = int(os.environ["RAYSIM_RT_THREADS"])
    if threads is not None and (int(threads) != threads or threads < 1):
        raise ValueError(f"threads must be a positive integer, got {threads!r}")
    if cache_dir is not None:
        Path(cache_dir).mkdir(parents=True, exist_ok=True)
        os.environ["DRJIT_CACHE_DIR"] = str(Path(cache_dir).resolve())

    import drjit as dr
    import mitsuba as mi

    llvm = None
    if name.startswith("llvm"):
        llvm = _check_llvm()
    current = mi.variant()
    if "sionna.rt" in sys.modules and current is not None and current != name:
        raise BackendError(
            f"sionna.rt is already imported with variant {current!r}; configure the "
            f"backend ({name!r}) before anything imports sionna.rt"
        )
    if current != name:
        try:
            mi.set_variant(name)
        except (ImportError, AttributeError, RuntimeError) as err:
            hint = (" (no CUDA device or driver found; use variant='cpu')"
                    if name.startswith("cuda") else "")
            raise BackendError(f"cannot activate Mitsuba variant {name!r}{hint}: {err}") from err
    if threads is not None and name.startswith("llvm"):
        dr.set_thread_count(int(threads))
    _defer_preview()
    importlib.import_module("sionna.rt")
    cache = os.environ.get("DRJIT_CACHE_DIR", str(Path.home() / ".drjit"))
    _INFO = BackendInfo(name, llvm, int(dr.thread_count()), cache)
    return _INFO


#: Sionna RT's interactive scene preview (Jupyter widgets: IPython, ipywidgets, pythreejs,
#: about half of ``import sionna.rt``), loaded on the first preview instead of at import.
PREVIEW_MODULE = "sionna.rt.preview"


def _defer_preview() -> None:
    """Before ``sionna.rt`` is first imported, stand in for its preview module.

    ``sionna.rt`` imports ``Previewer`` at import time, but only
    ``Scene.preview()`` uses it (raysim never does). The stand-in's
    ``Previewer(...)`` imports the real module and returns the real previewer, so a
    notebook's preview works as before. Inside IPython, where the widgets' stack is
    loaded anyway, nothing is deferred.
    """
    if "sionna.rt" in sys.modules or PREVIEW_MODULE in sys.modules or "IPython" in sys.modules:
        return
    import types

    stand_in = types.ModuleType(PREVIEW_MODULE, "raysim: Sionna RT's preview, loaded on use")

    class Previewer:
        """Stand-in for ``sionna.rt.preview.Previewer``: imports it on first use."""

        def __new__(cls, *args, **kwargs):
            return _real_preview().Previewer(*args, **kwargs)

    stand_in.Previewer = Previewer
    stand_in.__raysim_deferred__ = True
    sys.modules[PREVIEW_MODULE] = stand_in


def _real_preview():
    """The real ``sionna.rt.preview`` module (imported now if only the stand-in is loaded)."""
    mod = sys.modules.get(PREVIEW_MODULE)
    if mod is None or getattr(mod, "__raysim_deferred__", False):
        sys.modules.pop(PREVIEW_MODULE, None)
        mod = importlib.import_module(PREVIEW_MODULE)
        rt = sys.modules.get("sionna.rt")
        if rt is not None:
            rt.preview = mod
            rt.Previewer = mod.Previewer
            scene = sys.modules.get("sionna.rt.scene")
            if scene is not None:
                scene.Previewer = mod.Previewer
    return mod


def info() -> BackendInfo | None:
    """The active configuration, or ``None`` before :func:`configure`."""
    return _INFO


def cuda_available() -> bool:
    """Whether the CUDA variant can be activated (a GPU and driver are present)."""
    try:
        import drjit as dr

        return bool(dr.has_backend(dr.JitBackend.CUDA))
    except Exception:
        return False


def sionna_rt():
    """Return the ``sionna.rt`` module, configuring the default backend first if needed."""
    if _INFO is None:
        configure()
    return importlib.import_module("sionna.rt")
