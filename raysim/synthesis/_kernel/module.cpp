// Python binding of the fused synthesis kernel: raysim.synthesis._kernel._ext.
//
// spread(ints, ptrs, dbls, isa): three addresses of contiguous NumPy arrays
// (int64 sizes, uint64 array addresses, float64 scalars) laid out as
// kernel::Params; the Python wrapper (raysim/synthesis/kernel.py) builds and
// checks them. isa: 0 = best available, 1 = portable. Releases the GIL.
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <cstdint>
#include "kernel_params.h"

namespace kernel {
void spread_portable(const Params& P);
void spread_avx2(const Params& P);
bool avx2_compiled();
}

static bool have_avx2() {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
    __builtin_cpu_init();
    return kernel::avx2_compiled() && __builtin_cpu_supports("avx2") &&
           __builtin_cpu_supports("fma");
#else
    return false;
#endif
}

static PyObject* py_spread(PyObject*, PyObject* args) {
    unsigned long long pi, pp, pd;
    int isa;
    if (!PyArg_ParseTuple(args, "KKKi", &pi, &pp, &pd, &isa)) return nullptr;
    const int64_t* I = reinterpret_cast<const int64_t*>(pi);
    const uint64_t* A = reinterpret_cast<const uint64_t*>(pp);
    const double* D = reinterpret_cast<const double*>(pd);
    kernel::Params P;
    P.n_twin = I[0];
    P.n_static = I[1];
    P.n_moving = I[2];
    P.M = I[3];
    P.B = I[4];
    P.nf = I[5];
    P.w = I[6];
    P.deg = I[7];
    P.threads = I[8];
    P.double_grid = I[9];
    P.vstride = I[10];
    P.Lstride = I[11];
    P.astride = I[12];
    P.fx = reinterpret_cast<const double*>(A[0]);
    P.fy = reinterpret_cast<const double*>(A[1]);
    P.fz = reinterpret_cast<const double*>(A[2]);
    P.lx = reinterpret_cast<const double*>(A[3]);
    P.ly = reinterpret_cast<const double*>(A[4]);
    P.lz = reinterpret_cast<const double*>(A[5]);
    P.L = reinterpret_cast<const double*>(A[6]);
    P.ar = reinterpret_cast<const double*>(A[7]);
    P.ai = reinterpret_cast<const double*>(A[8]);
    P.vx = reinterpret_cast<const double*>(A[9]);
    P.vy = reinterpret_cast<const double*>(A[10]);
    P.vz = reinterpret_cast<const double*>(A[11]);
    P.times = reinterpret_cast<const double*>(A[12]);
    P.tx = reinterpret_cast<const double*>(A[13]);
    P.rx = reinterpret_cast<const double*>(A[14]);
    P.coef = reinterpret_cast<const double*>(A[15]);
    P.out = reinterpret_cast<void*>(A[16]);
    P.tref = D[0]; P.inv_c = D[1]; P.A = D[2]; P.half_mu = D[3]; P.beat = D[4];
    const bool avx2 = isa == 0 && have_avx2();
    Py_BEGIN_ALLOW_THREADS
    if (avx2) kernel::spread_avx2(P); else kernel::spread_portable(P);
    Py_END_ALLOW_THREADS
    Py_RETURN_NONE;
}

static PyObject* py_isa(PyObject*, PyObject*) {
    return PyUnicode_FromString(have_avx2() ? "avx2" : "portable");
}

static PyMethodDef methods[] = {
    {"spread", py_spread, METH_VARARGS, "Spread paths onto oversampled grids (see kernel.py)."},
    {"isa", py_isa, METH_NOARGS, "Instruction set the kernel uses on this CPU."},
    {nullptr, nullptr, 0, nullptr}};

static PyModuleDef moddef = {PyModuleDef_HEAD_INIT, "_ext",
                             "Fused exact IF-synthesis kernel (C++).", -1, methods};

PyMODINIT_FUNC PyInit__ext(void) { return PyModule_Create(&moddef); }
