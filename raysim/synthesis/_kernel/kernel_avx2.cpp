// AVX2 + FMA copy of the kernel, used when the CPU reports both at run time.
// The standard headers come before the target pragma: their inline functions keep the
// baseline target, so the AVX2 code may inline them (GCC 13 refuses the reverse).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>
#include "kernel_params.h"
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#pragma GCC target("avx2,fma")
#define KERNEL_HAVE_AVX2 1
#endif
#define KERNEL_NS avx2
#define KERNEL_VBYTES 32
#include "kernel_impl.h"
namespace kernel {
bool avx2_compiled() {
#ifdef KERNEL_HAVE_AVX2
    return true;
#else
    return false;
#endif
}
void spread_avx2(const Params& P) { avx2::spread(P); }
}
