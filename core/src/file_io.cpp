// Input files read whole, output files written all or nothing (see file_io.h).
#include "cullide/file_io.h"

#include "cullide/error.h"

#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

namespace cullide {

namespace fs = std::filesystem;

std::string readFile(const fs::path& path) {
    const std::string src = path.string();
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec || !fs::exists(st)) throw InputError(src, "cannot open: no such file");
    if (fs::is_directory(st)) throw InputError(src, "cannot read: it is a directory, not a file");
    std::FILE* f = std::fopen(src.c_str(), "rb");
    if (!f) throw InputError(src, std::string("cannot open: ") + std::strerror(errno));
    // A regular file's size is known: one buffer of that size, read into in place. Appending
    // 64 KiB at a time grew the string by doubling, copying it at each step: a 10 MB mesh touched
    // about twice its size in fresh pages, whose faults cost more than the parse (a virtual
    // machine may pay ~10 us per 4 KiB fault). The loop after it reads what a file that grew, a
    // pipe or a special file still holds.
    std::string data;
    struct stat info;
    if (::fstat(::fileno(f), &info) == 0 && S_ISREG(info.st_mode) && info.st_size > 0) {
        data.reserve(size_t(info.st_size));
        const uintptr_t at = reinterpret_cast<uintptr_t>(data.data()), huge = uintptr_t(2) << 20;
        const uintptr_t from = (at + huge - 1) & ~(huge - 1), to = (at + size_t(info.st_size)) & ~(huge - 1);
        if (to > from) ::madvise(reinterpret_cast<void*>(from), to - from, MADV_HUGEPAGE);
        data.resize(size_t(info.st_size));
        data.resize(std::fread(data.data(), 1, data.size(), f));
    }
    char buf[1 << 16];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) data.append(buf, n);
    const bool failed = std::ferror(f) != 0;
    std::fclose(f);
    if (failed) throw InputError(src, "cannot read: I/O error");
    return data;
}

void writeFileAtomically(const fs::path& path, std::string_view bytes) {
    static std::atomic<unsigned> counter{0};
    const std::string src = path.string();
    fs::path tmp = path;
    tmp += ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
    std::FILE* f = std::fopen(tmp.string().c_str(), "wb");
    if (!f) {
        const int openErrno = errno;
        // The commonest cause, said plainly: the folder to write into is not there.
        const fs::path folder = path.parent_path();
        std::error_code ec;
        if (!folder.empty() && !fs::exists(folder, ec))
            throw InputError(src, "folder " + folder.string() + " does not exist");
        throw InputError(src, std::string("cannot write: ") + std::strerror(openErrno));
    }
    const bool wrote = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
    const int writeErrno = errno;
    const bool closed = std::fclose(f) == 0;
    std::error_code ec;
    if (!wrote || !closed) {
        fs::remove(tmp, ec);
        throw InputError(src, std::string("cannot write: ") + std::strerror(wrote ? errno : writeErrno));
    }
    fs::rename(tmp, path, ec);
    if (ec) {
        std::error_code ignored;
        fs::remove(tmp, ignored);
        throw InputError(src, "cannot write: " + ec.message());
    }
}

}  // namespace cullide
