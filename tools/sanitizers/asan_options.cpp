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
