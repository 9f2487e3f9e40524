#pragma once
// Computations under a chosen number of TBB threads, for tests that require a result not to depend
// on how the work was split: compare with_threads(1, f) against with_threads(kManyThreads, f).
// TBB allows more threads than the machine has cores, so the two runs split the work differently
// on any machine (the default thread count would equal 1 on a one-core machine).
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <cstddef>
#include <utility>

namespace mesolab::test {

constexpr int kManyThreads = 5;

// f() run in an arena of exactly `threads` threads (parallel loops inside f use that arena).
template <class F>
auto with_threads(int threads, F&& f) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    tbb::task_arena arena(threads);
    return arena.execute(std::forward<F>(f));
}
}  // namespace mesolab::test
