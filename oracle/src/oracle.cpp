// The exact oracle (see oracle.h): the grid's broad phase (broad_phase_grid.cpp), then the exact
// narrow phase (narrow_phase.h) on its candidates, per thread, merged and sorted.
#include "cullide/oracle/oracle.h"

#include "broad_phase.h"
#include "narrow_phase.h"
#include "cullide/error.h"
#include "cullide/predicates.h"

#include "cullide/parallel.h"

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>

namespace cullide::oracle {
namespace {

using detail::Box;
using detail::Candidate;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Coordinates beyond this are refused: Embree drops boxes beyond ~1.8e18, and the float filter's
// products stay far from overflow. Core's scenes are held to the same limit (scene.h).
constexpr double kMaxCoordinate = kMaxWorldCoordinate;

using detail::Prim;  // what the narrow phase reads of one primitive (narrow_phase.h)

using detail::Buffer;

struct ObjectData {
    ObjectData() = default;
    explicit ObjectData(PageArena* arena)
        : prims(ArenaAllocator<Prim>(arena)),
          boxes(ArenaAllocator<Box>(arena)),
          planes(ArenaAllocator<detail::Plane>(arena)) {}

    Buffer<Prim> prims;  // Embree primitive order = ascending triangle index
    Buffer<Box> boxes;  // one per primitive
    Buffer<detail::Plane> planes;  // one per primitive on small scenes (storedPlanesMax), else empty
};

struct Local {
    std::vector<IntersectingPair> pairs;
    size_t candidates = 0;
    std::vector<detail::Hit> hits;  // primContacts' output, room for a batch
};

struct Context {
    std::vector<ObjectData>& objects;  // the call's own, or its workspace's
    bool storedPlanes = false;  // ObjectData::planes filled
    std::vector<detail::StoredPrims> stored;  // per object its records and planes, when stored
    tbb::enumerable_thread_specific<Local> locals;
};

PairClass toClass(Contact c) {
    return c == Contact::Crossing ? PairClass::Crossing : PairClass::Touching;
}

// A pair that meets, triangles in ascending order in one object (primitives are in spatial order
// on large meshes, and the broad phase's pairs in its own).
void record(Local& local, const ObjectData* objects, const Candidate& c, Contact contact) {
    const Prim& a = objects[c.object0].prims[c.prim0];
    const Prim& b = objects[c.object1].prims[c.prim1];
    if (c.object0 == c.object1 && a.triangle > b.triangle)
        local.pairs.push_back({c.object0, b.triangle, c.object1, a.triangle, toClass(contact)});
    else local.pairs.push_back({c.object0, a.triangle, c.object1, b.triangle, toClass(contact)});
}

// The narrow phase, called concurrently by the broad phase with batches of candidates.
void narrowPhase(void* user, const Candidate* pairs, uint32_t count) {
    Context& ctx = *static_cast<Context*>(user);
    Local& local = ctx.locals.local();
    const ObjectData* const objects = ctx.objects.data();
    if (ctx.storedPlanes) {  // by batches, in sharing classes (primContacts)
        if (local.hits.size() < count) local.hits.resize(count);
        const uint32_t found =
            detail::primContacts(ctx.stored.data(), pairs, count, local.hits.data(), local.candidates);
        for (uint32_t h = 0; h < found; ++h) record(local, objects, pairs[local.hits[h].pair], local.hits[h].contact);
        return;
    }
    // One pair at a time, each first triangle's plane computed once per run of pairs that share
    // it (the grid hands over such runs).
    const Prim* last = nullptr;
    detail::Plane plane;
    // The second record of the pair kAhead on is fetched ahead: a random read (their misses were
    // a quarter of the narrow phase's time on a 46k mesh).
    constexpr uint32_t kAhead = 8;
    for (uint32_t k = 0; k < count; ++k) {
        const Candidate& c = pairs[k];
        if (k + kAhead < count) __builtin_prefetch(&objects[pairs[k + kAhead].object1].prims[pairs[k + kAhead].prim1]);
        // The broad phase reports each unordered pair once (the filter is for one reporting
        // both orders).
        if (!detail::inTestOrder(c)) continue;
        ++local.candidates;
        const Prim& a = objects[c.object0].prims[c.prim0];
        if (&a != last) plane = detail::planeOf(a), last = &a;
        const Contact contact =
            detail::primContact(a, plane, objects[c.object1].prims[c.prim1], nullptr, c.object0 == c.object1);
        if (contact != Contact::None) record(local, objects, c, contact);
    }
}

// Bit pattern of a float position, for welding.
std::array<uint32_t, 3> bits(const Vec3f& p) {
    return {std::bit_cast<uint32_t>(p.x()), std::bit_cast<uint32_t>(p.y()), std::bit_cast<uint32_t>(p.z())};
}

// Vertex -> the smallest index with the same bit pattern.
std::vector<uint32_t> weldMap(std::span<const Vec3f> positions) {
    std::vector<uint32_t> order(positions.size());
    for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        const auto ba = bits(positions[a]), bb = bits(positions[b]);
        return ba != bb ? ba < bb : a < b;
    });
    std::vector<uint32_t> map(positions.size());
    for (size_t k = 0; k < order.size(); ++k)
        map[order[k]] =
            (k > 0 && bits(positions[order[k]]) == bits(positions[order[k - 1]])) ? map[order[k - 1]] : order[k];
    return map;
}

// Bit i of q (10 bits) at bit 3i.
uint64_t spreadBits(uint64_t q) {
    q &= 0x3ff;
    q = (q | q << 16) & 0x30000ff;
    q = (q | q << 8) & 0x300f00f;
    q = (q | q << 4) & 0x30c30c3;
    q = (q | q << 2) & 0x9249249;
    return q;
}

// Sorts `kept` (triangle indices, ascending) by the Morton code of the triangles' first corner
// on a 2^10 grid over the mesh's bounds, ties by index: neighbours in space become neighbours in
// memory, which the narrow phase's random reads of primitive records need (cache misses).
void spatialOrder(std::span<const Vec3f> positions, std::span<const Triangle> triangles, Buffer<uint32_t>& kept) {
    if (kept.size() < 2) return;
    const size_t n = kept.size();
    // Bounds per fixed block, combined in block order (min/max: the same for any thread count).
    constexpr size_t kBlock = 16384;
    std::vector<std::array<float, 6>> blockBounds((n + kBlock - 1) / kBlock);
    parallelForEach(0, blockBounds.size(), [&](size_t blk) {
        const Vec3f& p0 = positions[triangles[kept[blk * kBlock]][0]];
        Vec3f lo = p0, hi = p0;
        for (size_t i = blk * kBlock, e = std::min(n, i + kBlock); i < e; ++i) {
            const Vec3f& p = positions[triangles[kept[i]][0]];
            lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
        }
        blockBounds[blk] = {lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z()};
    });
    std::array<float, 6> b = blockBounds[0];
    for (const auto& bb : blockBounds)
        for (int k = 0; k < 3; ++k) b[k] = std::min(b[k], bb[k]), b[3 + k] = std::max(b[3 + k], bb[3 + k]);
    Buffer<uint64_t> keys(n, kept.get_allocator()), tmp(n, kept.get_allocator());
    parallelFor(0, n, 4096, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            const Vec3f& p = positions[triangles[kept[i]][0]];
            uint64_t code = 0;
            for (int k = 0; k < 3; ++k) {
                const float extent = b[3 + k] - b[k];
                const uint64_t q =
                    extent > 0 ? std::min<uint64_t>(1023, uint64_t(double(p[k] - b[k]) / extent * 1024)) : 0;
                code |= spreadBits(q) << k;
            }
            keys[i] = code << 32 | kept[i];
            tmp[i] = 0;  // first touch here, in parallel
        }
    });
    const uint64_t* sorted = detail::radixSortHigh(keys.data(), tmp.data(), n, 30);
    for (size_t i = 0; i < n; ++i) kept[i] = uint32_t(sorted[i]);
}

}  // namespace

// What a Workspace keeps: per object its arrays, the world positions, the grid's arrays. A call
// without a workspace makes its own, from its PageArena when it has one.
struct Workspace::Impl {
    Impl() = default;
    explicit Impl(PageArena* a) : arena(a), world(ArenaAllocator<Vec3f>(a)), grid(a) {}

    PageArena* arena = nullptr;  // where the arrays come from (null: malloc)
    std::vector<ObjectData> objects;
    Buffer<Vec3f> world;
    detail::GridScratch grid;
};

Workspace::Workspace() = default;
Workspace::~Workspace() = default;
Workspace::Workspace(Workspace&&) noexcept = default;
Workspace& Workspace::operator=(Workspace&&) noexcept = default;

void Workspace::release() {
    impl_.reset();
}

Workspace::Impl& Workspace::impl() {
    if (!impl_) {  // first use, or after release() or a move
        impl_ = std::make_unique<Impl>();
        impl_->grid.keep = true;
    }
    return *impl_;
}

// Measured (docs/oracle.md): on the bench's meshes of 5.8k to 46k triangles the
// Morton order cost more (its sort, and the setup's and grid's reads through the permuted list)
// than it saved; on bunny75k it still saves a little.
size_t detail::spatialOrderMin = size_t(1) << 16;
size_t detail::storedPlanesMax = size_t(1) << 18;
detail::CallArena detail::callArena = detail::CallArena::WhereAvailable;

namespace {

// Whether a call without a workspace takes its arrays from its own PageArena (detail::callArena).
bool wantsCallArena() {
    using detail::CallArena;
    return detail::callArena == CallArena::Always ||
        (detail::callArena == CallArena::WhereAvailable && PageArena::available());
}

// The object's world positions (Scene::worldMesh's arithmetic, without copying the triangles) into
// `world`: one array for every object, freed after the last (a workspace's kept for the next call).
void toWorld(const Object& object, Buffer<Vec3f>& world) {
    const size_t nv = object.mesh.positions.size();
    world.clear();
    world.resize(nv);
    parallelFor(0, nv, 4096, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v)
            world[v] = applyTransform(object.transform, object.mesh.positions[v]);
    });
}

// Refuses what the oracle cannot decide on: a world coordinate that is not finite or beyond 2^60,
// a vertex index out of range.
void checkObject(const Object& object, std::span<const Vec3f> positions) {
    const std::string name = "object '" + object.name + "'";
    const std::span<const Triangle> triangles = object.mesh.triangles;
    const size_t n = triangles.size(), nv = positions.size();
    for (size_t v = 0; v < nv; ++v)
        for (int k = 0; k < 3; ++k) {
            const float x = positions[v][k];
            if (!std::isfinite(x))
                throw InputError("scene",
                                 name + ": vertex " + std::to_string(v) + " has a non-finite world coordinate");
            if (std::abs(double(x)) > kMaxCoordinate)
                throw InputError("scene",
                                 name + ": vertex " + std::to_string(v) +
                                     " has a world coordinate beyond 2^60, which the oracle cannot decide on");
        }
    for (size_t t = 0; t < n; ++t)
        if (triangles[t][0] >= nv || triangles[t][1] >= nv || triangles[t][2] >= nv)
            throw InputError("scene", name + ": triangle " + std::to_string(t) + " has a vertex index out of range");
}

// degen[t]: whether triangle t is degenerate (a repeated index, or collinear corners); each
// triangle's plane into d.planes[t] with `planesHere`. `only`: which triangles take part (null: all).
void findDegenerate(ObjectData& d, std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                    const std::vector<char>* only, bool planesHere, std::vector<char>& degen) {
    const size_t n = triangles.size();
    degen.assign(n, 0);
    parallelFor(0, n, 4096, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t) {
            if (only && !(*only)[t]) continue;
            const Triangle& tri = triangles[t];  // the file's indices: a repeat is degenerate
            const Vec3f &p0 = positions[tri[0]], &p1 = positions[tri[1]], &p2 = positions[tri[2]];
            const detail::Plane plane = detail::planeOf(p0, p1, p2);
            if (planesHere) d.planes[t] = plane;
            degen[t] = tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] ||
                (!detail::certainlyNotCollinear(plane) &&
                 collinear(p0.cast<double>(), p1.cast<double>(), p2.cast<double>()));
        }
    });
}

// The primitives' triangles into `kept` (ascending), the degenerate ones into truth.degenerate.
void keepTriangles(size_t o, const std::vector<char>* only, const std::vector<char>& degen, Buffer<uint32_t>& kept,
                   Truth& truth) {
    const size_t n = degen.size();
    kept.clear();
    kept.reserve(n);
    for (size_t t = 0; t < n; ++t) {
        if (only && !(*only)[t]) continue;
        if (degen[t]) truth.degenerate.push_back({uint32_t(o), uint32_t(t)});
        else kept.push_back(uint32_t(t));
    }
}

// The primitive records of the kept triangles, in kept's order, and their planes when stored
// (those of findDegenerate moved into primitive order with `planesHere`, else computed here).
void buildPrims(ObjectData& d, std::span<const Vec3f> positions, std::span<const Triangle> triangles,
                const Buffer<uint32_t>& kept, const std::vector<uint32_t>& vertexId, bool storedPlanes,
                bool planesHere) {
    const size_t n = triangles.size();
    if (planesHere && kept.size() < n) {  // in primitive order (kept[i] >= i: forward, in place)
        for (size_t i = 0; i < kept.size(); ++i) d.planes[i] = d.planes[kept[i]];
        d.planes.resize(kept.size());
    }
    d.prims.resize(kept.size());
    if (storedPlanes && !planesHere) d.planes.resize(kept.size());
    parallelFor(0, kept.size(), 4096, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            const uint32_t t = kept[i];
            const Triangle& tri = triangles[t];
            Prim& prim = d.prims[i];
            for (int k = 0; k < 3; ++k) {
                for (int c = 0; c < 3; ++c) prim.p[k][c] = positions[tri[k]][c];
                prim.v[k] = vertexId.empty() ? tri[k] : vertexId[tri[k]];
            }
            prim.triangle = t;
            const Vec3f &p0 = positions[tri[0]], &p1 = positions[tri[1]], &p2 = positions[tri[2]];
            if (storedPlanes && !planesHere) d.planes[i] = detail::planeOf(p0, p1, p2);
            prim.turns = detail::projectedTurns(p0, p1, p2, storedPlanes ? d.planes[i] : detail::planeOf(p0, p1, p2));
        }
    });
}

// Object o's primitive records (ctx.objects[o]): its world positions checked, its degenerate
// triangles into truth, the others' records in spatial order on large meshes. `degen` and `kept`:
// arrays reused from one object to the next.
void setupObject(Context& ctx, size_t o, const Object& object, const OracleOptions& options,
                 const std::vector<char>* only, Workspace::Impl& mem, std::vector<char>& degen, Buffer<uint32_t>& kept,
                 Truth& truth) {
    const std::span<const Triangle> triangles = object.mesh.triangles;
    const size_t n = triangles.size();
    toWorld(object, mem.world);
    const std::span<const Vec3f> positions = mem.world;
    checkObject(object, positions);

    ObjectData& d = ctx.objects[o];
    std::vector<uint32_t> vertexId;  // the vertex each index stands for in the sharing rules
    if (options.weldByPosition) vertexId = weldMap(positions);
    // The planes, whose products decide most triangles' degeneracy (collinear()'s filter), are
    // kept from this pass, per triangle, when they are stored and the primitives keep the
    // triangles' order (no spatial order): computed twice, they cost the cow's setup 0.30
    // against 0.28 ms (eight alternated runs of 200 calls, the medians).
    // clear() first: a longer array is allocated anew, not copied from the shorter one.
    const bool planesHere = ctx.storedPlanes && n <= detail::spatialOrderMin;
    d.prims.clear(), d.boxes.clear(), d.planes.clear();
    if (planesHere) d.planes.resize(n);
    findDegenerate(d, positions, triangles, only, planesHere, degen);
    keepTriangles(o, only, degen, kept, truth);
    if (kept.size() > detail::spatialOrderMin) spatialOrder(positions, triangles, kept);
    buildPrims(d, positions, triangles, kept, vertexId, ctx.storedPlanes, planesHere);
    truth.trianglesTested += d.prims.size();
}

// The object's fans (detail::certifyFans), then its primitives' boxes from the records.
void fansAndBoxes(ObjectData& d, size_t vertexCount, PageArena* arena) {
    detail::certifyFans(d.prims, vertexCount, arena);
    d.boxes.resize(d.prims.size());
    parallelFor(0, d.prims.size(), 4096, [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            const detail::Prim& prim = d.prims[i];
            Box& b = d.boxes[i];
            for (int k = 0; k < 3; ++k) {
                const float a = prim.p[0][k], bb = prim.p[1][k], c = prim.p[2][k];
                // Float corners: the exact box is a float box; one ulp outward keeps boxes
                // that only touch overlapping, whatever Embree's comparisons.
                b.lo[k] = detail::roundDown(std::min({a, bb, c}));
                b.hi[k] = detail::roundUp(std::max({a, bb, c}));
            }
        }
    });
}

// The broad phase (options.broadPhase) over every object's boxes, the narrow phase on its
// candidates into the threads' locals.
void broadAndNarrowPhase(Context& ctx, const OracleOptions& options, detail::GridScratch& grid, Truth& truth) {
    if (ctx.storedPlanes)
        for (const ObjectData& d : ctx.objects) ctx.stored.push_back({d.prims.data(), d.planes.data()});
    std::vector<std::span<const Box>> boxes(ctx.objects.size());
    for (size_t o = 0; o < ctx.objects.size(); ++o) boxes[o] = ctx.objects[o].boxes;
    const detail::BroadPhaseTimes bt = options.broadPhase == BroadPhase::Embree
        ? detail::collideAll(boxes, narrowPhase, &ctx)
        : detail::collideGrid(boxes, narrowPhase, &ctx, grid);
    truth.buildSeconds = bt.buildSeconds;
    truth.collideSeconds = bt.collideSeconds;
}

// The threads' pairs and candidate counts into truth, the pairs sorted.
void mergePairs(const Context& ctx, Truth& truth) {
    size_t total = 0;
    for (const Local& l : ctx.locals) total += l.pairs.size(), truth.candidatePairs += l.candidates;
    truth.pairs.reserve(total);
    for (const Local& l : ctx.locals) truth.pairs.insert(truth.pairs.end(), l.pairs.begin(), l.pairs.end());
    std::sort(truth.pairs.begin(), truth.pairs.end());
}

// `subset`: per object, which triangles take part (null: all).
Truth run(const Scene& scene, const OracleOptions& options, const std::vector<std::vector<char>>* subset,
          Workspace* workspace) {
    const auto t0 = Clock::now();
    Truth truth;
    // Without a workspace, the call's own arrays, from its own huge pages where it can
    // (cullide/unwritten.h's PageArena: fresh 4 KiB pages were half of a 23k-triangle call's time
    // when malloc had given its memory back); each large one freed as soon as it is no longer needed.
    std::optional<PageArena> arena;
    if (!workspace && wantsCallArena()) arena.emplace();
    Workspace::Impl own(arena ? &*arena : nullptr);
    Workspace::Impl& mem = workspace ? workspace->impl() : own;
    Context ctx{mem.objects, false, {}, {}};
    if (ctx.objects.size() > scene.objects.size()) ctx.objects.resize(scene.objects.size());
    while (ctx.objects.size() < scene.objects.size()) ctx.objects.emplace_back(mem.arena);
    size_t allTriangles = 0;
    for (const Object& object : scene.objects) allTriangles += object.mesh.triangles.size();
    ctx.storedPlanes = allTriangles <= detail::storedPlanesMax;
    std::vector<char> degen;  // per object, in turn
    Buffer<uint32_t> kept(ArenaAllocator<uint32_t>(mem.arena));  // per object, in turn
    for (size_t o = 0; o < scene.objects.size(); ++o)
        setupObject(ctx, o, scene.objects[o], options, subset ? &(*subset)[o] : nullptr, mem, degen, kept, truth);
    // Freed (the allocators swap with the storage: each array goes back through its own).
    Buffer<uint32_t>().swap(kept);
    std::vector<char>().swap(degen);
    if (!workspace) Buffer<Vec3f>().swap(mem.world);
    if (truth.trianglesTested > (size_t(1) << 29))
        throw InputError("scene",
                         std::to_string(truth.trianglesTested) +
                             " triangles to test: the oracle's broad phase takes at most 2^29 (536,870,912)");
    // The fans, then the boxes from the records, once those arrays are gone: the fans' scratch (4
    // bytes a corner) is never live beside them or the boxes (the 1M bunny's peak: docs/oracle.md,
    // "Fans").
    for (size_t o = 0; o < scene.objects.size(); ++o)
        fansAndBoxes(ctx.objects[o], scene.objects[o].mesh.positions.size(), mem.arena);
    truth.setupSeconds = since(t0);

    broadAndNarrowPhase(ctx, options, mem.grid, truth);

    const auto t1 = Clock::now();
    mergePairs(ctx, truth);
    truth.sortSeconds = since(t1);
    truth.totalSeconds = since(t0);
    return truth;
}

}  // namespace

const char* toString(PairClass c) {
    return c == PairClass::Crossing ? "crossing" : "touching";
}

size_t Truth::count(PairClass c) const {
    return size_t(std::count_if(pairs.begin(), pairs.end(), [c](const IntersectingPair& p) { return p.cls == c; }));
}

const char* toString(BroadPhase b) {
    return b == BroadPhase::Embree ? "embree" : "grid";
}

BroadPhase parseBroadPhase(const std::string& text) {
    if (text == "grid") return BroadPhase::Grid;
    if (text == "embree") return BroadPhase::Embree;
    throw InputError("option --broad-phase", "unknown broad phase '" + text + "' (expected grid or embree)");
}

Truth findIntersections(const Scene& scene, const OracleOptions& options, Workspace* workspace) {
    return run(scene, options, nullptr, workspace);
}

Truth exactStage(const Scene& scene, std::span<const TriangleRef> pcs, const OracleOptions& options,
                 Workspace* workspace) {
    std::vector<std::vector<char>> subset(scene.objects.size());
    for (size_t o = 0; o < scene.objects.size(); ++o) subset[o].assign(scene.objects[o].mesh.triangleCount(), 0);
    for (const TriangleRef& p : pcs) {
        if (p.object >= scene.objects.size() || p.triangle >= subset[p.object].size())
            throw InputError("pcs",
                             "entry (" + std::to_string(p.object) + ", " + std::to_string(p.triangle) +
                                 ") names no triangle of the scene");
        subset[p.object][p.triangle] = 1;
    }
    return run(scene, options, &subset, workspace);
}

}  // namespace cullide::oracle
