// Option text -> CullideOptions (options.h).
#include "cullide/options.h"

#include "cullide/error.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <sstream>
#include <tuple>

namespace cullide {

namespace {

// Runs `parse`, re-throwing its InputError under `name` with the same cause: the pieces parsed
// elsewhere (method, depth format, hierarchy kind) name their own default source.
template <typename Parse>
auto named(const std::string& name, Parse&& parse) {
    try {
        return parse();
    } catch (const InputError& e) {
        const std::string what = e.what();
        const size_t prefix = e.source().size() + 2;  // "source: "
        throw InputError(name, what.size() >= prefix ? what.substr(prefix) : what);
    }
}

}  // namespace

std::pair<int, int> parseResolution(const std::string& text, const std::string& name) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) == 3 && (x == 'x' || x == 'X')) {
    } else if (std::sscanf(text.c_str(), "%d%c", &w, &extra) == 1) {
        h = w;
    } else {
        throw InputError(name, "cannot read '" + text + "' (expected N or WxH, e.g. 500 or 640x480)");
    }
    if (w < 1 || h < 1 || w > kMaxViewportSide || h > kMaxViewportSide)
        throw InputError(name,
                         "'" + text + "': each side must be 1 to " + std::to_string(kMaxViewportSide) + " pixels");
    return {w, h};
}

ResolutionSetting parseResolutionSetting(const std::string& text, const std::string& name) {
    ResolutionSetting r;
    if (text.rfind("auto", 0) != 0) {
        std::tie(r.width, r.height) = parseResolution(text, name);
        return r;
    }
    r.autoCoverage = kDefaultAutoCoverage;
    if (text == "auto") return r;
    const std::string k = text.size() > 5 && text[4] == ':' ? text.substr(5) : std::string();
    double value = 0;
    char extra = 0;
    if (k.empty() || k.find_first_not_of("0123456789.") != std::string::npos ||
        std::sscanf(k.c_str(), "%lf%c", &value, &extra) != 1)
        throw InputError(name, "cannot read '" + text + "' (expected auto or auto:K with a number K, e.g. auto:2)");
    if (!(value > 0 && value <= kMaxAutoCoverage))
        throw InputError(
            name,
            "'" + text + "': K must be more than 0 and at most " + std::to_string(int(kMaxAutoCoverage)) + " pixels");
    r.autoCoverage = value;
    return r;
}

DirectionMode parseDirectionMode(const std::string& text) {
    if (text == "pca") return DirectionMode::Pca;
    if (text == "coherent" || text.rfind("coherent:", 0) == 0) return DirectionMode::Coherent;
    return DirectionMode::Fixed;
}

std::vector<Vec3d> parseDirections(const std::string& text, const std::string& name) {
    if (text == "axes" || text == "pca" || text == "coherent") return axisDirections();
    if (text.rfind("coherent:", 0) == 0) {
        const std::string list = text.substr(9);
        if (list.empty() || list == "pca" || list.rfind("coherent", 0) == 0)
            throw InputError(name,
                             "'" + text +
                                 "': coherent takes a fixed list (coherent:axes, coherent:N or "
                                 "coherent:x,-y,z)");
        return parseDirections(list, name);
    }
    if (!text.empty() && std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; })) {
        if (text.size() > 6) throw InputError(name, "too many directions: " + text);
        return named(name, [&] { return spreadDirections(uint32_t(std::stoul(text))); });
    }
    std::vector<Vec3d> dirs;
    const char separator = text.find(';') != std::string::npos ? ';' : ',';
    std::stringstream items(text);
    std::string item;
    while (std::getline(items, item, separator)) {
        item.erase(0, item.find_first_not_of(' '));
        item.erase(item.find_last_not_of(' ') + 1);
        Vec3d d;
        if (item == "x" || item == "+x") d = Vec3d(1, 0, 0);
        else if (item == "-x") d = Vec3d(-1, 0, 0);
        else if (item == "y" || item == "+y") d = Vec3d(0, 1, 0);
        else if (item == "-y") d = Vec3d(0, -1, 0);
        else if (item == "z" || item == "+z") d = Vec3d(0, 0, 1);
        else if (item == "-z") d = Vec3d(0, 0, -1);
        else {
            std::stringstream nums(item);
            std::string rest;
            if (!(nums >> d.x() >> d.y() >> d.z()) || (nums >> rest))
                throw InputError(name,
                                 "cannot read direction '" + item +
                                     "' (expected axes, a count, or a list like x,-y,z or '1 0 0;0 1 1')");
        }
        if (!d.allFinite() || d.norm() == 0) throw InputError(name, "direction '" + item + "' is zero or not finite");
        dirs.push_back(d.normalized());
    }
    if (dirs.empty()) throw InputError(name, "no directions given");
    return dirs;
}

ExactSwitch parseExactSwitch(const std::string& text, const std::string& name) {
    ExactSwitch s;
    if (text == "never") return s;
    if (text == "auto") {
        s.kind = ExactSwitchKind::Auto;
        return s;
    }
    if (text.empty() || text.size() > 13 || text.find_first_not_of("0123456789") != std::string::npos)
        throw InputError(name, "cannot read '" + text + "' (expected never, auto or a triangle count N)");
    const unsigned long long n = std::stoull(text);
    if (n < 1 || n > 1'000'000'000'000ull)
        throw InputError(name, "'" + text + "': the triangle count must be 1 to 10^12");
    s.kind = ExactSwitchKind::Below;
    s.triangles = size_t(n);
    return s;
}

CullideOptions parseCullideOptions(const OptionText& text, const OptionNames& names) {
    CullideOptions o;
    o.method = named(names.method, [&] { return parseCullMethod(text.method); });
    const ResolutionSetting resolution = parseResolutionSetting(text.resolution, names.resolution);
    o.width = resolution.width, o.height = resolution.height, o.autoCoverage = resolution.autoCoverage;
    o.depth = named(names.depth, [&] { return DepthFormat::parse(text.depth); });
    o.directions = parseDirections(text.directions, names.directions);
    o.directionMode = parseDirectionMode(text.directions);
    o.hierarchy.kind = named(names.hierarchy, [&] { return parseHierarchyKind(text.hierarchy); });
    o.views = named(names.views, [&] { return parseViewMode(text.views); });
    if (text.leafSize < 1 || text.leafSize > kMaxLeafSize)
        throw InputError(names.leafSize,
                         std::to_string(text.leafSize) + ": the leaf size must be 1 to " +
                             std::to_string(kMaxLeafSize) + " triangles");
    if (text.branching < kMinBranching || text.branching > kMaxBranching)
        throw InputError(names.branching,
                         std::to_string(text.branching) + ": the branching must be " + std::to_string(kMinBranching) +
                             " to " + std::to_string(kMaxBranching));
    o.hierarchy.leafSize = text.leafSize;
    o.hierarchy.branching = text.branching;
    o.hierarchy.seed = text.seed;
    o.exactSwitch = parseExactSwitch(text.exactSwitch, names.exactSwitch);
    o.validate();  // nothing left to refuse: the checks above cover it
    return o;
}

// A depth format by name (declared with DepthFormat, depth_backend.h).
DepthFormat DepthFormat::parse(const std::string& text) {
    std::string t;
    for (char c : text) t.push_back(char(std::tolower(static_cast<unsigned char>(c))));
    if (t == "float" || t == "f32" || t == "d32f" || t == "float32") return float32();
    std::string digits = t;
    if (digits.rfind("unorm", 0) == 0) digits = digits.substr(5);
    else if (digits.rfind("d", 0) == 0) digits = digits.substr(1);
    const bool numeric = !digits.empty() && digits.size() <= 2 &&
        std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (!numeric)
        throw InputError("depth format", "'" + text + "' is not a depth format (use 8..32, d24, unorm16, float, d32f)");
    return unorm(std::stoi(digits));
}

int checkThreads(long long threads, const std::string& name) {
    if (threads < 0 || threads > kMaxThreads)
        throw InputError(name, std::to_string(threads) + " is not 0 (all cores) to " + std::to_string(kMaxThreads));
    return int(threads);
}

DepthFunc parseDepthFunc(const std::string& text, const std::string& name) {
    static const char* names[] = {"never", "less", "equal", "lequal", "greater", "notequal", "gequal", "always"};
    for (int i = 0; i < 8; ++i)
        if (text == names[i]) return DepthFunc(i);
    throw InputError(name,
                     "'" + text + "' is not one of never, less, equal, lequal, greater, notequal, gequal, always");
}

QueryKind parseQueryKind(const std::string& text, const std::string& name) {
    if (text == "samples") return QueryKind::SamplesPassed;
    if (text == "any") return QueryKind::AnySamplesPassed;
    throw InputError(name, "'" + text + "' is not 'samples' or 'any'");
}

}  // namespace cullide
