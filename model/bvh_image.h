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
};

class BvhImage {
public:
    BvhImage() = default;
    explicit BvhImage(std::vector<uint8_t> bytes) : bytes_(std::move(bytes)) {
        if (bytes_.size() < kBlockBytes) throw std::runtime_error("BVH image too small");
        header_ = decode_header(bytes_.data());
    }
    const ImageHeader& header() const { return header_; }
    size_t size() const { return bytes_.size(); }
    const std::vector<uint8_t>& bytes() const { return bytes_; }
    // Bytes of the node at `addr`; throws if [addr, addr+len) is outside the image.
    const uint8_t* at(uint64_t addr, uint32_t len) const {
        if (addr + len > bytes_.size() || addr + len < addr)
            throw std::out_of_range("BVH image read outside the image at " + std::to_string(addr));
        return bytes_.data() + addr;
    }

    BvhStats stats;

private:
    std::vector<uint8_t> bytes_;
    ImageHeader header_;
};

}  // namespace rtu
