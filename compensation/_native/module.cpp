// Python binding of the real-time projection kernel: compensation._native._ext.
//
// project(ints, ptrs, dbls, isa): three addresses of contiguous NumPy arrays
// (int64 sizes, uint64 array addresses, float64 scalars) laid out as
// rt::Params; the Python wrapper (compensation/realtime.py) builds and checks
// them and keeps the arrays alive. isa: 0 = best available, 1 = portable,
// 2 = at most AVX2 (the best copy without AVX-512).
// gated_dft(...): the range transform at the gated bins (see rt_impl.h).
// gated_dft_start(...) / join(handle): the same on a thread of its own, so that
// the caller runs Python (e.g. the strapdown of the frame) meanwhile; the
// caller keeps the arrays alive until join. Release the GIL.
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <cstdint>
#include <thread>
#include "rt_params.h"

namespace rt {
void project_portable(const Params& P);
void project_avx2(const Params& P);
void project_avx512(const Params& P);
bool avx2_compiled();
bool avx512_compiled();
void gated_dft_portable(const float*, const float*, const float*, float*, int64_t, int64_t,
                        int64_t, int64_t);
void gated_dft_avx2(const float*, const float*, const float*, float*, int64_t, int64_t, int64_t,
                    int64_t);
void gated_dft_avx512(const float*, const float*, const float*, float*, int64_t, int64_t,
                      int64_t, int64_t);
}

static bool have_avx2() {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
    __builtin_cpu_init();
    return rt::avx2_compiled() && __builtin_cpu_supports("avx2") &&
           __builtin_cpu_supports("fma");
#else
    return false;
#endif
}

// AVX-512 F, VL, DQ and BW with the OS saving their registers (libgcc's check reads XCR0).
static bool have_avx512() {
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
    __builtin_cpu_init();
    return rt::avx512_compiled() && have_avx2() && __builtin_cpu_supports("avx512f") &&
           __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq") &&
           __builtin_cpu_supports("avx512bw");
#else
    return false;
#endif
}

enum Isa { PORTABLE, AVX2, AVX512 };

// The copy to run for the caller's request (0 best, 1 portable, 2 at most AVX2).
static Isa pick(int request) {
    if (request == 1) return PORTABLE;
    if (request == 0 && have_avx512()) return AVX512;
    return have_avx2() ? AVX2 : PORTABLE;
}

static PyObject* py_project(PyObject*, PyObject* args) {
    unsigned long long pi, pp, pd;
    int isa;
    if (!PyArg_ParseTuple(args, "KKKi", &pi, &pp, &pd, &isa)) return nullptr;
    const int64_t* I = reinterpret_cast<const int64_t*>(pi);
    const uint64_t* A = reinterpret_cast<const uint64_t*>(pp);
    const double* F = reinterpret_cast<const double*>(pd);
    rt::Params P;
    P.N = I[0]; P.S = I[1]; P.n_tdm = I[2]; P.D = I[3]; P.G = I[4]; P.NB = I[5];
    P.M = I[6]; P.M_max = I[7]; P.threads = I[8];
    P.slot_index = reinterpret_cast<const int64_t*>(A[0]);
    P.slot_off = reinterpret_cast<const int64_t*>(A[1]);
    P.slot_line = reinterpret_cast<const int64_t*>(A[2]);
    P.block_start = reinterpret_cast<const int64_t*>(A[3]);
    P.pos = reinterpret_cast<const double*>(A[4]);
    P.rot = reinterpret_cast<const double*>(A[5]);
    P.disp = reinterpret_cast<const double*>(A[6]);
    P.ux = reinterpret_cast<const double*>(A[7]);
    P.uy = reinterpret_cast<const double*>(A[8]);
    P.uz = reinterpret_cast<const double*>(A[9]);
    P.rg = reinterpret_cast<const double*>(A[10]);
    P.block_r = reinterpret_cast<const double*>(A[11]);
    P.x = reinterpret_cast<const float*>(A[12]);
    P.out = reinterpret_cast<float*>(A[13]);
    P.k = F[0]; P.small = F[1];
    const Isa use = pick(isa);
    Py_BEGIN_ALLOW_THREADS
    if (use == AVX512) rt::project_avx512(P);
    else if (use == AVX2) rt::project_avx2(P);
    else rt::project_portable(P);
    Py_END_ALLOW_THREADS
    Py_RETURN_NONE;
}

// One gated range transform: addresses of contiguous arrays x [rows, K] complex64,
// wr / wi [G, K] float32, out [rows, G] complex64, and the copy that runs it.
struct GatedDft {
    const float* x;
    const float* wr;
    const float* wi;
    float* out;
    long long rows, K, G, threads;
    Isa use;

    // Parses (x, wr, wi, out, rows, K, G, threads, isa); false with a Python error set.
    bool parse(PyObject* args) {
        unsigned long long px, pr, pi, po;
        int isa;
        if (!PyArg_ParseTuple(args, "KKKKLLLLi", &px, &pr, &pi, &po, &rows, &K, &G, &threads,
                              &isa))
            return false;
        x = reinterpret_cast<const float*>(px);
        wr = reinterpret_cast<const float*>(pr);
        wi = reinterpret_cast<const float*>(pi);
        out = reinterpret_cast<float*>(po);
        use = pick(isa);
        return true;
    }

    void run() const {
        if (use == AVX512) rt::gated_dft_avx512(x, wr, wi, out, rows, K, G, threads);
        else if (use == AVX2) rt::gated_dft_avx2(x, wr, wi, out, rows, K, G, threads);
        else rt::gated_dft_portable(x, wr, wi, out, rows, K, G, threads);
    }
};

// gated_dft(x, wr, wi, out, rows, K, G, threads, isa): the transform, on this thread.
static PyObject* py_gated_dft(PyObject*, PyObject* args) {
    GatedDft job;
    if (!job.parse(args)) return nullptr;
    Py_BEGIN_ALLOW_THREADS
    job.run();
    Py_END_ALLOW_THREADS
    Py_RETURN_NONE;
}

// A started range transform: its thread, joined by join() or when the handle goes.
static const char* const JOB = "compensation._native._ext.job";

static void job_free(PyObject* capsule) {
    auto* t = static_cast<std::thread*>(PyCapsule_GetPointer(capsule, JOB));
    if (t == nullptr) { PyErr_Clear(); return; }
    if (t->joinable()) t->join();
    delete t;
}

// gated_dft_start(x, wr, wi, out, rows, K, G, threads, isa) -> handle for join()
static PyObject* py_gated_dft_start(PyObject*, PyObject* args) {
    GatedDft job;
    if (!job.parse(args)) return nullptr;
    std::thread* t = nullptr;
    try {
        t = new std::thread([job] { job.run(); });
    } catch (...) {
        return PyErr_Format(PyExc_RuntimeError, "could not start a thread for the range transform");
    }
    PyObject* capsule = PyCapsule_New(t, JOB, job_free);
    if (capsule == nullptr) {
        t->join();
        delete t;
    }
    return capsule;
}

// join(handle): waits for a started range transform (once; later calls return at once).
static PyObject* py_join(PyObject*, PyObject* args) {
    PyObject* capsule;
    if (!PyArg_ParseTuple(args, "O", &capsule)) return nullptr;
    auto* t = static_cast<std::thread*>(PyCapsule_GetPointer(capsule, JOB));
    if (t == nullptr) return nullptr;
    if (t->joinable()) {
        Py_BEGIN_ALLOW_THREADS
        t->join();
        Py_END_ALLOW_THREADS
    }
    Py_RETURN_NONE;
}

// isa([request]): the instruction set the copy for that request (default 0, best) uses here.
static PyObject* py_isa(PyObject*, PyObject* args) {
    int request = 0;
    if (!PyArg_ParseTuple(args, "|i", &request)) return nullptr;
    static const char* names[] = {"portable", "avx2", "avx512"};
    return PyUnicode_FromString(names[pick(request)]);
}

static PyMethodDef methods[] = {
    {"project", py_project, METH_VARARGS, "Exact beams of one frame (see realtime.py)."},
    {"gated_dft", py_gated_dft, METH_VARARGS, "Range transform at the gated bins."},
    {"gated_dft_start", py_gated_dft_start, METH_VARARGS,
     "Range transform at the gated bins on a thread of its own; join(handle) waits."},
    {"join", py_join, METH_VARARGS, "Wait for a range transform started by gated_dft_start."},
    {"isa", py_isa, METH_VARARGS, "Instruction set the kernel uses on this CPU."},
    {nullptr, nullptr, 0, nullptr}};

static PyModuleDef moddef = {PyModuleDef_HEAD_INIT, "_ext",
                             "Real-time exact projection kernel (C++).", -1, methods};

PyMODINIT_FUNC PyInit__ext(void) { return PyModule_Create(&moddef); }
