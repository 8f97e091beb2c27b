// AVX2 + FMA copy of the kernel, used when the CPU reports both at run time.
// The standard headers come before the target pragma: their inline functions keep the
// baseline target, so the AVX2 code may inline them (GCC 13 refuses the reverse).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <thread>
#include <vector>
#include "rt_params.h"
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#pragma GCC target("avx2,fma")
#define RT_HAVE_AVX2 1
#endif
#define RT_NS avx2
#include "rt_impl.h"
namespace rt {
bool avx2_compiled() {
#ifdef RT_HAVE_AVX2
    return true;
#else
    return false;
#endif
}
void project_avx2(const Params& P) { avx2::project(P); }
void gated_dft_avx2(const float* x, const float* wr, const float* wi, float* out, int64_t R,
                    int64_t K, int64_t G, int64_t threads) {
    avx2::gated_dft(x, wr, wi, out, R, K, G, threads);
}
}
