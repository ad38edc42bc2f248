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

namespace cullide::test {

Scene sceneOf(std::initializer_list<std::pair<Mesh, Transform>> objects) {
    Scene s;
    int i = 0;
    for (const auto& [mesh, t] : objects) {
        std::string name = "o";  // (not "o" + to_string(): GCC 12 warns falsely, -Wrestrict)
        name += std::to_string(i++);
        s.objects.push_back({name, mesh, t});
    }
    return s;
}

Mesh box(const Vec3f& lo, const Vec3f& hi) {
    Mesh m;
    for (int i = 0; i < 8; ++i)
        m.positions.push_back(Vec3f(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z()));
    const uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : q) {
        m.triangles.push_back({f[0], f[1], f[2]});
        m.triangles.push_back({f[0], f[2], f[3]});
    }
    return m;
}

Transform rotation(double ax, double ay, double az, const Vec3f& translation) {
    Transform t = Transform::Identity();
    t.translate(translation);
    t.rotate(Eigen::AngleAxisf(float(az), Vec3f::UnitZ()) * Eigen::AngleAxisf(float(ay), Vec3f::UnitY()) *
             Eigen::AngleAxisf(float(ax), Vec3f::UnitX()));
    return t;
}

}  // namespace cullide::test
