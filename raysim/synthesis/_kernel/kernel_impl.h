// Fused exact IF-synthesis kernel: geometry -> delay -> phase -> spread.
// Included once per instruction set with KERNEL_NS defined (see kernel_*.cpp);
// everything here lives in that namespace, so each copy is compiled for its
// own target (portable x86-64-v2, or AVX2+FMA) and dispatched at run time.
//
// One work item = (chirp b, group of up to GROUP channels). For each chunk of
// CHUNK paths (kept in L1/L2) and each row of the group it computes, per path:
//   tau  = (|x_tx - v_f(t)| + L + |v_l(t) - x_rx|) / c          (float64)
//   cyc  = tau (A - mu tau / 2) mod 1,  A = f_c + h mu / f_s    (float64)
//   nu   = mu tau / f_s mod 1 in [-1/2, 1/2]                    (float64)
//   c    = a exp(j 2 pi cyc)        (float64 polynomial sin/cos, error < 1e-11)
// and spreads c onto a padded, oversampled grid of nf points with the
// piecewise-polynomial exponential-of-semicircle kernel (width w <= WP taps),
// accumulated in G (float or double). The padded grid is folded periodically
// into the output row at the end. FFT and deconvolution are done by the caller.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>
#include "kernel_params.h"

namespace KERNEL_NS {

constexpr int CHUNK = 512;   // paths per chunk (geometry of 512 paths ~ 50 KB)
constexpr int GROUP = 16;    // rows per work item
constexpr int MAX_DEGREE = 31;  // largest kernel polynomial degree

// sin and cos of 2 pi r for r in [-1/8, 1/8] (Taylor to degree 13/12, error < 1e-11)
static inline void sincos_2pi_small(double r, double& s, double& c) {
    const double x = 6.283185307179586 * r;
    const double x2 = x * x;
    s = x * (1.0 + x2 * (-1.0 / 6 + x2 * (1.0 / 120 + x2 * (-1.0 / 5040 + x2 * (1.0 / 362880
          + x2 * (-1.0 / 39916800 + x2 * (1.0 / 6227020800.0)))))));
    c = 1.0 + x2 * (-0.5 + x2 * (1.0 / 24 + x2 * (-1.0 / 720 + x2 * (1.0 / 40320
          + x2 * (-1.0 / 3628800 + x2 * (1.0 / 479001600.0))))));
}

template <typename G, int WP, bool TWIN, bool MOVING>
static void chunk_row(const kernel::Params& P, int64_t p0, int64_t p1, int64_t b, int64_t row,
                      const G* coef, G* pad) {
    const double* tx = P.tx + 3 * row;
    const double* rx = P.rx + 3 * row;
    const double txx = tx[0], txy = tx[1], txz = tx[2];
    const double rxx = rx[0], rxy = rx[1], rxz = rx[2];
    const double dt = MOVING ? P.times[row] - P.tref : 0.0;
    const double* fx = P.fx + b * P.vstride;
    const double* fy = P.fy + b * P.vstride;
    const double* fz = P.fz + b * P.vstride;
    const double* lx = P.lx + b * P.vstride;
    const double* ly = P.ly + b * P.vstride;
    const double* lz = P.lz + b * P.vstride;
    const double* L = P.L + b * P.Lstride;
    const double* ar = P.ar + b * P.astride;
    const double* ai = P.ai + b * P.astride;
    const double A = P.A, half_mu = P.half_mu, beat = P.beat, inv_c = P.inv_c;
    const double nf = (double)P.nf, half_w = 0.5 * (double)P.w;
    const double off = (double)(P.nf / 2 + WP);
    alignas(64) double cr[CHUNK + 8], ci[CHUNK + 8], sv[CHUNK + 8];
    alignas(64) int32_t qv[CHUNK + 8];
    const int64_t n = p1 - p0;
    // stage 1: geometry, phase reduction, sin/cos, grid position (vectorisable)
    for (int64_t j = 0; j < n; ++j) {
        const int64_t p = p0 + j;
        double ax = fx[p], ay = fy[p], az = fz[p];
        if (MOVING) {
            ax += P.vx[p] * dt; ay += P.vy[p] * dt; az += P.vz[p] * dt;
        }
        const double dx = txx - ax, dy = txy - ay, dz = txz - az;
        const double d1 = std::sqrt(dx * dx + dy * dy + dz * dz);
        double d2;
        if (TWIN) {
            d2 = d1;
        } else {
            double bx = lx[p], by = ly[p], bz = lz[p];
            if (MOVING) {
                bx += P.vx[p] * dt; by += P.vy[p] * dt; bz += P.vz[p] * dt;
            }
            const double ex = rxx - bx, ey = rxy - by, ez = rxz - bz;
            d2 = std::sqrt(ex * ex + ey * ey + ez * ez);
        }
        const double tau = (d1 + L[p] + d2) * inv_c;
        double cyc = tau * (A - half_mu * tau);
        cyc -= std::floor(cyc + 0.5);                          // [-1/2, 1/2] cycles
        double nu = tau * beat;
        nu -= std::floor(nu + 0.5);                            // [-1/2, 1/2] cycles/sample
        const double q4 = std::floor(4.0 * cyc + 0.5);         // quadrant -2..2
        const double r = cyc - 0.25 * q4;                      // [-1/8, 1/8]
        double s, c;
        sincos_2pi_small(r, s, c);
        const int qi = ((int)q4) & 3;
        const double co = qi == 0 ? c : qi == 1 ? -s : qi == 2 ? -c : s;
        const double si = qi == 0 ? s : qi == 1 ? c : qi == 2 ? -s : -c;
        cr[j] = ar[p] * co - ai[p] * si;
        ci[j] = ar[p] * si + ai[p] * co;
        const double u = nu * nf - half_w;                     // leftmost tap position
        const double l0 = std::ceil(u);
        sv[j] = 2.0 * (l0 - u) - 1.0;                          // s = 2 t - 1 in [-1, 1)
        qv[j] = (int32_t)(l0 + off);
    }
    // stage 2: kernel taps by Horner on one vector of WP taps (GCC vector extension:
    // AVX2 registers in the AVX2 copy, SSE pairs in the portable copy), then add
    // re * taps and im * taps into the split real / imaginary padded grids
    // NV native vectors of VL lanes hold the WP taps
    constexpr int VL = KERNEL_VBYTES / (int)sizeof(G);
    constexpr int NV = WP / VL;
    typedef G V __attribute__((vector_size(KERNEL_VBYTES)));
    const int deg = (int)P.deg;            // <= MAX_DEGREE (checked by the caller)
    V C[MAX_DEGREE + 1][NV];
    for (int d = 0; d <= deg; ++d) std::memcpy(&C[d][0], coef + (int64_t)d * WP, sizeof(V) * NV);
    G* gre = pad;
    G* gim = pad + (P.nf + 2 * WP + 2);
    // U paths at a time: U independent Horner chains hide the FMA latency
    constexpr int U = 4;
    for (int64_t j = n; j < ((n + U - 1) / U) * U; ++j) {  // pad the chunk tail
        sv[j] = 0.0; cr[j] = 0.0; ci[j] = 0.0; qv[j] = qv[0];
    }
    for (int64_t j0 = 0; j0 < n; j0 += U) {
        V ker[U][NV];
        G s[U];
        for (int u = 0; u < U; ++u) {
            s[u] = (G)sv[j0 + u];
            for (int v = 0; v < NV; ++v) ker[u][v] = C[deg][v];
        }
        for (int d = deg - 1; d >= 0; --d)
            for (int u = 0; u < U; ++u)
                for (int v = 0; v < NV; ++v) ker[u][v] = ker[u][v] * s[u] + C[d][v];
        for (int u = 0; u < U; ++u) {
            const int64_t q = qv[j0 + u];
            const G re = (G)cr[j0 + u], im = (G)ci[j0 + u];
            for (int v = 0; v < NV; ++v) {
                V a, c;
                std::memcpy(&a, gre + q + v * VL, sizeof(V));
                std::memcpy(&c, gim + q + v * VL, sizeof(V));
                a += ker[u][v] * re;
                c += ker[u][v] * im;
                std::memcpy(gre + q + v * VL, &a, sizeof(V));
                std::memcpy(gim + q + v * VL, &c, sizeof(V));
            }
        }
    }
}

template <typename G, int WP>
static void run_item(const kernel::Params& P, int64_t b, int64_t m0, int64_t m1,
                     const G* coef, std::vector<G>& pads) {
    const int64_t npad = P.nf + 2 * WP + 2;
    const int64_t rows = m1 - m0;
    std::memset(pads.data(), 0, sizeof(G) * 2 * npad * rows);  // [row][re | im][npad]
    const int64_t n0 = P.n_twin, n1 = n0 + P.n_static, n2 = n1 + P.n_moving;
    for (int64_t c0 = 0; c0 < n2; c0 += CHUNK) {
        const int64_t c1 = std::min(c0 + CHUNK, n2);
        for (int64_t r = 0; r < rows; ++r) {
            const int64_t row = b * P.M + m0 + r;
            G* pad = pads.data() + 2 * npad * r;
            // class boundaries inside this chunk
            int64_t a = c0, e = std::min(c1, n0);
            if (a < e) chunk_row<G, WP, true, false>(P, a, e, b, row, coef, pad);
            a = std::max(c0, n0); e = std::min(c1, n1);
            if (a < e) chunk_row<G, WP, false, false>(P, a, e, b, row, coef, pad);
            a = std::max(c0, n1); e = c1;
            if (a < e) chunk_row<G, WP, false, true>(P, a, e, b, row, coef, pad);
        }
    }
    // fold the padded grids into the periodic output rows
    const int64_t off = P.nf / 2 + WP;
    for (int64_t r = 0; r < rows; ++r) {
        const int64_t row = b * P.M + m0 + r;
        G* out = static_cast<G*>(P.out) + 2 * P.nf * row;
        const G* pad = pads.data() + 2 * npad * r;
        for (int64_t j = 0; j < npad; ++j) {
            int64_t t = (j - off) % P.nf;
            if (t < 0) t += P.nf;
            out[2 * t] += pad[j];
            out[2 * t + 1] += pad[npad + j];
        }
    }
}

template <typename G, int WP>
static void run_all(const kernel::Params& P) {
    std::vector<G> coef((P.deg + 1) * WP, G(0));
    for (int64_t d = 0; d <= P.deg; ++d)
        for (int64_t i = 0; i < P.w; ++i) coef[d * WP + i] = (G)P.coef[d * P.w + i];
    const int64_t groups = (P.M + GROUP - 1) / GROUP;
    const int64_t items = P.B * groups;
#pragma omp parallel num_threads(P.threads)
    {
        std::vector<G> pads(2 * (P.nf + 2 * WP + 2) * GROUP);
#pragma omp for schedule(dynamic, 1)
        for (int64_t it = 0; it < items; ++it) {
            const int64_t b = it / groups, g = it % groups;
            const int64_t m0 = g * GROUP, m1 = std::min(P.M, m0 + GROUP);
            run_item<G, WP>(P, b, m0, m1, coef.data(), pads);
        }
    }
}

inline void spread(const kernel::Params& P) {
    if (P.double_grid) {
        if (P.w <= 8) run_all<double, 8>(P); else run_all<double, 16>(P);
    } else {
        if (P.w <= 8) run_all<float, 8>(P); else run_all<float, 16>(P);
    }
}

}  // namespace KERNEL_NS
