"""Build of the optional compiled kernels: synthesis (``raysim.synthesis._kernel._ext``) and
real-time projection (``compensation._rt._ext``).

Everything else is in pyproject.toml. The extension is plain C++ on the Python
C API (no binding library), compiled with OpenMP for the x86-64-v2 baseline
plus an AVX2+FMA copy chosen at run time. If it cannot be built (no compiler),
set ``RAYSIM_NO_KERNEL=1``: raysim then falls back to FINUFFT and
``compensation.realtime`` to its NumPy engine.
"""

import os
import platform

from setuptools import Extension, setup

SRC = "raysim/synthesis/_kernel/"
x86 = platform.machine().lower() in ("x86_64", "amd64")
flags = ["-O3", "-std=c++17", "-fopenmp", "-fno-math-errno", "-fno-trapping-math"]
if x86:
    flags.append("-march=x86-64-v2")
ext = Extension(
    "raysim.synthesis._kernel._ext",
    sources=[SRC + "module.cpp", SRC + "kernel_portable.cpp", SRC + "kernel_avx2.cpp"],
    depends=[SRC + "kernel_impl.h", SRC + "kernel_params.h"],
    extra_compile_args=flags,
    extra_link_args=["-fopenmp"],
    language="c++",
)
RT = "compensation/_rt/"
rt_ext = Extension(
    "compensation._rt._ext",
    sources=[RT + "module.cpp", RT + "rt_portable.cpp", RT + "rt_avx2.cpp"],
    depends=[RT + "rt_impl.h", RT + "rt_params.h"],
    extra_compile_args=flags,
    extra_link_args=["-fopenmp"],
    language="c++",
)
setup(ext_modules=[] if os.environ.get("RAYSIM_NO_KERNEL") else [ext, rt_ext])
