// Reading input files whole; writing output files all or nothing.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace cullide {

// The bytes of the file at `path`. Throws InputError(path, cause) when it cannot be read ("cannot
// open: no such file", "cannot read: it is a directory, not a file", an I/O error).
std::string readFile(const std::filesystem::path& path);

// Writes `bytes` to `path` through a temporary file beside it (unique per process and call)
// and a rename, so a reader never sees a half-written file and a failed write leaves nothing.
// Throws InputError(path, cause) when the file cannot be written ("folder F does not exist" when
// the folder it would go in is missing: folders are never created).
void writeFileAtomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace cullide
