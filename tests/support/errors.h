#pragma once
// Bad input is an InputError whose message names the file, key or value: the tests' check.
#include "core/error.h"

#include <gtest/gtest.h>
#include <initializer_list>
#include <string>

namespace mesolab::test {

// Runs `f`, expecting an InputError whose message contains every string in `parts`.
template <typename F>
void expect_input_error(F&& f, std::initializer_list<std::string> parts) {
    try {
        f();
        ADD_FAILURE() << "expected InputError";
    } catch (const InputError& e) {
        const std::string msg = e.what();
        for (const std::string& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "message: " << msg << "\nmissing: " << p;
    }
}
}  // namespace mesolab::test
