// Parameters of one call of the real-time projection kernel (filled and checked
// in compensation/realtime.py, _compiled_project).
#pragma once
#include <cstdint>

namespace rt {

struct Params {
    // sizes
    int64_t N;        // chirps
    int64_t S;        // slots with channels (entries of slot_index / slot_line)
    int64_t n_tdm;    // TDM slots of the pose arrays (their second axis)
    int64_t D;        // directions
    int64_t G;        // gates
    int64_t NB;       // gate blocks
    int64_t M;        // channels (ordered slot after slot)
    int64_t M_max;    // most channels of one slot
    int64_t threads;
    // arrays
    const int64_t* slot_index;   // [S] TDM slot of each entry (pose index)
    const int64_t* slot_off;     // [S + 1] first channel of each slot in x / pos
    const int64_t* slot_line;    // [S] 1: p_i = p_0 + i a (Horner form); n1 >= 2: lattice
                                 // p_(i1 + n1 i2) = p_0 + i1 a + i2 b (two-step Horner); 0: general
    const int64_t* block_start;  // [NB + 1] first gate of each block
    const double* pos;           // [M, 3] virtual positions [m]
    const double* rot;           // [N, n_tdm, 3, 3] attitude (radar frame -> world)
    const double* disp;          // [N, n_tdm, 3] radar displacement [m]
    const double *ux, *uy, *uz;  // [D] grid directions
    const double* rg;            // [G] gate ranges [m]
    const double* block_r;       // [NB] focal (mean) range of each block [m]
    const float* x;              // [N, M, G] weighted gated data, complex64 (re, im)
    float* out;                  // [N, G, D] beams, complex64 (re, im)
    // scalars
    double k;                    // wavenumber 2 pi / lambda [rad/m]
    double small;                // largest per-gate phase for the float32 Taylor form [rad]
};

}  // namespace rt
