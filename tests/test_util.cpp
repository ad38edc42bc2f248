#include <cctype>
#include "test_util.h"

#include <atomic>
#include <stdexcept>
#include <unistd.h>

namespace cullide::test {

std::string testData(const char* relative) { return std::string(CULLIDE_TEST_DATA_DIR) + "/" + relative; }

TempDir::TempDir() {
    static std::atomic<unsigned> counter{0};
    const auto base = std::filesystem::temp_directory_path();
    for (int attempt = 0; attempt < 100; ++attempt) {
        auto p = base / ("cullide_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
        if (std::filesystem::create_directory(p)) {
            path_ = p;
            return;
        }
    }
    throw std::runtime_error("TempDir: cannot create a temporary folder");
}

TempDir::~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
}

}  // namespace cullide::test

namespace cullide::test {

std::string paramName(const std::string& path) {
    std::string name;
    for (char c : path) name += (std::isalnum(static_cast<unsigned char>(c)) ? c : '_');
    return name;
}

}  // namespace cullide::test
