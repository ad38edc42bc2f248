// Scene files (see scene_io.h and docs/scene-format.md).
//
// Parsing is strict: every key is known, every value has the documented type, every number is a
// finite float. Transforms are composed as  T * R * S  (scale first, then rotate, then
// translate), evaluated in double and rounded once to float. JSON is read by readJsonFile
// (json_read.h: duplicate keys, nesting and size bounded).
// Writing is deterministic: keys in a fixed order, numbers as the shortest decimal that reads
// back to the same double (every float is exactly a double), meshes as OFF (writeOff), a
// deforming object's frames as one positions file (positions_file.h).
#include "cullide/scene_io.h"

#include "cullide/error.h"
#include "cullide/file_io.h"
#include "cullide/json_read.h"
#include "cullide/mesh_io.h"
#include "cullide/positions_file.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <span>

namespace cullide {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using OrderedJson = nlohmann::ordered_json;

// 256 MiB: about five million objects.
constexpr JsonLimits kSceneJson{.kind = "a scene file", .maxBytes = uint64_t(256) << 20};

class SceneParser {
public:
    SceneParser(fs::path path) : path_(std::move(path)), src_(path_.string()), dir_(path_.parent_path()) {}

    Animation parse() {
        const Json root = readJsonFile(path_, kSceneJson);
        Animation a;
        requireObject(root, "the top level");
        allowKeys(root, "the top level", {"objects", "animation"});
        const Json& objects = requireKey(root, "objects", "the top level");
        if (!objects.is_array()) fail("'objects': expected an array, got " + typeName(objects));
        if (objects.empty()) fail("'objects' is empty: a scene needs at least one object");
        std::map<std::string, size_t> byName;
        for (size_t i = 0; i < objects.size(); ++i) {
            const std::string where = "objects[" + std::to_string(i) + "]";
            const Json& o = objects[i];
            requireObject(o, where);
            allowKeys(o, where, {"name", "mesh", "transform"});
            Object obj;
            obj.name = requireString(requireKey(o, "name", where), where + ".name");
            checkObjectName(obj.name, byName.contains(obj.name), src_, where);
            byName.emplace(obj.name, i);
            const std::string meshRef = requireString(requireKey(o, "mesh", where), where + ".mesh");
            // Instances of one mesh in a row read its file once.
            const bool again = i > 0 && meshRef == objects[i - 1]["mesh"];
            obj.mesh = again ? a.scene.objects.back().mesh : loadReferencedMesh(meshRef, "object '" + obj.name + "'");
            if (o.contains("transform")) obj.transform = parseTransform(o["transform"], where + ".transform");
            a.scene.objects.push_back(std::move(obj));
        }
        if (root.contains("animation")) parseAnimation(root["animation"], a, byName);
        validateAnimation(a, src_);
        return a;
    }

private:
    [[noreturn]] void fail(const std::string& cause) const { throw InputError(src_, cause); }

    static std::string typeName(const Json& j) { return j.type_name(); }

    void requireObject(const Json& j, const std::string& where) const {
        if (!j.is_object()) fail(where + ": expected an object, got " + typeName(j));
    }

    const Json& requireKey(const Json& j, const char* key, const std::string& where) const {
        const auto it = j.find(key);
        if (it == j.end()) fail(where + ": missing key '" + key + "'");
        return *it;
    }

    void allowKeys(const Json& j, const std::string& where, std::initializer_list<const char*> allowed) const {
        for (const auto& [key, value] : j.items()) {
            bool known = false;
            for (const char* a : allowed) known |= key == a;
            if (!known) {
                std::string list;
                for (const char* a : allowed) list += (list.empty() ? "'" : ", '") + std::string(a) + "'";
                fail(where + ": unknown key '" + key + "' (expected " + list + ")");
            }
        }
    }

    std::string requireString(const Json& j, const std::string& where) const {
        if (!j.is_string()) fail(where + ": expected a string, got " + typeName(j));
        return j.get<std::string>();
    }

    double requireNumber(const Json& j, const std::string& where) const {
        if (!j.is_number()) fail(where + ": expected a number, got " + typeName(j));
        const double d = j.get<double>();
        if (!std::isfinite(d) || !std::isfinite(static_cast<float>(d)))
            fail(where + ": " + j.dump() + " is not a finite float");
        return d;
    }

    Eigen::Vector3d requireVec3(const Json& j, const std::string& where) const {
        if (!j.is_array() || j.size() != 3)
            fail(where + ": expected an array of 3 numbers, got " + typeName(j) +
                 (j.is_array() ? " of size " + std::to_string(j.size()) : ""));
        return {requireNumber(j[0], where + "[0]"), requireNumber(j[1], where + "[1]"),
                requireNumber(j[2], where + "[2]")};
    }

    Transform parseTransform(const Json& j, const std::string& where) const {
        requireObject(j, where);
        allowKeys(j, where, {"translate", "rotate", "scale", "matrix"});
        Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
        if (j.contains("matrix")) {
            if (j.size() != 1) fail(where + ": 'matrix' cannot be combined with translate/rotate/scale");
            const Json& rows = j["matrix"];
            if (!rows.is_array() || rows.size() != 4) fail(where + ".matrix: expected 4 rows of 4 numbers (row-major)");
            for (int r = 0; r < 4; ++r) {
                const std::string rw = where + ".matrix[" + std::to_string(r) + "]";
                if (!rows[r].is_array() || rows[r].size() != 4) fail(rw + ": expected a row of 4 numbers");
                for (int c = 0; c < 4; ++c) m(r, c) = requireNumber(rows[r][c], rw + "[" + std::to_string(c) + "]");
            }
            if (m(3, 0) != 0 || m(3, 1) != 0 || m(3, 2) != 0 || m(3, 3) != 1)
                fail(where + ".matrix: the last row must be [0, 0, 0, 1] (an affine transform)");
        } else {
            Eigen::Vector3d scale(1, 1, 1);
            if (j.contains("scale")) {
                const Json& s = j["scale"];
                if (s.is_number()) scale.setConstant(requireNumber(s, where + ".scale"));
                else if (s.is_array()) scale = requireVec3(s, where + ".scale");
                else fail(where + ".scale: expected a number or an array of 3 numbers, got " + typeName(s));
            }
            Eigen::Matrix3d rot = Eigen::Matrix3d::Identity();
            if (j.contains("rotate")) {
                const Json& r = j["rotate"];
                const std::string rw = where + ".rotate";
                requireObject(r, rw);
                allowKeys(r, rw, {"axis", "degrees"});
                const Eigen::Vector3d axis = requireVec3(requireKey(r, "axis", rw), rw + ".axis");
                const double degrees = requireNumber(requireKey(r, "degrees", rw), rw + ".degrees");
                if (axis.norm() == 0) fail(rw + ".axis is the zero vector");
                rot = Eigen::AngleAxisd(degrees * std::numbers::pi / 180.0, axis.normalized()).toRotationMatrix();
            }
            Eigen::Vector3d t = Eigen::Vector3d::Zero();
            if (j.contains("translate")) t = requireVec3(j["translate"], where + ".translate");
            m.topLeftCorner<3, 3>() = rot * scale.asDiagonal();
            m.topRightCorner<3, 1>() = t;
        }
        Transform out;
        out.matrix() = m.cast<float>();
        if (!out.matrix().allFinite()) fail(where + ": the transform is not finite in float");
        return out;
    }

    fs::path referencedPath(const std::string& ref) const {
        return fs::path(ref).is_absolute() ? fs::path(ref) : dir_ / ref;
    }

    Mesh loadReferencedMesh(const std::string& ref, const std::string& what) const {
        const fs::path p = referencedPath(ref);
        try {
            return loadMesh(p);
        } catch (const InputError& e) {
            fail(what + ": " + e.what());
        }
    }

    // The frames, and the positions files that give deforming objects every frame: their frame
    // count is the animation's when `frames` is absent, and must be frames' when it is given.
    void parseAnimation(const Json& anim, Animation& a, const std::map<std::string, size_t>& byName) const {
        requireObject(anim, "'animation'");
        allowKeys(anim, "'animation'", {"positions", "frames"});
        const uint64_t fileFrames = anim.contains("positions") ? parsePositionsFiles(anim["positions"], a, byName) : 0;
        if (!anim.contains("frames")) {
            if (fileFrames == 0) (void)requireKey(anim, "frames", "'animation'");
            a.frames.resize(size_t(fileFrames));
            return;
        }
        const Json& frames = anim["frames"];
        if (!frames.is_array()) fail("animation.frames: expected an array, got " + typeName(frames));
        if (fileFrames != 0 && fileFrames != frames.size())
            fail("animation.positions: the positions files have " + std::to_string(fileFrames) +
                 " frames, but animation.frames has " + std::to_string(frames.size()) + " (wrong frame count)");
        for (size_t f = 0; f < frames.size(); ++f) a.frames.push_back(parseFrame(frames[f], f, a.scene, byName));
    }

    // animation.positions: object name -> positions file, each checked now (header, size, vertex
    // count, frame count) and its frames when sceneAt reads them. Returns their frame count (0:
    // none given).
    uint64_t parsePositionsFiles(const Json& j, Animation& a, const std::map<std::string, size_t>& byName) const {
        requireObject(j, "animation.positions");
        uint64_t frames = 0;
        std::string first;
        for (const auto& [name, ref] : j.items()) {
            const std::string where = "animation.positions." + name;
            const auto it = byName.find(name);
            if (it == byName.end()) fail(where + ": unknown object '" + name + "' (not in 'objects')");
            const std::string file = requireString(ref, where);
            const fs::path path = referencedPath(file);
            PositionsHeader h;
            try {
                h = PositionsFile(path).header();
            } catch (const InputError& e) {
                fail(where + ": " + e.what());
            }
            const size_t vertices = a.scene.objects[it->second].mesh.vertexCount();
            if (h.vertexCount != vertices)
                fail(where + ": '" + file + "' has " + std::to_string(h.vertexCount) + " vertices per frame, but object '" +
                     name + "' has " + std::to_string(vertices) + " (wrong vertex count)");
            if (frames != 0 && h.frameCount != frames)
                fail(where + ": '" + file + "' has " + std::to_string(h.frameCount) + " frames, but '" + first + "' has " +
                     std::to_string(frames) + " (wrong frame count)");
            if (frames == 0) frames = h.frameCount, first = file;
            a.positionsFiles.push_back({it->second, path.string()});
        }
        std::sort(a.positionsFiles.begin(), a.positionsFiles.end(),
                  [](const PositionsFileRef& x, const PositionsFileRef& y) { return x.object < y.object; });
        return frames;
    }

    Frame parseFrame(const Json& j, size_t f, const Scene& scene, const std::map<std::string, size_t>& byName) const {
        const std::string where = "animation.frames[" + std::to_string(f) + "]";
        requireObject(j, where);
        allowKeys(j, where, {"objects"});
        Frame frame;
        if (!j.contains("objects")) return frame;
        const Json& objs = j["objects"];
        requireObject(objs, where + ".objects");
        if (objs.empty()) return frame;
        frame.poses.resize(scene.objects.size());
        for (const auto& [name, pose] : objs.items()) {
            const auto it = byName.find(name);
            if (it == byName.end()) fail(where + ": unknown object '" + name + "' (not in 'objects')");
            const std::string pw = where + ".objects." + name;
            requireObject(pose, pw);
            allowKeys(pose, pw, {"transform", "positions"});
            ObjectPose& p = frame.poses[it->second];
            if (pose.contains("transform")) p.transform = parseTransform(pose["transform"], pw + ".transform");
            if (pose.contains("positions")) {
                const std::string ref = requireString(pose["positions"], pw + ".positions");
                Mesh m = loadReferencedMesh(ref, pw + ".positions");
                const size_t expected = scene.objects[it->second].mesh.positions.size();
                if (m.positions.size() != expected)
                    fail(pw + ".positions: '" + ref + "' has " + std::to_string(m.positions.size()) +
                         " vertices, but object '" + name + "' has " + std::to_string(expected) +
                         " (wrong position count)");
                const Object& object = scene.objects[it->second];
                checkPosePositions(m.positions, object, src_, where);
                checkWorldPositions(m.positions, p.transform ? *p.transform : object.transform, name, src_,
                                    "frame " + std::to_string(f));
                // Checked now, read again by sceneAt when the frame is used (ObjectPose).
                p.positionsFile = referencedPath(ref).string();
            }
        }
        return frame;
    }

    fs::path path_;
    std::string src_;
    fs::path dir_;
};

bool isMeshExtension(const fs::path& p) {
    try {
        (void)meshFormatFromPath(p);
        return true;
    } catch (const InputError&) {
        return false;
    }
}

OrderedJson transformJson(const Transform& t) {
    OrderedJson rows = OrderedJson::array();
    for (int r = 0; r < 4; ++r) {
        OrderedJson row = OrderedJson::array();
        for (int c = 0; c < 4; ++c) row.push_back(static_cast<double>(t.matrix()(r, c)));
        rows.push_back(std::move(row));
    }
    OrderedJson j;
    j["matrix"] = std::move(rows);
    return j;
}

// A file-name-safe version of an object name (the index in front keeps the names unique).
std::string safeName(const std::string& name) {
    std::string s;
    for (char c : name) s += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
    return s.substr(0, 64);
}

// The files a writeScene call created, removed again unless the call completes: a scene file
// that cannot be written leaves no meshes or positions files behind without it. (Files that were
// there before are overwritten, not removed: the call does not know what else uses them.)
class CreatedFiles {
public:
    CreatedFiles() = default;
    CreatedFiles(const CreatedFiles&) = delete;
    CreatedFiles& operator=(const CreatedFiles&) = delete;
    ~CreatedFiles() {
        std::error_code ec;
        if (!kept_)
            for (const fs::path& p : created_) fs::remove(p, ec);
    }
    // Writes `path` with write(path).
    void write(const fs::path& path, const std::function<void(const fs::path&)>& write) {
        std::error_code ec;
        const bool existed = fs::exists(fs::symlink_status(path, ec));
        write(path);
        if (!existed) created_.push_back(path);
    }
    void keep() { kept_ = true; }

private:
    std::vector<fs::path> created_;
    bool kept_ = false;
};

// Whether any frame changes object i's positions.
bool deforms(const Animation& a, size_t i) {
    if (a.positionsFileOf(i)) return true;
    for (const Frame& fr : a.frames)
        if (i < fr.poses.size() && (fr.poses[i].positions || !fr.poses[i].positionsFile.empty())) return true;
    return false;
}

// Object i's positions in every frame as one positions file at `path` (the base mesh's in the
// frames that leave them), read and written a frame at a time.
void writeObjectFrames(const Animation& a, size_t i, const fs::path& path) {
    const Mesh& base = a.scene.objects[i].mesh;
    if (base.vertexCount() > std::numeric_limits<uint32_t>::max())
        throw InputError(pathText(path), "object '" + a.scene.objects[i].name + "' has more than 2^32 - 1 vertices");
    if (a.frames.size() > kMaxPositionsFrames)
        throw InputError(pathText(path), std::to_string(a.frames.size()) + " frames, over the limit of " +
                                             std::to_string(kMaxPositionsFrames) + " for a positions file");
    std::optional<std::vector<Vec3f>> current;
    writePositionsFile(path, uint32_t(base.vertexCount()), a.frames.size(), [&](uint64_t f) {
        current = a.framePositions(size_t(f), i);
        return current ? std::span<const Vec3f>(*current) : std::span<const Vec3f>(base.positions);
    });
}

// The "animation" object: a positions file per deforming object, and the frames' transforms
// ("frames" left out when no frame gives one: the files say how many frames there are).
OrderedJson animationJson(const Animation& a, const fs::path& dir, const std::vector<std::string>& bases,
                          CreatedFiles& files) {
    OrderedJson positions = OrderedJson::object();
    for (size_t i = 0; i < a.scene.objects.size(); ++i) {
        if (!deforms(a, i)) continue;
        const std::string file = bases[i] + ".pos";
        files.write(dir / file, [&](const fs::path& p) { writeObjectFrames(a, i, p); });
        positions[a.scene.objects[i].name] = file;
    }
    OrderedJson frames = OrderedJson::array();
    bool anyTransform = false;
    for (const Frame& fr : a.frames) {
        OrderedJson poses = OrderedJson::object();
        for (size_t i = 0; i < fr.poses.size(); ++i)
            if (fr.poses[i].transform)
                poses[a.scene.objects[i].name] = OrderedJson{{"transform", transformJson(*fr.poses[i].transform)}};
        OrderedJson jf = OrderedJson::object();
        if (!poses.empty()) jf["objects"] = std::move(poses), anyTransform = true;
        frames.push_back(std::move(jf));
    }
    OrderedJson j = OrderedJson::object();
    if (!positions.empty()) j["positions"] = std::move(positions);
    if (anyTransform || j.empty()) j["frames"] = std::move(frames);
    return j;
}

}  // namespace

Animation loadScene(const fs::path& path) {
    if (isMeshExtension(path)) {
        Animation a;
        Object o;
        o.name = path.stem().string();
        o.mesh = loadMesh(path);
        a.scene.objects.push_back(std::move(o));
        return a;
    }
    std::string ext = path.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".json")
        throw InputError(path.string(),
                         "unknown scene format '" + ext + "' (expected .json, or a mesh file: .obj .off .ply .stl)");
    return SceneParser(path).parse();
}

void writeScene(const Animation& animation, const fs::path& path) {
    validateAnimation(animation, path.string());  // names too: frames refer to objects by name
    const fs::path dir = path.parent_path();
    const std::string stem = path.stem().string();
    OrderedJson root;
    OrderedJson objects = OrderedJson::array();
    std::vector<std::string> bases;
    CreatedFiles files;
    for (size_t i = 0; i < animation.scene.objects.size(); ++i) {
        const Object& o = animation.scene.objects[i];
        const std::string base = stem + "_" + std::to_string(i) + "_" + safeName(o.name);
        bases.push_back(base);
        files.write(dir / (base + ".off"), [&](const fs::path& p) { writeOff(o.mesh, p); });
        OrderedJson jo;
        jo["name"] = o.name;
        jo["mesh"] = base + ".off";
        if (o.transform.matrix() != Eigen::Matrix4f::Identity()) jo["transform"] = transformJson(o.transform);
        objects.push_back(std::move(jo));
    }
    root["objects"] = std::move(objects);
    if (!animation.frames.empty()) root["animation"] = animationJson(animation, dir, bases, files);
    writeFileAtomically(path, root.dump(2) + "\n");
    files.keep();
}

}  // namespace cullide
