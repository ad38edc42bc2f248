// Output files, all or nothing (see file_io.h).
#include "cullide/file_io.h"

#include "cullide/error.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

namespace cullide {

namespace fs = std::filesystem;

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
