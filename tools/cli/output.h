// Writing the command's output files: all or nothing.
#pragma once

#include <filesystem>
#include <string_view>

namespace cullide::cli {

// Writes `bytes` to `path` through a temporary file in the same folder and a rename, so a
// reader never sees a half-written file. Throws InputError naming `path` on failure.
void writeFileAtomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace cullide::cli
