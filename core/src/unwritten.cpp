// PageArena (cullide/unwritten.h): a call's arrays on transparent huge pages.
#include "cullide/unwritten.h"

#include <fstream>
#include <mutex>
#include <string>

namespace cullide {
namespace {

using Pages = UnwrittenAllocator<std::byte, true>;  // whole 2 MiB pages from kChunk on

// The chunks that ended arenas left, for the next arenas (PageArena::kPooled at most).
struct ChunkPool {
    std::mutex mutex;
    std::vector<std::byte*> free;
    ~ChunkPool() {  // at exit: back to the system (LeakSanitizer)
        for (std::byte* c : free) Pages().deallocate(c, PageArena::kChunk);
    }
};
ChunkPool& pool() {
    static ChunkPool p;
    return p;
}

}  // namespace

bool PageArena::available() {
#if defined(__SANITIZE_ADDRESS__)
    return false;
#else
    static const bool thp = [] {
        std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
        std::string line;
        if (!std::getline(in, line)) return false;
        return line.find("[always]") != std::string::npos || line.find("[madvise]") != std::string::npos;
    }();
    return thp;
#endif
}

void PageArena::releasePool() {
    ChunkPool& p = pool();
    std::lock_guard lock(p.mutex);
    for (std::byte* c : p.free) Pages().deallocate(c, kChunk);
    p.free.clear();
}

size_t PageArena::pooled() {
    ChunkPool& p = pool();
    std::lock_guard lock(p.mutex);
    return p.free.size();
}

PageArena::~PageArena() {
    ChunkPool& p = pool();
    std::lock_guard lock(p.mutex);
    for (std::byte* c : chunks_) {
        if (p.free.size() < kPooled) p.free.push_back(c);
        else Pages().deallocate(c, kChunk);
    }
}

void* PageArena::allocate(size_t bytes, size_t align) {
    if (bytes < kMinBytes) return ::operator new(bytes, std::align_val_t(align));
    if (bytes >= kChunk) return Pages().allocate(bytes);  // 2 MiB aligned
    // align <= 2 MiB: every chunk starts on a 2 MiB boundary.
    const auto aligned = [&](std::byte* p) {
        return reinterpret_cast<std::byte*>((reinterpret_cast<uintptr_t>(p) + align - 1) & ~uintptr_t(align - 1));
    };
    std::byte* p = next_ ? aligned(next_) : nullptr;
    if (!p || size_t(end_ - p) < bytes) {
        chunks_.reserve(chunks_.size() + 1);  // before taking the chunk: nothing to lose if it throws
        std::byte* chunk = nullptr;
        {
            ChunkPool& pl = pool();
            std::lock_guard lock(pl.mutex);
            if (!pl.free.empty()) chunk = pl.free.back(), pl.free.pop_back();
        }
        if (!chunk) chunk = Pages().allocate(kChunk);
        chunks_.push_back(chunk);
        p = chunk, end_ = chunk + kChunk;
    }
    next_ = p + bytes;
    return p;
}

void PageArena::deallocate(void* p, size_t bytes, size_t align) noexcept {
    if (bytes < kMinBytes) ::operator delete(p, std::align_val_t(align));
    else if (bytes >= kChunk) Pages().deallocate(static_cast<std::byte*>(p), bytes);
    else if (static_cast<std::byte*>(p) + bytes == next_) next_ = static_cast<std::byte*>(p);  // the latest
}

}  // namespace cullide
