// Real-time exact rigid-body projection kernel (the model of
// compensation.realtime.RealtimeProjector, whose NumPy engine is the reference).
// Included once per instruction set with RT_NS defined (see rt_*.cpp); each copy
// is compiled for its own target (portable x86-64-v2, AVX2+FMA or AVX-512) and
// dispatched at run time.
//
// One work item = (chirp n, chunk of CH directions); threads take items in turn.
// For each TDM slot s (pose R_n,s, displacement d_n,s) and gate block (focal
// range r), per direction u (float64):
//   q = u . d, e = max(|d|^2 - q^2, 0), t = r - q, L = sqrt(t^2 + e) = |r u - d|
//   range phase 2 k (q - e / (L + t)), steering phase k (r u . R p - d . R p) / L,
//   exp(j .) of both by expj (float64 reduction to a quarter turn, float32
//   polynomial); for a slot on a line p_i = p_0 + i a only exp(j phi(p_0)) and
//   z = exp(j k v . a), otherwise one exp(j .) per channel;
// then per gate g (float32, small phase):
//   -2 k (rho_g - rho_mid) = a (r - R_g) (1 + (t + t_g) / (L + L_g)) / (L_g + t_g),
//   a = -2 k e / (L + t), t_g = R_g - q, L_g = sqrt(t_g^2 + e)   (no cancellation),
//   exp(j .) by its Taylor series while |phase| <= small, else in float64 by expj;
//   channel sum by Horner's rule in z (line), by Horner's rule in two steps
//   (z_a = exp(j k v . a) along rows of n1 channels, z_b = exp(j k v . b) across
//   them) for a slot on a lattice p_(i1 + n1 i2) = p_0 + i1 a + i2 b, or a sum of
//   steering x data for any other layout;
//   accumulated over slots into out[n, g, direction].
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <thread>
#include <vector>
#include "rt_params.h"

namespace RT_NS {

constexpr int64_t CH = 256;  // directions per work item (buffers ~25 KB, in L1/L2)
constexpr double INV_2PI = 0.15915494309189535;
constexpr double TWO_PI = 6.283185307179586;

// exp(j phase) in two steps, so that the float32 polynomial runs at full vector
// width: reduce (float64) gives the quarter turn q and the rest x in [-pi/4, pi/4]
// of phase / 2 pi; rotate (float32) evaluates sin (degree 7) and cos (degree 8)
// of x with the minimax coefficients of Cephes' sinf/cosf (S. L. Moshier,
// "Methods and Programs for Mathematical Functions", 1989; error about one
// float32 ulp on [-pi/4, pi/4]) and turns by j^q.
static inline void reduce(double phase, float& x, int32_t& q) {
    const double r4 = std::rint(4.0 * INV_2PI * phase);
    x = (float)(phase - (0.25 * TWO_PI) * r4);
    q = (int32_t)r4;
}

static inline void rotate(float x, int32_t q, float& c, float& s) {
    const float x2 = x * x;
    const float sn = x + x * x2 * ((-1.9515295891e-4f * x2 + 8.3321608736e-3f) * x2
                                   - 1.6666654611e-1f);
    const float cs = 1.0f - 0.5f * x2 + x2 * x2 * ((2.443315711809948e-5f * x2
                                                     - 1.388731625493765e-3f) * x2
                                                    + 4.166664568298827e-2f);
    const float c1 = (q & 1) ? -sn : cs;
    const float s1 = (q & 1) ? cs : sn;
    const float sg = (q & 2) ? -1.0f : 1.0f;
    c = sg * c1;
    s = sg * s1;
}

static inline void expj(double phase, float& c, float& s) {
    float x;
    int32_t q;
    reduce(phase, x, q);
    rotate(x, q, c, s);
}

// Per-gate phase -2 k (rho_g - rho_mid) = a dr (1 + (t + t_g) / (L + L_g)) / (L_g + t_g)
// in float32 (one division), t_g = R_g - q, L_g = sqrt(t_g^2 + e).
static inline float gate_phase(float rgf, float drf, float q, float e, float t, float L, float a) {
    const float tg = rgf - q;
    const float lg = std::sqrt(tg * tg + e);
    const float ll = L + lg;
    return (ll + t + tg) * a * drf / (ll * (lg + tg));
}

// exp(j ph) by its Taylor series (degree 4 and 5; error < 4e-11 for |ph| <= 0.05)
static inline void expj_small(float ph, float& c, float& s) {
    const float x2 = ph * ph;
    c = (x2 * (1.0f / 24) - 0.5f) * x2 + 1.0f;
    s = ((x2 * (1.0f / 120) - 1.0f / 6) * x2 + 1.0f) * ph;
}

// Geometry of one (chirp, slot, gate block, direction chunk), per direction.
struct Focus {
    const double *q, *e;                  // float64 (large-phase path)
    const float *fq, *fe, *ft, *fL, *fa;  // float32: q, e, t, L, a
};

// Per-gate phase in float64 from q and e (directions where it is not small).
static inline double large_phase(double rg, double r, double k, double q, double e) {
    const double t = r - q, tg = rg - q;
    const double L = std::sqrt(t * t + e), lg = std::sqrt(tg * tg + e);
    return ((t + tg) / (L + lg) + 1.0) * (-2.0 * k * e / (L + t)) / (lg + tg) * (r - rg);
}

// One gate of a slot on a line with MC channels, fused: per direction the small
// phase, exp(j .) by Taylor, the channel sum by Horner's rule in z, times the
// slot's exp(j phi(p_0)), accumulated into (gr, gi). Returns the number of
// directions whose phase exceeds `small` (fixed afterwards by fix_large).
template <int MC, bool FOCAL>
static int gate_line(int64_t nd, float rgf, float drf, float small, const Focus& F,
                     const float* br, const float* bi, const float* zr, const float* zi,
                     const float* xg, int64_t xstride, float* gr, float* gi) {
    float xr[MC], xi[MC];
    for (int i = 0; i < MC; ++i) { xr[i] = xg[xstride * i]; xi[i] = xg[xstride * i + 1]; }
    int large = 0;
    for (int64_t j = 0; j < nd; ++j) {
        // a gate at the block's focal range has a zero phase: no correction
        const float ph = FOCAL ? 0.0f
                               : gate_phase(rgf, drf, F.fq[j], F.fe[j], F.ft[j], F.fL[j], F.fa[j]);
        float c = 1.0f, s = 0.0f;
        if (!FOCAL) expj_small(ph, c, s);
        float ar = xr[MC - 1], ai = xi[MC - 1];
        for (int i = MC - 2; i >= 0; --i) {
            const float nr = ar * zr[j] - ai * zi[j] + xr[i];
            ai = ar * zi[j] + ai * zr[j] + xi[i];
            ar = nr;
        }
        const float vr = ar * br[j] - ai * bi[j], vi = ar * bi[j] + ai * br[j];
        if (FOCAL) {
            gr[j] += vr;
            gi[j] += vi;
        } else {
            // a large phase adds nothing here (its Taylor value can be huge and would be
            // lost to float32 rounding when taken out again); fix_large adds it
            const bool big = std::fabs(ph) > small;
            c = big ? 0.0f : c;
            s = big ? 0.0f : s;
            gr[j] += vr * c - vi * s;
            gi[j] += vr * s + vi * c;
            large += big;
        }
    }
    return large;
}

// Directions of a fused line gate whose phase exceeded `small` (gate_line added
// nothing for them): add their term with the float64 phase and expj (scalar; rare).
static void fix_large(int64_t nd, double rg, double r, double k, float small, const Focus& F,
                      const float* br, const float* bi, const float* zr, const float* zi,
                      const float* xg, int64_t xstride, int64_t m, float* gr, float* gi) {
    const float rgf = (float)rg, drf = (float)(r - rg);
    for (int64_t j = 0; j < nd; ++j) {
        const float ph = gate_phase(rgf, drf, F.fq[j], F.fe[j], F.ft[j], F.fL[j], F.fa[j]);
        if (!(std::fabs(ph) > small)) continue;
        float ec, es;
        expj(large_phase(rg, r, k, F.q[j], F.e[j]), ec, es);
        float ar = xg[xstride * (m - 1)], ai = xg[xstride * (m - 1) + 1];
        for (int64_t i = m - 2; i >= 0; --i) {
            const float nr = ar * zr[j] - ai * zi[j] + xg[xstride * i];
            ai = ar * zi[j] + ai * zr[j] + xg[xstride * i + 1];
            ar = nr;
        }
        const float vr = ar * br[j] - ai * bi[j], vi = ar * bi[j] + ai * br[j];
        gr[j] += vr * ec - vi * es;
        gi[j] += vr * es + vi * ec;
    }
}

// Horner steps of a lattice row per pass over the directions (the paper frame's
// projection, 8 chirps, one thread: 1.41 CPU ms with 4 against 2.88 with 1; 6 and 8
// were no faster).
constexpr int ROW_STEPS = 4;

// Largest slot size with a fused (compile-time) Horner loop.
constexpr int64_t FUSED_MAX = 8;

// Inlined into project() whatever the rest of it: there the vectoriser sees that the
// arrays are disjoint parts of the thread's buffers; out of line it needs a run-time
// alias check per array, gives up and runs the pass scalar (5x slower, measured).
__attribute__((always_inline)) static inline int gate_line_fused(int64_t m, int64_t nd, float rgf, float drf, float small,
                           const Focus& F, const float* br, const float* bi, const float* zr,
                           const float* zi, const float* xg, int64_t xstride, float* gr,
                           float* gi) {
#define RT_CASE(MC) case MC: return drf == 0.0f                                               \
    ? gate_line<MC, true>(nd, rgf, drf, small, F, br, bi, zr, zi, xg, xstride, gr, gi)          \
    : gate_line<MC, false>(nd, rgf, drf, small, F, br, bi, zr, zi, xg, xstride, gr, gi);
    switch (m) {
        RT_CASE(1) RT_CASE(2) RT_CASE(3) RT_CASE(4) RT_CASE(5) RT_CASE(6) RT_CASE(7) RT_CASE(8)
        default: return -1;
    }
#undef RT_CASE
}

// Phases of a slot on a line for a gate block whose gates all lie at its focal
// range (no per-gate phase): the geometry of project() without the per-gate
// arrays, then exp(j .) of phi(p_0) into (br, bi) and of the step into (zr, zi).
// Kept out of line so that the general loops keep their vector code.
__attribute__((noinline)) static void focal_phases(
    int64_t nd, const double* __restrict__ ux, const double* __restrict__ uy,
    const double* __restrict__ uz, double dx, double dy, double dz, double dd, double r,
    double k, double ax, double ay, double az, double a0, double bx, double by, double bz,
    double b0, float* __restrict__ xa, int32_t* __restrict__ qa, float* __restrict__ xb,
    int32_t* __restrict__ qb, float* __restrict__ br, float* __restrict__ bi,
    float* __restrict__ zr, float* __restrict__ zi) {
    for (int64_t j = 0; j < nd; ++j) {
        const double q = ux[j] * dx + uy[j] * dy + uz[j] * dz;
        double e = dd - q * q;
        e = e > 0.0 ? e : 0.0;
        const double t = r - q;
        const double L = std::sqrt(t * t + e);
        const double w = 1.0 / (L * (L + t));
        const double h = e * L * w;
        const double inv = k * (L + t) * w;
        const double phi0 = (r * (ux[j] * ax + uy[j] * ay + uz[j] * az) - a0) * inv
                            + 2.0 * k * (q - h);
        const double alpha = (r * (ux[j] * bx + uy[j] * by + uz[j] * bz) - b0) * inv;
        reduce(phi0, xa[j], qa[j]);
        reduce(alpha, xb[j], qb[j]);
    }
    for (int64_t j = 0; j < nd; ++j) {
        rotate(xa[j], qa[j], br[j], bi[j]);
        rotate(xb[j], qb[j], zr[j], zi[j]);
    }
}

// Runs work() on `threads` threads (the calling one and threads - 1 started for this
// call, joined before the return). Threads started per call rather than an OpenMP
// team: a team's threads spin after the parallel region (libgomp's default wait
// policy, milliseconds per frame), taking the cores the caller's next steps need on
// a loaded machine; starting and joining one costs about 40 us per call.
template <class F>
static void run_threads(int64_t threads, F& work) {
    std::vector<std::thread> pool;
    for (int64_t t = 1; t < threads; ++t) {
        try {
            pool.emplace_back([&work] { work(); });
        } catch (...) {   // no more threads to be had: the running ones take every item
            break;
        }
    }
    work();
    for (auto& th : pool) th.join();
}

static void project(const rt::Params& P) {
    const int64_t nchunk = (P.D + CH - 1) / CH;
    const int64_t items = P.N * nchunk;
    std::atomic<int64_t> next{0};   // the next work item
    auto work = [&]() {
        // the scalars as locals of the thread: captured by reference, a double such as k
        // could alias the stores into the double buffers, and the loops would not vectorise
        const double k = P.k;
        const float small = (float)P.small;
        const int64_t G = P.G, D = P.D, Mm = std::max<int64_t>(P.M_max, 1);
        std::vector<double> dbuf(4 * CH);
        std::vector<float> fbuf(16 * CH + 2 * Mm * CH);
        std::vector<int32_t> qbuf((2 + Mm) * CH);   // quarter turns of reduce
        std::vector<float> acc(2 * G * CH);   // beams of the item, planar [gate][re, im][CH]
        std::vector<double> rp(3 * Mm + 3), dp(Mm + 1);
        double* dq = dbuf.data();
        double* de = dq + CH;
        double* dh = de + CH;
        double* dinv = dh + CH;
        float* fq = fbuf.data();
        float* fe = fq + CH;
        float* ft = fe + CH;
        float* fL = ft + CH;
        float* fA = fL + CH;
        float* br = fA + CH;
        float* bi = br + CH;
        float* zr = bi + CH;
        float* zi = zr + CH;
        float* cr = zi + CH;
        float* ci = cr + CH;
        float* accr = ci + CH;
        float* acci = accr + CH;
        float* sr = acci + CH;
        float* si = sr + Mm * CH;
        float* xa = si + Mm * CH;   // reduced phases (float32 rest)
        float* xb = xa + CH;
        int32_t* qa = qbuf.data();
        int32_t* qb = qa + CH;
        int32_t* qm = qb + CH;      // [m][CH] per-channel quarter turns
        const Focus F{dq, de, fq, fe, ft, fL, fA};
        for (int64_t it = next.fetch_add(1, std::memory_order_relaxed); it < items;
             it = next.fetch_add(1, std::memory_order_relaxed)) {
            const int64_t n = it / nchunk;
            const int64_t j0 = (it % nchunk) * CH;
            const int64_t nd = std::min(CH, D - j0);
            const double* ux = P.ux + j0;
            const double* uy = P.uy + j0;
            const double* uz = P.uz + j0;
            std::fill(acc.begin(), acc.end(), 0.0f);
            for (int64_t s = 0; s < P.S; ++s) {
                const int64_t pose = n * P.n_tdm + P.slot_index[s];
                const double* R = P.rot + 9 * pose;
                const double* d = P.disp + 3 * pose;
                const int64_t m0 = P.slot_off[s], m = P.slot_off[s + 1] - m0;
                const bool line = P.slot_line[s] == 1;
                const int64_t n1 = P.slot_line[s] >= 2 ? P.slot_line[s] : 0;   // lattice rows
                const bool grid = n1 >= 2;
                const double dx = d[0], dy = d[1], dz = d[2];
                const double dd = dx * dx + dy * dy + dz * dz;
                // rotated positions R p and d . R p: (p_0, a) on a line, else every channel
                // p_0 and the step a (line), p_0, a and b (lattice), else every channel
                const int64_t nv = line ? 2 : (grid ? 3 : m);
                for (int64_t i = 0; i < nv; ++i) {
                    double v[3];
                    const double* p = P.pos + 3 * (m0 + i);
                    for (int c = 0; c < 3; ++c)
                        v[c] = (line && i == 1) ? (m > 1 ? P.pos[3 * (m0 + 1) + c] - P.pos[3 * m0 + c]
                                                         : 0.0)
                             : (grid && i == 1) ? P.pos[3 * (m0 + 1) + c] - P.pos[3 * m0 + c]
                             : (grid && i == 2) ? P.pos[3 * (m0 + n1) + c] - P.pos[3 * m0 + c]
                                                : p[c];
                    for (int c = 0; c < 3; ++c)
                        rp[3 * i + c] = R[3 * c] * v[0] + R[3 * c + 1] * v[1] + R[3 * c + 2] * v[2];
                    dp[i] = dx * rp[3 * i] + dy * rp[3 * i + 1] + dz * rp[3 * i + 2];
                }
                const float* xs = P.x + 2 * (n * P.M + m0) * G;   // [m, G] complex
                for (int64_t b = 0; b < P.NB; ++b) {
                    const double r = P.block_r[b];
                    // focal geometry per direction (float64); for a slot on a line the
                    // phases of p_0 and of the step a, reduced, in the same pass
                    const double ax = rp[0], ay = rp[1], az = rp[2], a0 = dp[0];
                    const double bx = rp[3], by = rp[4], bz = rp[5], b0 = dp[1];
#define RT_GEOMETRY                                                                      \
    const double q = ux[j] * dx + uy[j] * dy + uz[j] * dz;                               \
    double e = dd - q * q;                                                               \
    e = e > 0.0 ? e : 0.0;                                                               \
    const double t = r - q;                                                              \
    const double L = std::sqrt(t * t + e);                                               \
    const double w = 1.0 / (L * (L + t)); /* one division for h and k / L */            \
    const double h = e * L * w;                                                          \
    const double inv = k * (L + t) * w;                                                  \
    dq[j] = q; de[j] = e;                                                                \
    fq[j] = (float)q; fe[j] = (float)e; ft[j] = (float)t; fL[j] = (float)L;              \
    fA[j] = (float)(-2.0 * k * h);
                    // every gate of the block at its focal range (a block of one gate):
                    // no per-gate phase, so only the two phases per direction
                    bool focal = line && m <= FUSED_MAX;
                    for (int64_t g = P.block_start[b]; g < P.block_start[b + 1]; ++g)
                        focal = focal && (float)(r - P.rg[g]) == 0.0f;
                    if (focal) {
                        focal_phases(nd, ux, uy, uz, dx, dy, dz, dd, r, k, ax, ay, az, a0, bx, by,
                                     bz, b0, xa, qa, xb, qb, br, bi, zr, zi);
                    } else if (line) {
                        for (int64_t j = 0; j < nd; ++j) {
                            RT_GEOMETRY
                            const double phi0 = (r * (ux[j] * ax + uy[j] * ay + uz[j] * az) - a0)
                                                * inv + 2.0 * k * (q - h);
                            const double alpha = (r * (ux[j] * bx + uy[j] * by + uz[j] * bz) - b0)
                                                 * inv;
                            reduce(phi0, xa[j], qa[j]);
                            reduce(alpha, xb[j], qb[j]);
                        }
                        for (int64_t j = 0; j < nd; ++j) {
                            rotate(xa[j], qa[j], br[j], bi[j]);
                            rotate(xb[j], qb[j], zr[j], zi[j]);
                        }
                    } else if (grid) {
                        // phases of p_0 (with the range phase), a and b; z_b into (sr, si)
                        const double cx = rp[6], cy = rp[7], cz = rp[8], c0 = dp[2];
                        int32_t* qc = qm;
                        for (int64_t j = 0; j < nd; ++j) {
                            RT_GEOMETRY
                            const double phi0 = (r * (ux[j] * ax + uy[j] * ay + uz[j] * az) - a0)
                                                * inv + 2.0 * k * (q - h);
                            const double alpha = (r * (ux[j] * bx + uy[j] * by + uz[j] * bz) - b0)
                                                 * inv;
                            const double beta = (r * (ux[j] * cx + uy[j] * cy + uz[j] * cz) - c0)
                                                * inv;
                            reduce(phi0, xa[j], qa[j]);
                            reduce(alpha, xb[j], qb[j]);
                            reduce(beta, sr[j], qc[j]);
                        }
                        for (int64_t j = 0; j < nd; ++j) {
                            rotate(xa[j], qa[j], br[j], bi[j]);
                            rotate(xb[j], qb[j], zr[j], zi[j]);
                            rotate(sr[j], qc[j], sr[j], si[j]);
                        }
                    } else {
                        for (int64_t j = 0; j < nd; ++j) {
                            RT_GEOMETRY
                            dh[j] = h;
                            dinv[j] = inv;
                        }
#undef RT_GEOMETRY
                        for (int64_t i = 0; i < m; ++i) {
                            const double ax = rp[3 * i], ay = rp[3 * i + 1], az = rp[3 * i + 2],
                                         a0 = dp[i];
                            float* sri = sr + i * CH;
                            float* sii = si + i * CH;
                            for (int64_t j = 0; j < nd; ++j) {
                                const double ph = (r * (ux[j] * ax + uy[j] * ay + uz[j] * az) - a0)
                                                  * dinv[j] + 2.0 * k * (dq[j] - dh[j]);
                                reduce(ph, sri[j], qm[i * CH + j]);
                            }
                            for (int64_t j = 0; j < nd; ++j)
                                rotate(sri[j], qm[i * CH + j], sri[j], sii[j]);
                        }
                    }
                    for (int64_t g = P.block_start[b]; g < P.block_start[b + 1]; ++g) {
                        const float rgf = (float)P.rg[g];
                        const float drf = (float)(r - P.rg[g]);
                        const float* xg = xs + 2 * g;
                        float* gr = acc.data() + 2 * g * CH;
                        float* gi = gr + CH;
                        if (line && m <= FUSED_MAX) {
                            if (gate_line_fused(m, nd, rgf, drf, small, F, br, bi, zr, zi, xg,
                                                2 * G, gr, gi))
                                fix_large(nd, P.rg[g], r, k, small, F, br, bi, zr, zi, xg, 2 * G, m,
                                          gr, gi);
                            continue;
                        }
                        // per-gate phase (float32, Taylor; float64 and expj where large)
                        int large = 0;
                        for (int64_t j = 0; j < nd; ++j) {
                            const float ph = gate_phase(rgf, drf, fq[j], fe[j], ft[j], fL[j],
                                                        fA[j]);
                            expj_small(ph, cr[j], ci[j]);
                            large += std::fabs(ph) > small;
                        }
                        if (large) {
                            for (int64_t j = 0; j < nd; ++j) {
                                const float ph = gate_phase(rgf, drf, fq[j], fe[j], ft[j], fL[j],
                                                            fA[j]);
                                if (!(std::fabs(ph) > small)) continue;
                                expj(large_phase(P.rg[g], r, k, dq[j], de[j]), cr[j], ci[j]);
                            }
                        }
                        if (line) {   // Horner: sum_i x_i z^i, times exp(j phi(p_0))
                            const float xr = xg[2 * G * (m - 1)], xi = xg[2 * G * (m - 1) + 1];
                            for (int64_t j = 0; j < nd; ++j) { accr[j] = xr; acci[j] = xi; }
                            for (int64_t i = m - 2; i >= 0; --i) {
                                const float yr = xg[2 * G * i], yi = xg[2 * G * i + 1];
                                for (int64_t j = 0; j < nd; ++j) {
                                    const float ar = accr[j], ai = acci[j];
                                    accr[j] = ar * zr[j] - ai * zi[j] + yr;
                                    acci[j] = ar * zi[j] + ai * zr[j] + yi;
                                }
                            }
                            for (int64_t j = 0; j < nd; ++j) {
                                const float ar = accr[j] * br[j] - acci[j] * bi[j];
                                const float ai = accr[j] * bi[j] + acci[j] * br[j];
                                accr[j] = ar; acci[j] = ai;
                            }
                        } else if (grid) {
                            // rows by Horner's rule in z_a, then across rows in z_b, times
                            // exp(j phi(p_0)); (tr, ti) holds the row being summed
                            const float* wr = sr;
                            const float* wi = si;
                            float* tr = sr + CH;
                            float* ti = si + CH;
                            const int64_t n2 = m / n1;
                            for (int64_t i2 = n2 - 1; i2 >= 0; --i2) {
                                const float* xrow = xg + 2 * G * n1 * i2;
                                const float xr = xrow[2 * G * (n1 - 1)], xi = xrow[2 * G * (n1 - 1) + 1];
                                for (int64_t j = 0; j < nd; ++j) { tr[j] = xr; ti[j] = xi; }
                                // ROW_STEPS Horner steps per pass over the directions: the
                                // row's partial sums stay in registers between them
                                int64_t i1 = n1 - 2;
                                for (; i1 >= ROW_STEPS - 1; i1 -= ROW_STEPS) {
                                    float yr[ROW_STEPS], yi[ROW_STEPS];
                                    for (int u = 0; u < ROW_STEPS; ++u) {
                                        yr[u] = xrow[2 * G * (i1 - u)];
                                        yi[u] = xrow[2 * G * (i1 - u) + 1];
                                    }
                                    for (int64_t j = 0; j < nd; ++j) {
                                        float ar = tr[j], ai = ti[j];
                                        const float cr = zr[j], cj = zi[j];
                                        for (int u = 0; u < ROW_STEPS; ++u) {
                                            const float nr = ar * cr - ai * cj + yr[u];
                                            ai = ar * cj + ai * cr + yi[u];
                                            ar = nr;
                                        }
                                        tr[j] = ar;
                                        ti[j] = ai;
                                    }
                                }
                                for (; i1 >= 0; --i1) {
                                    const float yr = xrow[2 * G * i1], yi = xrow[2 * G * i1 + 1];
                                    for (int64_t j = 0; j < nd; ++j) {
                                        const float ar = tr[j], ai = ti[j];
                                        tr[j] = ar * zr[j] - ai * zi[j] + yr;
                                        ti[j] = ar * zi[j] + ai * zr[j] + yi;
                                    }
                                }
                                if (i2 == n2 - 1) {
                                    for (int64_t j = 0; j < nd; ++j) { accr[j] = tr[j]; acci[j] = ti[j]; }
                                } else {
                                    for (int64_t j = 0; j < nd; ++j) {
                                        const float ar = accr[j], ai = acci[j];
                                        accr[j] = ar * wr[j] - ai * wi[j] + tr[j];
                                        acci[j] = ar * wi[j] + ai * wr[j] + ti[j];
                                    }
                                }
                            }
                            for (int64_t j = 0; j < nd; ++j) {
                                const float ar = accr[j] * br[j] - acci[j] * bi[j];
                                const float ai = accr[j] * bi[j] + acci[j] * br[j];
                                accr[j] = ar; acci[j] = ai;
                            }
                        } else {      // sum_i steer_i x_i
                            for (int64_t j = 0; j < nd; ++j) { accr[j] = 0.0f; acci[j] = 0.0f; }
                            for (int64_t i = 0; i < m; ++i) {
                                const float yr = xg[2 * G * i], yi = xg[2 * G * i + 1];
                                const float* sri = sr + i * CH;
                                const float* sii = si + i * CH;
                                for (int64_t j = 0; j < nd; ++j) {
                                    accr[j] += sri[j] * yr - sii[j] * yi;
                                    acci[j] += sri[j] * yi + sii[j] * yr;
                                }
                            }
                        }
                        for (int64_t j = 0; j < nd; ++j) {
                            gr[j] += accr[j] * cr[j] - acci[j] * ci[j];
                            gi[j] += accr[j] * ci[j] + acci[j] * cr[j];
                        }
                    }
                }
            }
            for (int64_t g = 0; g < G; ++g) {   // interleave into out[n, g, j0:j0+nd]
                const float* gr = acc.data() + 2 * g * CH;
                const float* gi = gr + CH;
                float* o = P.out + 2 * ((n * G + g) * D + j0);
                for (int64_t j = 0; j < nd; ++j) { o[2 * j] = gr[j]; o[2 * j + 1] = gi[j]; }
            }
        }
    };
    run_threads(std::min(P.threads, items), work);
}

// Gated range transform: out[r, g] = sum_k x[r, k] W[g, k] for rows r of complex
// samples x [R, K] (complex64, interleaved) and the window-weighted DFT rows
// W [G, K] given planar (wr, wi, float32). Each thread de-interleaves one row
// into (xr, xi) so that the G dot products run at full vector width. Threads take
// blocks of DFT_ROWS rows in turn.
constexpr int64_t DFT_ROWS = 64;

static void gated_dft(const float* x, const float* wr, const float* wi, float* out, int64_t R,
                      int64_t K, int64_t G, int64_t threads) {
    std::atomic<int64_t> next{0};   // first row of the next block
    auto work = [&]() {
        std::vector<float> buf(2 * K);
        float* xr = buf.data();
        float* xi = xr + K;
        for (int64_t r0 = next.fetch_add(DFT_ROWS); r0 < R; r0 = next.fetch_add(DFT_ROWS)) {
            for (int64_t r = r0; r < std::min(R, r0 + DFT_ROWS); ++r) {
                const float* row = x + 2 * r * K;
                for (int64_t k = 0; k < K; ++k) { xr[k] = row[2 * k]; xi[k] = row[2 * k + 1]; }
                for (int64_t g = 0; g < G; ++g) {
                    const float* a = wr + g * K;
                    const float* b = wi + g * K;
                    float sr = 0.0f, si = 0.0f;
#pragma omp simd reduction(+ : sr, si)
                    for (int64_t k = 0; k < K; ++k) {
                        sr += xr[k] * a[k] - xi[k] * b[k];
                        si += xr[k] * b[k] + xi[k] * a[k];
                    }
                    out[2 * (r * G + g)] = sr;
                    out[2 * (r * G + g) + 1] = si;
                }
            }
        }
    };
    run_threads(std::min(threads, (R + DFT_ROWS - 1) / DFT_ROWS), work);
}

}  // namespace RT_NS
