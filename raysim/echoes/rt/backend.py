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
    _defer_viewers()
    importlib.import_module("sionna.rt")
    cache = os.environ.get("DRJIT_CACHE_DIR", str(Path.home() / ".drjit"))
    _INFO = BackendInfo(name, llvm, int(dr.thread_count()), cache)
    return _INFO


#: Sionna RT's Jupyter viewers (IPython, ipywidgets, pythreejs: about half of ``import
#: sionna.rt``) and the class each exports, loaded on first use instead of at import.
DEFERRED_VIEWERS = {"sionna.rt.preview": "Previewer",
                    "sionna.rt.rcs.scattering_model_viewer": "ScatteringModelViewer"}


def _defer_viewers() -> None:
    """Before ``sionna.rt`` is first imported, stand in for its viewer modules.

    ``sionna.rt`` imports ``Previewer`` and ``ScatteringModelViewer`` at import
    time, but only ``Scene.preview()`` and ``SensingTarget.show()`` use them
    (raysim never does). A stand-in class's ``__new__`` imports the real module
    and returns the real object, so a notebook's preview works as before. Inside
    IPython, where the widgets' stack is loaded anyway, nothing is deferred.
    """
    if "sionna.rt" in sys.modules or "IPython" in sys.modules:
        return
    import types

    for module, name in DEFERRED_VIEWERS.items():
        if module in sys.modules:
            continue
        stand_in = types.ModuleType(module, "raysim: a Sionna RT viewer, loaded on use")

        def new(cls, *args, _module=module, **kwargs):
            return getattr(_real_viewer(_module), cls.__name__)(*args, **kwargs)

        setattr(stand_in, name, type(name, (), {"__new__": new, "__doc__":
                                                f"Stand-in for {module}.{name}: imported on "
                                                "first use."}))
        stand_in.__raysim_deferred__ = True
        sys.modules[module] = stand_in


def _real_viewer(module: str):
    """The real viewer ``module`` (imported now if only its stand-in is loaded); the
    Sionna modules that imported the stand-in class get the real one."""
    mod = sys.modules.get(module)
    if mod is not None and not getattr(mod, "__raysim_deferred__", False):
        return mod
    stand_in = sys.modules.pop(module, None)
    mod = importlib.import_module(module)
    name = DEFERRED_VIEWERS[module]
    fake = getattr(stand_in, name, None)
    for other in list(sys.modules.values()):
        if getattr(other, "__name__", "").startswith("sionna.rt") and fake is not None \
                and getattr(other, name, None) is fake:
            setattr(other, name, getattr(mod, name))
    parent, _, leaf = module.rpartition(".")
    if parent in sys.modules:
        setattr(sys.modules[parent], leaf, mod)
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
