// Test include: found beside test/fill.comp; itself includes shaders/common.glsl twice (the
// second include is skipped).
#include "common.glsl"
#include "../common.glsl"
const float OFFSET = 0.5 * PI;
