#pragma once
// The figures of Daubert et al. 2001 that mesolab shows beside its own, written once (Athlon
// 1 GHz, GeForce 2 GTS; times in ms): the stages' timing lines and `mesolab bench cloth` read them.
#include "core/stage.h"

namespace mesolab::cloth::paper {

inline constexpr const char* kMachine = "Athlon 1 GHz / GeForce 2 GTS";
// §4: acquisition "15-45 min", the upper end.
inline constexpr double kAcquireMs = 45.0 * 60e3;
// §5: fitting "about 2.5 h".
inline constexpr double kFitMs = 2.5 * 3600e3;
// §7: "about 1 fps" at 730 x 400.
inline constexpr double kFrameMs = 1000.0;
inline constexpr int kFrameWidth = 730, kFrameHeight = 400;
// §7: the fitted representation's memory, "4 MB".
inline constexpr const char* kMemory = "4 MB";

inline PaperFigure acquire() { return {kAcquireMs, "Daubert 2001, §4: acquisition 15-45 min (Athlon 1 GHz)"}; }
inline PaperFigure fit() { return {kFitMs, "Daubert 2001, §5: fitting ~2.5 h (Athlon 1 GHz)"}; }
}  // namespace mesolab::cloth::paper
