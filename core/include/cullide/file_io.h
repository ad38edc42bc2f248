// Reading input files whole; writing output files all or nothing.
#pragma once

#include "cullide/error.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

namespace cullide {

// The largest input file read whole unless a reader says otherwise (meshes: 4 GiB holds a binary
// STL of 85 million triangles, more than the 2^32 vertices a mesh may index).
inline constexpr uint64_t kMaxInputFileBytes = uint64_t(4) << 30;

// `path` as messages show it: a NUL byte in it written as "\0" (a C string would end there).
std::string pathText(const std::filesystem::path& path);

// The size of the regular file at `path`, which an input reader may then open. Only regular files
// are input: opening a FIFO blocks until a writer comes, a device never ends. Throws
// InputError(pathText(path), cause): "cannot open: no such file", "cannot open: too many levels of
// symbolic links", "cannot open: the path contains a NUL byte", "cannot read: it is a directory,
// not a file", "cannot read: not a regular file (a FIFO)" (a character device, a block device, a
// socket), or the system's cause.
uint64_t inputFileSize(const std::filesystem::path& path);

// The bytes of the regular file at `path` (inputFileSize's checks), at most `maxBytes` of them:
// a larger file is refused before it is read ("N bytes, over the limit of M bytes for `kind`").
// Also InputError(path, cause) for an I/O error, or no memory for its bytes.
std::string readFile(const std::filesystem::path& path, uint64_t maxBytes = kMaxInputFileBytes,
                     std::string_view kind = "an input file");

// Writes `bytes` to `path` through a temporary file beside it (unique per process and call)
// and a rename, so a reader never sees a half-written file and a failed write leaves nothing;
// into a character device or FIFO in place (outputTarget).
// Throws InputError(path, cause) when the file cannot be written ("folder F does not exist" when
// the folder it would go in is missing: folders are never created).
void writeFileAtomically(const std::filesystem::path& path, std::string_view bytes);

// Where an output at `path` is written. Nothing there, or a regular file: a temporary beside it,
// renamed into place (`renameOnto`: `path`, or the file a symbolic link at `path` leads to, so
// that the link stays a link). A character device or a FIFO (/dev/null; /dev/stdout on a pipe or
// a terminal): in place, since renaming a file onto it would replace the device itself. Throws
// InputError(pathText(path), cause) for a folder, a block device, a socket or a NUL byte.
struct OutputTarget {
    std::filesystem::path renameOnto;  // empty: written in place
    bool inPlace() const { return renameOnto.empty(); }
};
OutputTarget outputTarget(const std::filesystem::path& path);

// An output being written all or nothing at `path` (outputTarget): into a temporary beside it
// that commit() renames into place and that goes, unnamed, if the object goes first; or in place
// into a device or FIFO (one that no process reads is refused, not waited for). Throws
// InputError(pathText(path), cause): a failed open, write or rename, said with its cause.
class OutputFile {
public:
    explicit OutputFile(const std::filesystem::path& path);
    ~OutputFile();
    OutputFile(const OutputFile&) = delete;
    OutputFile& operator=(const OutputFile&) = delete;

    // Appends `bytes`; a failure is kept and said by commit(), and later writes are skipped.
    void write(std::string_view bytes);
    bool failed() const { return writeError_ != 0; }
    // Closes the file and renames it into place.
    void commit();

private:
    std::filesystem::path path_, temporary_;  // temporary_ empty: written in place
    OutputTarget target_;
    std::FILE* file_ = nullptr;
    int writeError_ = 0;  // the errno of the first failed write
};

// A fresh name beside `path` for the temporary an all-or-nothing write renames into place:
// "<path>.tmp.<pid>.<n>", unique per process and call.
std::filesystem::path temporaryBeside(const std::filesystem::path& path);

// Why `path` cannot be written, from the errno of the failed open or write: "folder F does not
// exist" when that is why (folders are never created), else "cannot write: <strerror>".
InputError cannotWrite(const std::filesystem::path& path, int err);

}  // namespace cullide
