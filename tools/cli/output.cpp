#include "output.h"

#include "cullide/error.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <unistd.h>

namespace cullide::cli {

void writeFileAtomically(const std::filesystem::path& path, std::string_view bytes) {
    const std::filesystem::path tmp = path.string() + ".tmp" + std::to_string(::getpid());
    {
        std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
        if (!f) throw InputError(path.string(), std::string("cannot write: ") + std::strerror(errno));
        f.write(bytes.data(), std::streamsize(bytes.size()));
        f.close();
        if (!f) {
            std::error_code ec;
            std::filesystem::remove(tmp, ec);
            throw InputError(path.string(), "cannot write (disk full?)");
        }
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        std::filesystem::remove(tmp, ec);
        throw InputError(path.string(), "cannot write: " + ec.message());
    }
}

}  // namespace cullide::cli
