// Portable copy of the kernel (compiled for the extension's -march baseline).
#define RT_NS portable
#include "rt_impl.h"
namespace rt {
void project_portable(const Params& P) { portable::project(P); }
void gated_dft_portable(const float* x, const float* wr, const float* wi, float* out, int64_t R,
                    int64_t K, int64_t G, int64_t threads) {
    portable::gated_dft(x, wr, wi, out, R, K, G, threads);
}
}
