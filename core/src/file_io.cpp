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

// What a file that is neither regular nor a folder is, for messages.
const char* specialKind(mode_t mode) {
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISCHR(mode)) return "a character device";
    if (S_ISBLK(mode)) return "a block device";
    if (S_ISSOCK(mode)) return "a socket";
    return "a special file";
}

void requireRegular(const std::string& src, mode_t mode) {
    if (S_ISREG(mode)) return;
    if (S_ISDIR(mode)) throw InputError(src, "cannot read: it is a directory, not a file");
    throw InputError(src, std::string("cannot read: not a regular file (") + specialKind(mode) + ")");
}

void refuseNul(const fs::path& path) {
    if (path.native().find('\0') != std::string::npos)
        throw InputError(pathText(path), "cannot write: the path contains a NUL byte");
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

OutputTarget outputTarget(const fs::path& path) {
    refuseNul(path);
    struct stat link {};
    if (::lstat(path.c_str(), &link) != 0) return {path};  // nothing there (or the open says why)
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {  // a symbolic link to nothing, replaced; or a loop
        if (errno == ELOOP) throw InputError(pathText(path), "cannot write: " + systemCause(ELOOP));
        return {path};
    }
    if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) return {};
    if (S_ISDIR(st.st_mode)) throw InputError(pathText(path), "cannot write: it is a directory, not a file");
    if (!S_ISREG(st.st_mode))
        throw InputError(pathText(path), std::string("cannot write: not a regular file (") + specialKind(st.st_mode) + ")");
    if (!S_ISLNK(link.st_mode)) return {path};
    std::error_code ec;
    const fs::path target = fs::canonical(path, ec);
    if (ec) throw InputError(pathText(path), "cannot write: " + ec.message());
    return {target};
}

namespace {

// The character device or FIFO at `path` opened for writing. Non-blocking at first, so that a FIFO
// nobody reads fails at once (ENXIO) instead of waiting for a reader.
std::FILE* openInPlace(const fs::path& path) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        if (errno == ENXIO) throw InputError(pathText(path), "cannot write: a FIFO that no process reads");
        throw cannotWrite(path, errno);
    }
    const int flags = ::fcntl(fd, F_GETFL);
    std::FILE* f = flags < 0 || ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0 ? nullptr : ::fdopen(fd, "wb");
    if (!f) {
        const int err = errno;
        ::close(fd);
        throw cannotWrite(path, err);
    }
    return f;
}

}  // namespace

OutputFile::OutputFile(const fs::path& path) : path_(path), target_(outputTarget(path)) {
    if (target_.inPlace()) {
        file_ = openInPlace(path_);
        return;
    }
    temporary_ = temporaryBeside(target_.renameOnto);
    file_ = std::fopen(temporary_.c_str(), "wb");
    if (!file_) throw cannotWrite(path_, errno);
}

OutputFile::~OutputFile() {
    if (file_) std::fclose(file_);
    std::error_code ec;
    if (!temporary_.empty()) fs::remove(temporary_, ec);
}

void OutputFile::write(std::string_view bytes) {
    if (writeError_ == 0 && std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size())
        writeError_ = errno ? errno : EIO;
}

void OutputFile::commit() {
    const bool closed = std::fclose(file_) == 0;
    const int closeError = errno;
    file_ = nullptr;
    if (writeError_ != 0 || !closed)
        throw InputError(pathText(path_), std::string("cannot write: ") + std::strerror(writeError_ ? writeError_ : closeError));
    if (target_.inPlace()) return;
    std::error_code ec;
    fs::rename(temporary_, target_.renameOnto, ec);
    if (ec) throw InputError(pathText(path_), "cannot write: " + ec.message());
    temporary_.clear();  // renamed: nothing for the destructor to remove
}

void writeFileAtomically(const fs::path& path, std::string_view bytes) {
    OutputFile out(path);
    out.write(bytes);
    out.commit();
}

}  // namespace cullide
