// Parameters of one call of the fused kernel (filled from Python; see kernel.py).
#pragma once
#include <cstdint>

namespace kernel {

struct Params {
    // sizes
    int64_t n_twin, n_static, n_moving;  // path classes, stored in this order
    int64_t M, B, nf, w, deg, threads, double_grid;
    int64_t vstride, Lstride, astride;   // 0 (per path) or number of paths (per chirp)
    // arrays (float64 unless noted)
    const double *fx, *fy, *fz, *lx, *ly, *lz;  // vertices [B or 1][path]
    const double *L, *ar, *ai;                  // interior length, amplitude re/im
    const double *vx, *vy, *vz;                 // velocity [path] (moving class only)
    const double *times;                        // transmit instants [B * M]
    const double *tx, *rx;                      // element positions [B * M * 3]
    const double *coef;                         // kernel polynomial [deg + 1][w]
    void* out;                                  // grid [B * M][nf] complex (float or double)
    // scalars
    double tref, inv_c, A, half_mu, beat;
};

}  // namespace kernel
