// Treelets (Chou et al., MICRO 2023), as their published code forms and lays them out
// (GitHub yavuz650/vulkan-sim, branch treelet_traversal, vulkan_ray_tracing.cc
// createTreelets and remapBVHToTreeletLayout): the BVH cut into sub-trees grown breadth-first
// from a root up to a byte budget. Growth stops at the first node that does not fit; that node
// and the rest of the frontier become the roots of further treelets, taken in order. Every node
// belongs to exactly one treelet. Instance leaves lead into their BLAS like child edges. An image
// with headers has its TLAS header in the root treelet and each BLAS's header in the treelet of
// the (first) instance leaf that leads into it.
//
// Layout: the nodes stay where the BVH builder put them (`bvh`, what the TTP paper ran: the
// Treelet code's remap_to_treelet_layout 0), or every treelet is moved, for the memory system
// only, into a block of its own (`contiguous`, the Treelet paper's treelet layout): treelet i,
// in the order of its root's address, at base + i x (budget + stride), its root first and its
// other nodes after it in the order they joined. Traversal still reads the node bytes from the
// image; what moves is the address each fetch and prefetch sends to memory (placed()).
#pragma once
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "bvh_image.h"
#include "prefetch_config.h"
#include "traversal.h"

namespace rtu {

struct Treelets {
    std::unordered_map<uint64_t, uint32_t> of;  // node address -> treelet
    std::vector<std::vector<StackEntry>> nodes; // treelet -> its nodes (address, type), root first
    std::vector<uint64_t> bytes;                // treelet -> bytes of its nodes
    std::unordered_map<uint64_t, uint64_t> moved;  // contiguous layout: node address -> its place in memory
    TreeletOrder order = TreeletOrder::Treelets;  // how a treelet traversal moves between them (prefetch.treelet_order)
    uint32_t treelet_of(uint64_t addr) const {
        auto it = of.find(addr);
        return it == of.end() ? ~0u : it->second;
    }
    // Where the node at image address `addr` sits in simulated memory.
    uint64_t placed(uint64_t addr) const {
        if (moved.empty()) return addr;
        auto it = moved.find(addr);
        return it == moved.end() ? addr : it->second;
    }
};

// `contiguous`: lay every treelet out in a block of its own, `stride` bytes apart beyond the
// budget, starting at the first 4 KiB boundary past the image.
Treelets form_treelets(const BvhImage& image, uint32_t budget_bytes, bool contiguous = false, uint32_t stride = 256);

}  // namespace rtu
