// Writing output files: all or nothing.
#pragma once

#include <filesystem>
#include <string_view>

namespace cullide {

// Writes `bytes` to `path` through a temporary file beside it (unique per process and call)
// and a rename, so a reader never sees a half-written file and a failed write leaves nothing.
// Throws InputError(path, cause) when the file cannot be written ("folder F does not exist" when
// the folder it would go in is missing: folders are never created).
void writeFileAtomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace cullide
