#pragma once
// The GUI's clock: elapsed time for frame timings, script time limits, toasts and progress.
#include <chrono>

namespace mesolab::gui {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
inline double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }
}  // namespace mesolab::gui
