// Treelets (Chou et al., MICRO 2023): the BVH cut into sub-trees grown breadth-first from a root
// up to a byte budget; the nodes that do not fit become the roots of further treelets. Every
// node belongs to exactly one treelet. Instance leaves lead into their BLAS like child edges.
#pragma once
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "bvh_image.h"
#include "traversal.h"

namespace rtu {

struct Treelets {
    std::unordered_map<uint64_t, uint32_t> of;  // node address -> treelet
    std::vector<std::vector<StackEntry>> nodes; // treelet -> its nodes (address, type)
    std::vector<uint64_t> bytes;                // treelet -> bytes of its nodes
    uint32_t treelet_of(uint64_t addr) const {
        auto it = of.find(addr);
        return it == of.end() ? ~0u : it->second;
    }
};

Treelets form_treelets(const BvhImage& image, uint32_t budget_bytes);

}  // namespace rtu
