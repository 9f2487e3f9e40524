#pragma once
// The figures of Heidrich et al. 2000 that microgeom's timings are compared with, each written
// once here: the stages show them beside ours (StageDecl::paper, the Timings panel) and the
// bench tables beside theirs (BenchRow::paper_ms, bench.cpp).
//  - Table 1: precomputation and rendering with 100 directions, for three heightfields; software
//    on an SGI Octane (300 MHz R12000), hardware rendering on a GeForce 256. The paper's seconds
//    are given here in ms.
//  - §6: the estimated time of a simulated BRDF of 16^4 goniometer images.
#include "core/stage.h"
#include <string>

namespace mesolab::microgeom::paper {

inline PaperFigure table1(double ms, const std::string& what) { return {ms, "Heidrich et al. 2000, Table 1: " + what}; }

// One row of Table 1 (one heightfield), a figure per column.
struct Table1Row {
    PaperFigure visibility;  // S_i precompute (software)
    PaperFigure shadows;     // shadow (ellipse) precompute (software)
    PaperFigure scattering;  // software render: scattering, depth 2, 100 samples
    PaperFigure frame;       // hardware render
};

inline const Table1Row kTriangles32{table1(27e3, "Triangles 32x32, 100 directions (SGI Octane)"),
                                    table1(32e3, "Triangles 32x32 shadow precompute (SGI Octane)"),
                                    table1(10e3, "Triangles 32x32, software render, 100 samples (SGI Octane)"),
                                    table1(480, "Triangles 32x32, hardware render (GeForce 256)")};
inline const Table1Row kBricks128{table1(1029e3, "Bricks 128x128, 100 directions (SGI Octane)"),
                                  table1(194e3, "Bricks 128x128 shadow precompute (SGI Octane)"),
                                  table1(12e3, "Bricks 128x128, software render, 100 samples (SGI Octane)"),
                                  table1(2100, "Bricks 128x128, hardware render (GeForce 256)")};
inline const Table1Row kBumps32{table1(109e3, "Bumps 32x32, 100 directions (SGI Octane)"),
                                table1(65e3, "Bumps 32x32 shadow precompute (SGI Octane)"),
                                table1(8e3, "Bumps 32x32, software render, 100 samples (SGI Octane)"),
                                table1(480, "Bumps 32x32, hardware render (GeForce 256)")};

// §6: a simulated BRDF of 16^4 images.
inline const PaperFigure kBrdf16{7.5 * 3600e3, "Heidrich et al. 2000, §6: a 16^4 BRDF would take about 7-8 hours (hardware, 2000)"};
}  // namespace mesolab::microgeom::paper
