// AVX-512 copy of the kernel (F, VL, DQ, BW; 512-bit vectors), used when the CPU and the OS
// report them at run time. Same source as the AVX2 copy: twice the lanes and 32 vector
// registers (no spills in the fused per-gate pass).
// The standard headers come before the target pragma: their inline functions keep the
// baseline target, so the AVX-512 code may inline them (GCC 13 refuses the reverse).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <thread>
#include <vector>
#include "rt_params.h"
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#pragma GCC target("avx2,fma,avx512f,avx512vl,avx512dq,avx512bw,prefer-vector-width=512")
#define RT_HAVE_AVX512 1
#endif
#define RT_NS avx512
#include "rt_impl.h"
namespace rt {
bool avx512_compiled() {
#ifdef RT_HAVE_AVX512
    return true;
#else
    return false;
#endif
}
void project_avx512(const Params& P) { avx512::project(P); }
void gated_dft_avx512(const float* x, const float* wr, const float* wi, float* out, int64_t R,
                      int64_t K, int64_t G, int64_t threads) {
    avx512::gated_dft(x, wr, wi, out, R, K, G, threads);
}
}
