// Errors, in two tiers (as pbrt-v4 does):
//   - InputError: bad input from a user (a file, a scene, an option). The message names the
//     source (file path, or "option --foo") and the cause. Loaders and parsers throw it; this
//     is their documented contract. The command-line tool catches it, prints it and exits 2.
//   - CULLIDE_CHECK: a broken invariant inside cullide (a bug). It prints the failed condition
//     with file and line and aborts; it is never used for user input.
#pragma once

#include <stdexcept>
#include <string>

namespace cullide {

class InputError : public std::runtime_error {
public:
    // `source`: the file (or option) the problem is in; `what`: the cause, in words.
    InputError(std::string source, const std::string& cause)
        : std::runtime_error(source + ": " + cause), source_(std::move(source)) {}

    const std::string& source() const noexcept { return source_; }

private:
    std::string source_;
};

[[noreturn]] void checkFailed(const char* condition, const char* file, int line, const char* message);

}  // namespace cullide

#define CULLIDE_CHECK(cond, msg)                                               \
    do {                                                                       \
        if (!(cond)) ::cullide::checkFailed(#cond, __FILE__, __LINE__, (msg)); \
    } while (0)
