#include "bvh_image.h"

#include <algorithm>
#include <deque>

namespace rtu {

BvhImage::BvhImage(std::vector<uint8_t> bytes, size_t decoded_budget) : owned_(std::move(bytes)) {
    data_ = owned_.data();
    size_ = owned_.size();
    decode(decoded_budget);
}

BvhImage BvhImage::view(const uint8_t* data, size_t size, size_t decoded_budget) {
    BvhImage b;
    b.data_ = data;
    b.size_ = size;
    b.decode(decoded_budget);
    return b;
}

BvhImage::BvhImage(const BvhImage& o)
    : stats(o.stats), owned_(o.owned_), data_(o.owned_.empty() ? o.data_ : owned_.data()), size_(o.size_), header_(o.header_),
      decoded_words_(o.decoded_words_), decoded_(o.decoded_) {}

BvhImage& BvhImage::operator=(const BvhImage& o) {
    if (this != &o) *this = BvhImage(o);
    return *this;
}

void BvhImage::decode(size_t decoded_budget) {
    if (size_ < kBlockBytes) throw std::runtime_error("BVH image too small");
    header_ = decode_header(data_);
    // Decode the internal nodes reachable from the root, through instance leaves into their
    // BLASes, once, breadth first, until the budget is spent. Nodes outside the image are left
    // alone: traversal reports them as before.
    const uint64_t blocks = size_ / kBlockBytes;
    std::vector<uint32_t> index(blocks, kNotDecoded);  // per block: its place in decoded_ while it is built
    const auto inside = [&](uint64_t addr, NodeType t) {
        return addr % kBlockBytes == 0 && addr + node_bytes(t) <= size_ && addr + node_bytes(t) > addr;
    };
    std::deque<uint64_t> todo;  // breadth first: the nodes near the root, visited most, come first
    const size_t cap = decoded_budget / sizeof(InternalNode);
    decoded_.clear();
    decoded_.reserve(std::min<uint64_t>(cap, blocks));
    const auto visit = [&](uint64_t addr) {
        if (decoded_.size() < cap && inside(addr, NodeType::Internal) && index[addr / kBlockBytes] == kNotDecoded) {
            index[addr / kBlockBytes] = uint32_t(decoded_.size());
            decoded_.push_back(decode_internal(data_ + addr));
            todo.push_back(addr);
        }
    };
    visit(header_.root);
    while (!todo.empty()) {
        const InternalNode& n = decoded_[index[todo.front() / kBlockBytes]];
        todo.pop_front();
        // Copy what is needed before visit() grows decoded_ (and moves n).
        const int count = n.count;
        const auto types = n.type;
        const auto addrs = n.addr;
        for (int i = 0; i < count && i < kMaxChildren; ++i) {
            if (types[i] == NodeType::Internal) visit(addrs[i]);
            if (types[i] == NodeType::Instance && inside(addrs[i], NodeType::Instance))
                visit(decode_instance(data_ + addrs[i]).blas_root);
        }
    }
    // Into address order, in place (each node moves along its cycle of the permutation), and the
    // bit map with each word's count of the decoded blocks before it.
    std::vector<uint32_t> place(decoded_.size());  // per breadth-first place: its place in address order
    uint32_t next = 0;
    decoded_words_.assign((blocks + 63) / 64, DecodedWord{});
    for (uint64_t b = 0; b < blocks; ++b) {
        if (b % 64 == 0) decoded_words_[b / 64].before = next;
        if (index[b] == kNotDecoded) continue;
        decoded_words_[b / 64].bits |= uint64_t(1) << (b % 64);
        place[index[b]] = next++;
    }
    for (uint32_t i = 0; i < place.size(); ++i)
        while (place[i] != i) {
            std::swap(decoded_[i], decoded_[place[i]]);
            std::swap(place[i], place[place[i]]);
        }
    decoded_.shrink_to_fit();
}

}  // namespace rtu
