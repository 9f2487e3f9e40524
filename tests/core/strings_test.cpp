// core/strings.h: printf into strings of any length, byte counts, fields.
#include "core/strings.h"

#include <gtest/gtest.h>

using namespace mesolab;

TEST(Strings, PrintfWritesWholeStringsAnyLength) {
    EXPECT_EQ(strprintf("%.2f MB", 3.14159), "3.14 MB");
    const std::string wide(1000, 'x');
    EXPECT_EQ(strprintf("[%s]", wide.c_str()), "[" + wide + "]");  // longer than the stack buffer
    EXPECT_EQ(strprintf("%s", ""), "");
}

TEST(Strings, BytesInBinaryUnits) {
    EXPECT_EQ(format_bytes(812), "812 B");
    EXPECT_EQ(format_bytes(3.5 * 1024), "3.5 KiB");
    EXPECT_EQ(format_bytes(48.0 * 1024 * 1024), "48.0 MiB");
    EXPECT_EQ(format_bytes(1536.0 * 1024 * 1024), "1.50 GiB");
}

TEST(Strings, SplitKeepsEmptyFields) {
    EXPECT_EQ(split("a,,b,", ','), (std::vector<std::string>{"a", "", "b", ""}));
    EXPECT_EQ(split("light.intensity", '.'), (std::vector<std::string>{"light", "intensity"}));
    EXPECT_EQ(split("", ','), (std::vector<std::string>{""}));
}
