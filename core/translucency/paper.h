#pragma once
// The figures of Lensch et al. 2002 that mesolab shows beside its own, written once (Table 1:
// dual Xeon 1.7 GHz, GeForce 3, 512 x 512 atlas; times in ms).
#include "core/stage.h"

namespace mesolab::translucency::paper {

struct Table1Row {
    const char* model;
    int vertices;
    long form_factors;
    double fps, illumination_ms, local_ms, global_ms, display_ms, total_ms;
};

inline constexpr Table1Row kTable1[] = {
    {"horse", 10000, 16441460, 2.3, 29, 149, 371, 33, 431},
    {"horse textured", 10000, 12409116, 2.7, 29, 145, 302, 33, 364},
    {"bust", 8574, 4946764, 5.0, 24, 147, 144, 28, 199},
    {"bird", 4000, 1750862, 5.6, 16, 139, 86, 26, 180},
};
inline constexpr const char* kMachine = "dual Xeon 1.7 GHz + GeForce 3, 512 x 512 atlas";
// Preprocessing (§6): 1-2 min for the kernels, 2-8 min for the form factors.
inline constexpr double kKernelsMinMs = 60e3, kKernelsMaxMs = 120e3, kFactorsMinMs = 120e3, kFactorsMaxMs = 480e3;
}  // namespace mesolab::translucency::paper
