#pragma once
// Technique translucency's own internals shared by its files (other modules use translucency.h):
//   technique.cpp  parameters, stages, frame steps, CPU shading
//   frame.cpp      the atlas stage's extras, the gather table, rho and the per-frame CPU passes
//   bench.cpp      the timing table (Table 1) and its rows
//   paper.h        the paper's figures
#include "core/bench.h"
#include <vector>

namespace mesolab::translucency {
std::vector<BenchTable> translucency_bench_tables();
}  // namespace mesolab::translucency
