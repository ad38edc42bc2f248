// Input files read whole, output files written all or nothing (see file_io.h).
#include "cullide/file_io.h"

#include "cullide/error.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

namespace cullide {

namespace fs = std::filesystem;

namespace {

// The cause of a failed open or stat, in the words of the other messages ("no such file").
std::string systemCause(int error) {
    if (error == ENOENT) return "no such file";
    std::string cause = std::strerror(error);  // ELOOP: "Too many levels of symbolic links"
    if (!cause.empty()) cause[0] = char(std::tolower(static_cast<unsigned char>(cause[0])));
    return cause;
}

void requireRegular(const std::string& src, mode_t mode) {
    if (S_ISREG(mode)) return;
    if (S_ISDIR(mode)) throw InputError(src, "cannot read: it is a directory, not a file");
    const char* kind = "a special file";
    if (S_ISFIFO(mode)) kind = "a FIFO";
    if (S_ISCHR(mode)) kind = "a character device";
    if (S_ISBLK(mode)) kind = "a block device";
    if (S_ISSOCK(mode)) kind = "a socket";
    throw InputError(src, std::string("cannot read: not a regular file (") + kind + ")");
}

[[noreturn]] void tooLarge(const std::string& src, uint64_t bytes, uint64_t maxBytes, std::string_view kind,
                           const char* what) {
    const uint64_t mib = maxBytes >> 20;
    const std::string limit = std::to_string(maxBytes) + " bytes" +
        (mib << 20 == maxBytes ? " (" + std::to_string(mib) + " MiB)" : std::string());
    throw InputError(src,
                     "cannot read: " + std::string(what) + std::to_string(bytes) + " bytes, over the limit of " +
                         limit + " for " + std::string(kind));
}

// Reads up to `n` bytes at `out`; fewer only at the end of the file.
size_t readSome(int fd, char* out, size_t n, const std::string& src) {
    size_t got = 0;
    while (got < n) {
        const ssize_t r = ::read(fd, out + got, n - got);
        if (r == 0) break;
        if (r < 0) {
            if (errno == EINTR) continue;
            throw InputError(src, std::string("cannot read: ") + std::strerror(errno));
        }
        got += size_t(r);
    }
    return got;
}

struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
};

}  // namespace

std::string pathText(const fs::path& path) {
    std::string text = path.native();
    for (size_t at = text.find('\0'); at != std::string::npos; at = text.find('\0', at + 2)) text.replace(at, 1, "\\0");
    return text;
}

uint64_t inputFileSize(const fs::path& path) {
    const std::string src = pathText(path);
    if (path.native().find('\0') != std::string::npos)
        throw InputError(src, "cannot open: the path contains a NUL byte");
    struct stat info;
    if (::stat(path.c_str(), &info) != 0) throw InputError(src, "cannot open: " + systemCause(errno));
    requireRegular(src, info.st_mode);
    return uint64_t(info.st_size);
}

std::string readFile(const fs::path& path, uint64_t maxBytes, std::string_view kind) {
    const std::string src = pathText(path);
    if (path.native().find('\0') != std::string::npos)
        throw InputError(src, "cannot open: the path contains a NUL byte");
    // Opened without waiting (O_NONBLOCK: a FIFO's open would wait for a writer), then what was
    // opened is checked; what cannot be opened (a socket) is named by inputFileSize.
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) {
        const int openErrno = errno;
        (void)inputFileSize(path);
        throw InputError(src, "cannot open: " + systemCause(openErrno));
    }
    const FdCloser closer{fd};
    struct stat info;
    if (::fstat(fd, &info) != 0) throw InputError(src, std::string("cannot read: ") + std::strerror(errno));
    requireRegular(src, info.st_mode);
    const uint64_t size = uint64_t(info.st_size);
    if (size > maxBytes) tooLarge(src, size, maxBytes, kind, "");
    std::string data;
    try {
        // The size is known: one buffer of that size, read into in place. Appending 64 KiB at a
        // time grew the string by doubling, copying it at each step: a 10 MB mesh touched about
        // twice its size in fresh pages, whose faults cost more than the parse (a virtual machine
        // may pay ~10 us per 4 KiB fault). The loop after it reads what a file that grew, or one
        // whose size says nothing (procfs), still holds, up to the limit.
        if (size > 0) {
            data.reserve(size_t(size));
            const uintptr_t at = reinterpret_cast<uintptr_t>(data.data()), huge = uintptr_t(2) << 20;
            const uintptr_t from = (at + huge - 1) & ~(huge - 1), to = (at + size_t(size)) & ~(huge - 1);
            if (to > from) ::madvise(reinterpret_cast<void*>(from), to - from, MADV_HUGEPAGE);
            data.resize(size_t(size));
            data.resize(readSome(fd, data.data(), data.size(), src));
        }
        char buf[1 << 16];
        while (const size_t n = readSome(fd, buf, sizeof buf, src)) {
            if (data.size() + n > maxBytes) tooLarge(src, data.size() + n, maxBytes, kind, "it grew to more than ");
            data.append(buf, n);
            if (n < sizeof buf) break;
        }
    } catch (const std::bad_alloc&) {
        throw InputError(src, "cannot read: out of memory for its " + std::to_string(size) + " bytes");
    }
    return data;
}

fs::path temporaryBeside(const fs::path& path) {
    static std::atomic<unsigned> counter{0};
    fs::path tmp = path;
    tmp += ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
    return tmp;
}

InputError cannotWrite(const fs::path& path, int err) {
    // The commonest cause, said plainly: the folder to write into is not there.
    const fs::path folder = path.parent_path();
    std::error_code ec;
    if (!folder.empty() && !fs::exists(folder, ec))
        return InputError(pathText(path), "folder " + folder.string() + " does not exist");
    return InputError(pathText(path), std::string("cannot write: ") + std::strerror(err));
}

void writeFileAtomically(const fs::path& path, std::string_view bytes) {
    const std::string src = pathText(path);
    if (path.native().find('\0') != std::string::npos)
        throw InputError(src, "cannot write: the path contains a NUL byte");
    const fs::path tmp = temporaryBeside(path);
    std::FILE* f = std::fopen(tmp.string().c_str(), "wb");
    if (!f) throw cannotWrite(path, errno);
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
