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
      decoded_index_(o.decoded_index_), decoded_(o.decoded_) {}

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
    decoded_index_.assign(size_ / kBlockBytes, kNotDecoded);
    const auto inside = [&](uint64_t addr, NodeType t) {
        return addr % kBlockBytes == 0 && addr + node_bytes(t) <= size_ && addr + node_bytes(t) > addr;
    };
    std::deque<uint64_t> todo;  // breadth first: the nodes near the root, visited most, come first
    const size_t cap = decoded_budget / sizeof(InternalNode);
    decoded_.reserve(std::min(cap, decoded_index_.size()));
    const auto visit = [&](uint64_t addr) {
        if (decoded_.size() < cap && inside(addr, NodeType::Internal) && decoded_index_[addr / kBlockBytes] == kNotDecoded) {
            decoded_index_[addr / kBlockBytes] = uint32_t(decoded_.size());
            decoded_.push_back(decode_internal(data_ + addr));
            todo.push_back(addr);
        }
    };
    visit(header_.root);
    while (!todo.empty()) {
        const InternalNode& n = decoded_[decoded_index_[todo.front() / kBlockBytes]];
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
    decoded_.shrink_to_fit();
}

}  // namespace rtu
