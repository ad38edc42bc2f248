#include <cctype>
#include "test_util.h"

#include <sys/wait.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <cmath>
#include <random>
#include <stdexcept>
#include <unistd.h>

namespace cullide::test {

std::string testData(const char* relative) {
    return std::string(CULLIDE_TEST_DATA_DIR) + "/" + relative;
}

std::string readBytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

void writeBytes(const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
}

CommandRun runCommand(const std::string& command) {
    CommandRun r;
    FILE* p = popen((command + " 2>&1").c_str(), "r");
    if (!p) return r;
    std::array<char, 4096> buf;
    size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
    const int status = pclose(p);
    r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return r;
}

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

namespace cullide::test {

Mesh nearlyCoplanarFans(uint32_t seed, int fans) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    std::uniform_int_distribution<int> ulps(-3, 3), pick(0, 9);
    Mesh m;
    for (int fan = 0; fan < fans; ++fan) {
        const uint32_t centre = uint32_t(m.positions.size());
        const Vec3f c(float(fan % 6) * 3, float(fan / 6) * 3, 0.5f);
        m.positions.push_back(c);
        const int k = 5 + fan % 4;
        for (int i = 0; i < k; ++i) {
            const float angle = float(i) * 6.2831853f / float(k) + 0.2f * u(rng);
            float z = c.z();
            for (int step = pick(rng) < 5 ? 0 : ulps(rng); step != 0; step += step > 0 ? -1 : 1)
                z = std::nextafter(z, step > 0 ? 1.0f : 0.0f);
            if (pick(rng) == 0) z += 0.05f * u(rng);  // now and then a real fold
            m.positions.push_back(c + Vec3f(std::cos(angle), std::sin(angle), z - c.z()));
        }
        for (int i = 0; i < k; ++i)
            m.triangles.push_back({centre, centre + 1 + uint32_t(i), centre + 1 + uint32_t((i + 1) % k)});
        // Two triangles across the fan from its centre: crossing, touching or apart.
        for (int extra = 0; extra < 2; ++extra) {
            const uint32_t a = uint32_t(m.positions.size());
            m.positions.push_back(c + Vec3f(u(rng), u(rng), 0.02f * u(rng)));
            m.positions.push_back(c + Vec3f(u(rng), u(rng), pick(rng) < 6 ? 0.0f : 0.02f * u(rng)));
            m.triangles.push_back({centre, a, a + 1});
        }
    }
    return m;
}

}  // namespace cullide::test
