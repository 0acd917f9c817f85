// A BVH laid out in a flat byte image, as it sits in simulated memory.
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "node_format.h"

namespace rtu {

struct BvhStats {
    uint64_t internal_nodes = 0, triangle_leaves = 0, procedural_leaves = 0, instance_leaves = 0;
    uint32_t depth = 0;       // nodes on the longest root-to-leaf path, leaves included; two-level:
                              // TLAS internal levels + instance leaf + BLAS internal levels + leaf
    uint32_t tlas_depth = 0;  // internal levels of the TLAS (0 for a single-level BVH)
    uint64_t image_bytes = 0;
    uint32_t blas_count = 0;
    uint64_t repeats_left_out = 0;  // faces left out as copies of another beyond the builder's kCopiesKept
};

class BvhImage {
public:
    BvhImage() = default;
    // Host memory for the internal nodes decoded up front (decoded_internal). On the dragon
    // (290 k internal nodes) a 16 MB table of the top of the tree ran its traversal about as fast
    // as a table of all of them (60 MB): the host's caches hold the top, not the rest.
    static constexpr size_t kDecodedBudgetBytes = size_t(16) << 20;
    // An image that owns its bytes.
    explicit BvhImage(std::vector<uint8_t> bytes, size_t decoded_budget = kDecodedBudgetBytes);
    // A view of `size` bytes owned elsewhere (an image in a virtual platform's memory, or another
    // image's bytes); they must outlive the view and not change while it is used.
    static BvhImage view(const uint8_t* data, size_t size, size_t decoded_budget = kDecodedBudgetBytes);
    // A copy of an owning image owns a copy of the bytes; a copy of a view views the same bytes.
    BvhImage(const BvhImage& o);
    BvhImage& operator=(const BvhImage& o);
    BvhImage(BvhImage&&) noexcept = default;  // a vector's move keeps its buffer: data_ stays valid
    BvhImage& operator=(BvhImage&&) noexcept = default;

    const ImageHeader& header() const { return header_; }
    size_t size() const { return size_; }
    const uint8_t* data() const { return data_; }
    bool owns_bytes() const { return !owned_.empty(); }
    // Bytes of the node at `addr`; throws if [addr, addr+len) is outside the image.
    const uint8_t* at(uint64_t addr, uint32_t len) const {
        if (addr + len > size_ || addr + len < addr)
            throw std::out_of_range("BVH image read outside the image at " + std::to_string(addr));
        return data_ + addr;
    }
    // The internal node at `addr` decoded, or nullptr when it is not among those decoded up
    // front: the internal nodes reachable from the root, breadth first, within the budget (by
    // default all of them in scenes up to about 80 k internal nodes; in larger ones the top of
    // the tree, which most visits reach). Host-side only: traversal reads it instead of
    // decoding the same bytes on every visit (decode_internal is deterministic, so results are
    // unchanged); what the timing models fetch is still the node's 64 bytes.
    const InternalNode* decoded_internal(uint64_t addr) const {
        const uint64_t block = addr / kBlockBytes;
        if (addr % kBlockBytes != 0 || block / 64 >= decoded_words_.size()) return nullptr;
        // The decoded nodes sit in address order: a node's place is the decoded blocks before it,
        // counted in its word of the bit map (a bit per 64 B block, 16 B a word with the count
        // before it: 325 KB for party's 83 MB image, where an index of 4 B a block took 5.2 MB).
        const DecodedWord& w = decoded_words_[block / 64];
        const uint64_t bit = uint64_t(1) << (block % 64);
        if (!(w.bits & bit)) return nullptr;
        return &decoded_[w.before + uint32_t(__builtin_popcountll(w.bits & (bit - 1)))];
    }
    // Host memory of the nodes decoded up front and of their bit map.
    size_t decoded_bytes() const { return decoded_.capacity() * sizeof(InternalNode) + decoded_words_.capacity() * sizeof(DecodedWord); }

    BvhStats stats;

private:
    static constexpr uint32_t kNotDecoded = ~0u;
    void decode(size_t decoded_budget);
    struct DecodedWord {
        uint64_t bits = 0;    // bit b: block 64 x word + b is a decoded internal node
        uint32_t before = 0;  // decoded blocks in the words before this one
    };
    std::vector<uint8_t> owned_;  // empty for a view
    const uint8_t* data_ = nullptr;
    size_t size_ = 0;
    ImageHeader header_;
    std::vector<DecodedWord> decoded_words_;  // per 64 blocks of 64 B
    std::vector<InternalNode> decoded_;       // in address order
};

}  // namespace rtu
