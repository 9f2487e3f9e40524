#pragma once
// [SECTION] Text for people: numbers formatted as printf does, byte counts in binary units.
#include <string>

namespace mesolab {

// printf into a std::string (any length): strprintf("%.2f MB", bytes / 1048576.0).
std::string strprintf(const char* format, ...) __attribute__((format(printf, 1, 2)));

// A byte count with a binary unit: "812 B", "3.5 KiB", "48.0 MiB", "1.50 GiB".
std::string format_bytes(double bytes);
}  // namespace mesolab
