// Writes a file atomically: to a temporary file beside it, then rename(2). A reader (or a
// run interrupted half-way) sees the old file or the new one, never a torn one.
#pragma once

#include <string>
#include <string_view>

namespace tb {

// Throws std::runtime_error naming the path when writing fails. Creates parent folders.
void write_file_atomic(const std::string& path, std::string_view contents);
// Reads a whole file; throws std::runtime_error naming the path when it cannot be read.
std::string read_file(const std::string& path);

}  // namespace tb
