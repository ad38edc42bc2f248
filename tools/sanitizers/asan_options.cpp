// Default AddressSanitizer options for cullide's executables in sanitizer builds (linked in only
// when CMAKE_CXX_FLAGS holds -fsanitize=address; ASAN_OPTIONS in the environment is applied after
// these and wins).
//
// intercept_tls_get_addr=0: the sanitizer runtime of GCC 12 (Debian 12's; runtimes up to GCC 13 /
// LLVM 16 do this) records each dynamic TLS block that __tls_get_addr returns, and when the
// block's address is 16 bytes past a page boundary it assumes the header glibc 2.19-2.24 put
// there and reads the bounds from the two words before the block. Newer glibc has no header, so a
// block that malloc places at that offset by chance gets garbage bounds, and LeakSanitizer's
// stop-the-world tracer dies scanning them at exit ("Tracer caught signal 11"), after the test
// itself passed (google/sanitizers#1322). The GL tests load Mesa, whose TLS is such a dynamic
// block on every llvmpipe thread; whether one lands on the offset depends on the heap layout, so
// CI failed on it once while local runs passed. Reproduced here with a dlopen'ed library whose
// TLS block was steered to that offset: the same crash, gone with this option. Without the
// interceptor LeakSanitizer still scans every thread's stack and static TLS, not dynamic TLS.
extern "C" __attribute__((used, visibility("default"))) const char* __asan_default_options() {
    return "intercept_tls_get_addr=0";
}

// LeakSanitizer and the Vulkan drivers. The Vulkan loader dlopen()s the driver (Mesa's lavapipe,
// libvulkan_lvp.so) and the validation layer, and dlclose()s them when the instance goes; both keep
// a few small allocations of their own for the life of the process (under 2 KB per process in the
// Vulkan tests, 22 allocations). By exit the libraries are unmapped, so LeakSanitizer reports
// those allocations from "<unknown module>" and no suppression can name them. Loading the two
// libraries once more here with RTLD_NODELETE keeps them mapped (the loader's own dlopen() then
// shares that handle), so their frames keep their module names and the suppressions below match
// them, and nothing else: leaks with a frame in our code are still reported. Missing libraries
// (no Vulkan installed) are simply not loaded.
#include <dlfcn.h>

namespace {
__attribute__((constructor)) void keepVulkanDriversMapped() {
    static const char* const libs[] = {"libvulkan_lvp.so", "libVkLayer_khronos_validation.so"};
    for (const char* lib : libs) dlopen(lib, RTLD_LAZY | RTLD_LOCAL | RTLD_NODELETE);
}
}  // namespace

extern "C" __attribute__((used, visibility("default"))) const char* __lsan_default_suppressions() {
    return "leak:libvulkan_lvp.so\n"
           "leak:libVkLayer_khronos_validation.so\n";
}
