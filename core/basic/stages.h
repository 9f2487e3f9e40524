#pragma once
// Technique basic: the handles of its stages (core/stage.h), declared once.
#include "core/image.h"
#include "core/stage.h"

namespace mesolab::basic::stages {
// The object's albedo map, read once and kept until its file or path changes (absent without one).
inline constexpr Stage<Image> albedo{"basic.albedo"};
}  // namespace mesolab::basic::stages
