"""Build of the optional compiled kernels: synthesis (``raysim.synthesis._kernel._ext``) and
real-time projection (``compensation._native._ext``).

Everything else is in pyproject.toml. The extension is plain C++ on the Python
C API (no binding library), compiled with OpenMP for the x86-64-v2 baseline
plus an AVX2+FMA copy (and, for the real-time kernel, an AVX-512 copy) chosen at
run time. If it cannot be built (no compiler), set ``RAYSIM_NO_KERNEL=1``: raysim then
falls back to FINUFFT and ``compensation.realtime`` to its NumPy engine.
"""

import os
import platform

from setuptools import Extension, setup

x86 = platform.machine().lower() in ("x86_64", "amd64")
flags = ["-O3", "-std=c++17", "-fopenmp", "-fno-math-errno", "-fno-trapping-math"]
if x86:
    flags.append("-march=x86-64-v2")


def _extension(name: str, folder: str, stem: str, isas=("avx2",)) -> Extension:
    """One kernel: its module, portable and per-ISA copies, and their shared headers."""
    return Extension(
        name,
        sources=[folder + f for f in ("module.cpp", f"{stem}_portable.cpp",
                                      *(f"{stem}_{isa}.cpp" for isa in isas))],
        depends=[folder + f"{stem}_impl.h", folder + f"{stem}_params.h"],
        extra_compile_args=flags,
        extra_link_args=["-fopenmp"],
        language="c++",
    )


ext = _extension("raysim.synthesis._kernel._ext", "raysim/synthesis/_kernel/", "kernel")
rt_ext = _extension("compensation._native._ext", "compensation/_native/", "rt",
                    ("avx2", "avx512"))
setup(ext_modules=[] if os.environ.get("RAYSIM_NO_KERNEL") else [ext, rt_ext])
