#pragma once
// [SECTION] Parallel loops that keep the read contract.
// mesolab's loops over pixels, texels, faces and photons run on TBB's worker threads. A session
// checks that a stage reads only the keys it declares by watching every ParamTable read on the
// thread that runs it (core/param.h, ParamReadScope); a read made inside a task on another thread
// would escape that watch. These wrappers carry the caller's watch into every task, so a key read
// anywhere in a stage, a frame step or the truth is checked the same way.
//
// core/, gpu/ and app/ call these, never tbb::parallel_for directly (a test greps the sources).
#include "core/param.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace mesolab {

// body(subrange) for the parts of `range`, as tbb::parallel_for(range, body).
template <class Range, class Body>
void parallel_for(const Range& range, const Body& body) {
    ParamReadWatch* watch = current_read_watch();
    if (!watch) {
        tbb::parallel_for(range, body);
        return;
    }
    tbb::parallel_for(range, [&body, watch](const Range& r) {
        ParamReadScope scope(watch);
        body(r);
    });
}

// f(i) for i in [first, last), as tbb::parallel_for(first, last, f).
template <class Index, class F>
void parallel_for(Index first, Index last, const F& f) {
    ParamReadWatch* watch = current_read_watch();
    if (!watch) {
        tbb::parallel_for(first, last, f);
        return;
    }
    tbb::parallel_for(first, last, [&f, watch](Index i) {
        ParamReadScope scope(watch);
        f(i);
    });
}
}  // namespace mesolab
