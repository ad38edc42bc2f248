// Study specs from JSON (study.h): every field checked here, before anything runs, so that a bad
// spec is an InputError naming the field (exit status 2), never an exception from deep inside.
#include "cullide/study/study.h"

#include "cullide/cullide.h"
#include "cullide/error.h"
#include "cullide/hierarchy.h"
#include "cullide/raster/backends.h"

#include <algorithm>
#include <fstream>
#include <string>

namespace cullide::study {
namespace {

using Json = nlohmann::json;

// Reads the fields of one spec; every error names the file and the field.
class FieldReader {
public:
    explicit FieldReader(const std::string& source) : source_(source) {}

    [[noreturn]] void fail(const std::string& key, const std::string& cause) const {
        throw InputError(source_, "field '" + key + "': " + cause);
    }

    // A list field's items: a list (not empty), or one value standing for a list of one.
    std::vector<Json> items(const Json& v, const std::string& key) const {
        if (!v.is_array()) return {v};
        if (v.empty()) fail(key, "an empty list (give at least one value, or leave the field out)");
        return {v.begin(), v.end()};
    }

    // A single-valued field: a value, or a list of exactly one.
    const Json& single(const Json& v, const std::string& key) const {
        if (!v.is_array()) return v;
        if (v.size() != 1) fail(key, "expected one value, not a list of " + std::to_string(v.size()));
        return v[0];
    }

    // A JSON integer in [lo, hi] (2.5, "3", true and integers beyond the range are refused).
    int64_t integer(const Json& v, const std::string& key, int64_t lo, int64_t hi) const {
        const std::string range = "expected an integer from " + std::to_string(lo) + " to " + std::to_string(hi);
        if (!v.is_number_integer()) fail(key, range + ", not " + v.dump());
        if (v.is_number_unsigned() ? v.get<uint64_t>() > uint64_t(hi) : v.get<int64_t>() < lo || v.get<int64_t>() > hi)
            fail(key, range + ", not " + v.dump());
        return v.is_number_unsigned() ? int64_t(v.get<uint64_t>()) : v.get<int64_t>();
    }

    std::string text(const Json& v, const std::string& key) const {
        if (!v.is_string() || v.get<std::string>().empty()) fail(key, "expected a non-empty string, not " + v.dump());
        return v.get<std::string>();
    }

    // A string, or an integer in [lo, hi] written as its decimal text (resolutions, depths,
    // directions accept both).
    std::string textOrInteger(const Json& v, const std::string& key, int64_t lo, int64_t hi) const {
        return v.is_number() ? std::to_string(integer(v, key, lo, hi)) : text(v, key);
    }

    // Runs a core parser on a value, its InputError restated as the field's.
    template <typename Parse>
    void check(const std::string& key, const std::string& value, Parse parse) const {
        try {
            (void)parse(value);
        } catch (const InputError& e) {
            const std::string what = e.what();
            fail(key, "'" + value + "': " + what.substr(std::min(what.size(), e.source().size() + 2)));
        }
    }

private:
    std::string source_;
};

}  // namespace

Spec parseSpec(const nlohmann::json& j, const std::string& source) {
    if (!j.is_object()) throw InputError(source, "a study spec is a JSON object");
    const FieldReader r(source);
    Spec s;
    for (const auto& [key, v] : j.items()) {
        if (key == "scenes") {
            s.scenes.clear();
            for (const Json& x : r.items(v, key)) s.scenes.push_back(r.text(x, key));
        } else if (key == "methods") {
            s.methods.clear();
            for (const Json& x : r.items(v, key)) s.methods.push_back(r.text(x, key));
            for (const std::string& m : s.methods) r.check(key, m, parseCullMethod);
        } else if (key == "resolutions") {
            s.resolutions.clear();
            for (const Json& x : r.items(v, key)) s.resolutions.push_back(r.textOrInteger(x, key, 1, 16384));
            for (const std::string& t : s.resolutions) r.check(key, t, parseResolution);
        } else if (key == "depths") {
            s.depths.clear();
            for (const Json& x : r.items(v, key)) s.depths.push_back(r.textOrInteger(x, key, 8, 32));
            for (const std::string& t : s.depths) r.check(key, t, DepthFormat::parse);
        } else if (key == "directions") {
            s.directions.clear();
            for (const Json& x : r.items(v, key)) s.directions.push_back(r.textOrInteger(x, key, 1, 10000));
            for (const std::string& t : s.directions) r.check(key, t, parseDirections);
        } else if (key == "hierarchies") {
            s.hierarchies.clear();
            for (const Json& x : r.items(v, key)) s.hierarchies.push_back(r.text(x, key));
            for (const std::string& t : s.hierarchies) r.check(key, t, parseHierarchyKind);
        } else if (key == "leaf_sizes") {
            s.leafSizes.clear();
            for (const Json& x : r.items(v, key)) s.leafSizes.push_back(uint32_t(r.integer(x, key, 1, 1'000'000)));
        } else if (key == "backends") {
            s.backends.clear();
            for (const Json& x : r.items(v, key)) s.backends.push_back(r.text(x, key));
            for (const std::string& b : s.backends)
                if (!raster::isBackendName(b)) r.fail(key, "'" + b + "': " + raster::backendNameList());
        } else if (key == "threads") {
            s.threads.clear();
            for (const Json& x : r.items(v, key)) s.threads.push_back(int(r.integer(x, key, 0, 1024)));
        } else if (key == "branching") {
            s.branching = uint32_t(r.integer(r.single(v, key), key, 2, 64));
        } else if (key == "seed") {
            const Json& x = r.single(v, key);
            if (!x.is_number_unsigned()) r.fail(key, "expected an integer from 0 to 2^64 - 1, not " + x.dump());
            s.seed = x.get<uint64_t>();
        } else if (key == "repeats") {
            s.repeats = int(r.integer(r.single(v, key), key, 1, 1000));
        } else if (key == "oracle") {
            if (!v.is_boolean()) r.fail(key, "true or false, not " + v.dump());
            s.oracle = v.get<bool>();
        } else {
            throw InputError(source, "unknown field '" + key + "' (fields: scenes, methods, resolutions, depths, "
                                     "directions, hierarchies, leaf_sizes, backends, threads, branching, seed, "
                                     "repeats, oracle)");
        }
    }
    return s;
}

Spec loadSpec(const std::string& path) {
    std::ifstream f(path);
    if (!f) throw InputError(path, "cannot open the study spec");
    try {
        return parseSpec(nlohmann::json::parse(f), path);
    } catch (const nlohmann::json::parse_error& e) {
        throw InputError(path, std::string("not JSON: ") + e.what());
    }
}

}  // namespace cullide::study
