// The viewport's reduced-size rendering during drags, without a window.
#include "app/gui/viewport.h"

#include <gtest/gtest.h>

using namespace mesolab;
using namespace mesolab::gui;

TEST(RenderRequest, FullSizeUnlessDraggingWithSlowFrames) {
    bool reduced = true;
    EXPECT_EQ(render_request({640, 480}, false, 1000.0, reduced), ivec2(640, 480));
    EXPECT_FALSE(reduced);
    EXPECT_EQ(render_request({640, 480}, true, kInteractiveBudgetMs * 0.5, reduced), ivec2(640, 480));
    EXPECT_FALSE(reduced);
    EXPECT_EQ(render_request({640, 480}, true, 0.0, reduced), ivec2(640, 480));  // no full-size frame timed yet
    EXPECT_FALSE(reduced);
}

TEST(RenderRequest, DragsWithSlowFramesDrawFewerPixelsToMeetTheBudget) {
    bool reduced = false;
    // Four times the budget: half of each side, a quarter of the pixels.
    EXPECT_EQ(render_request({640, 480}, true, kInteractiveBudgetMs * 4.0, reduced), ivec2(320, 240));
    EXPECT_TRUE(reduced);
    // Never below a quarter of each side, nor 16 pixels.
    EXPECT_EQ(render_request({640, 480}, true, kInteractiveBudgetMs * 1000.0, reduced), ivec2(160, 120));
    EXPECT_EQ(render_request({40, 40}, true, kInteractiveBudgetMs * 1000.0, reduced), ivec2(16, 16));
    EXPECT_TRUE(reduced);
}
