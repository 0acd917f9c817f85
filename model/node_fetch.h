// A node fetch as the RT unit sends it to memory (paper section 2.3; docs/paper-preset.md): a node
// larger than 32 B leaves as consecutive 32 B chunks, and the threads of one warp that fetch the
// same node in one scheduling share one fetch (intra-warp coalescing). Used by every fidelity.
// Plain C++ (no SystemC).
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "node_format.h"

namespace rtu {

constexpr uint32_t kChunkBytes = 32;

// With rt.leaf_descriptor_read (the TTP authors' simulator: vulkan_ray_tracing.cc ~l.1229, then
// ~l.1294 / ~l.1367), a primitive leaf is read in two dependent steps: first its 8 B descriptor
// (the 32 B chunk at the leaf's address), and when that has arrived and been decoded
// (rt.latency.leaf_descriptor), the whole 64 B leaf. Instance leaves are read whole.
inline bool read_in_two_steps(NodeType t, bool leaf_descriptor_read) {
    return leaf_descriptor_read && (t == NodeType::Triangle || t == NodeType::Procedural);
}
constexpr uint32_t kDescriptorChunks = 1;

// Chunks of a node of type `t`, and the address of chunk `c` of the node at `node`.
inline uint32_t chunks_of(NodeType t) { return node_bytes(t) / kChunkBytes; }
inline uint64_t chunk_address(uint64_t node, uint32_t c) { return node + uint64_t(c) * kChunkBytes; }

// A 32 B read leaving the RT unit, demand or prefetch.
struct ChunkRequest {
    uint64_t id = 0;       // unique per RT unit
    uint64_t addr = 0;     // 32 B aligned, in simulated memory
    uint64_t image_addr = 0;  // the same chunk in the BVH image (differs under the contiguous treelet layout)
    uint32_t warp = 0;     // warp-buffer slot
    uint32_t thread = 0;   // first thread waiting on the node (others coalesced onto it); prefetch: the thread that made it
    uint8_t streak = 0;    // pop-streak class of the node fetch (model/pop_streak.h)
    bool prefetch = false;
    bool more = false;     // demand: another chunk of the same read follows
    uint64_t deadline = ~0ull;  // a prefetch not sent by this cycle is dropped (Park: the end of the leaf test)
};

// The distinct fetches of one scheduling: each key (a node address, or whatever else must match
// for two fetches to be one) gets a group; a key seen before is coalesced into its group.
// Warps have at most a few dozen threads, so a linear search is the fastest.
template <class Key>
class FetchCoalescer {
public:
    void clear() { keys_.clear(); }
    // The group of `key` and whether it is new (false: coalesced with an earlier fetch).
    std::pair<uint32_t, bool> add(const Key& key) {
        for (uint32_t g = 0; g < keys_.size(); ++g)
            if (keys_[g] == key) return {g, false};
        keys_.push_back(key);
        return {uint32_t(keys_.size() - 1), true};
    }
    uint32_t groups() const { return uint32_t(keys_.size()); }
    const Key& key(uint32_t g) const { return keys_[g]; }

private:
    std::vector<Key> keys_;
};

}  // namespace rtu
