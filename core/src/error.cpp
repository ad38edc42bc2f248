#include "cullide/error.h"

#include <cstdio>
#include <cstdlib>

namespace cullide {

void checkFailed(const char* condition, const char* file, int line, const char* message) {
    std::fprintf(stderr, "cullide: internal error at %s:%d: check '%s' failed: %s\n", file, line, condition,
                 message ? message : "");
    std::abort();
}

}  // namespace cullide
