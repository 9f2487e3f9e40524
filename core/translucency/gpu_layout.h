#pragma once
// Technique translucency: the tables the GPU passes read, laid out here, on the CPU, where they are
// unit-tested without GL (tests/translucency/gpu_layout_test.cpp); gpu/translucency only uploads,
// binds and dispatches them.
//
// [SECTION] The factor rows of the global product (global.comp)
// The complete rows of F (expand_directed: both halves of the symmetric pairs), each padded with
// zero entries to a multiple of kRowQuantum: a buffer-texture texel holds two entries of a row, and
// the shader's eight invocations of a row read two texels each per step, so a row ends without a
// last partial step. The padding adds about 0.8% at the paper's densities (the bunny: 18.2
// million factors). A zero entry is column 0 with weight 0: it adds nothing.
//
// [SECTION] Pieces
// The rows in pieces whose entries fit one buffer texture (GL_MAX_TEXTURE_BUFFER_SIZE texels; one
// piece on every driver we know, 2^27 texels), each starting at a pair of entries whose 16-byte
// texel (two entries) and 4-byte high-column texel are both at a multiple of the offset alignment.
//
// [SECTION] The shown texels (combine.comp)
// Per non-empty texel of the atlas: the texel, the texel its value comes from (itself, or its fill
// source), the source's triangle's first two vertices, then the source's barycentrics and the
// third vertex (its int bits in a float, -1 where the source has no triangle).
#include "core/math.h"
#include "core/translucency/global.h"
#include "core/translucency/translucency.h"
#include <cstdint>
#include <vector>

namespace mesolab::translucency {

struct PaddedFactors {
    static constexpr int kRowQuantum = 32;  // entries: global.comp's 8 invocations x 2 texels x 2 entries
    std::vector<int> outer;                 // n + 1; every row starts at a multiple of kRowQuantum
    std::vector<uint64_t> entry;            // as VertexFactors::pair, rows padded, then 2 zero entries (a piece binds at least one pair)
    std::vector<uint16_t> col_hi;           // as VertexFactors::col_hi, likewise (empty below 65,536 vertices)
    int64_t pairs() const { return int64_t(outer.back()) / 2; }  // pairs of entries in the rows
    bool wide() const { return !col_hi.empty(); }
};
PaddedFactors pad_factor_rows(const VertexFactors& F);

struct FactorPiece {
    int r0 = 0, r1 = 0;  // rows [r0, r1)
    int64_t base = 0;    // its first pair of entries (a multiple of align_pairs)
    int64_t count = 0;   // pairs bound from base on
};
// `max_texels`: GL_MAX_TEXTURE_BUFFER_SIZE; `align_pairs`: GL_TEXTURE_BUFFER_OFFSET_ALIGNMENT in
// pairs of entries (the high-column texels, 4 bytes per pair, set the pace: (align + 3) / 4).
std::vector<FactorPiece> factor_pieces(const PaddedFactors& P, int64_t max_texels, int64_t align_pairs);

struct ShownTexels {
    std::vector<glm::ivec4> shown;  // (texel, source, vertex 0, vertex 1)
    std::vector<vec4> bary;         // (barycentrics of the source, vertex 2's bits)
};
ShownTexels shown_texels(const AtlasStage& A, const std::vector<uint32_t>& index);
}  // namespace mesolab::translucency
