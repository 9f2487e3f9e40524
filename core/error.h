#pragma once
// Error types: InputError is bad input from the user (exit status 2), with one message naming
// the file / key / value and what was expected. Anything else is an internal failure (exit 1).
#include <stdexcept>
#include <string>
#include <vector>

namespace mesolab {

struct InputError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Bad input of one kind: work whose memory estimate is above the session's budget (the machine's
// available memory or --memory-limit; core/session.h). The message names the work, the figure and
// the parameters to lower.
struct MemoryBudgetError : InputError {
    using InputError::InputError;
};

// Thrown by a stage when its computation was cancelled.
struct Cancelled : std::runtime_error {
    Cancelled() : std::runtime_error("cancelled") {}
};

// "Did you mean" helper: the candidate with the smallest edit distance to `key`, or "" when
// none is close (distance > max(2, key.size()/3)).
std::string nearest_key(const std::string& key, const std::vector<std::string>& candidates);
}  // namespace mesolab
