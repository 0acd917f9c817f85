#include "treelet.h"

#include <algorithm>
#include <deque>

namespace rtu {

namespace {
// Children of a node as stack entries (internal: its children; instance leaf: its BLAS root).
void children(const BvhImage& img, const StackEntry& e, std::vector<StackEntry>& out) {
    out.clear();
    if (e.type == NodeType::Internal) {
        const InternalNode n = decode_internal(img.at(e.addr, kBlockBytes));
        for (int i = 0; i < n.count; ++i)
            if (n.type[i] != NodeType::Empty) out.push_back({n.addr[i], n.type[i], kNoId});
    } else if (e.type == NodeType::Instance) {
        const InstanceLeaf l = decode_instance(img.at(e.addr, 2 * kBlockBytes));
        out.push_back({l.blas_root, NodeType::Internal, kNoId});
    }
}
}  // namespace

Treelets form_treelets(const BvhImage& img, uint32_t budget, bool contiguous, uint32_t stride) {
    Treelets t;
    std::deque<StackEntry> roots = {{img.header().root, NodeType::Internal, kNoId}};
    std::vector<StackEntry> kids;
    // With headers, the Treelet code charges the TLAS header to the root treelet and a BLAS's
    // header to the treelet of the instance leaf that leads into it (createTreelets, vrt.cc
    // l.1044-1053 and l.1127): they belong to those treelets, read and prefetched with them.
    const bool headers = img.header().has_headers;
    auto add = [&](uint32_t id, const StackEntry& e) {
        t.of[e.addr] = id;
        t.nodes[id].push_back(e);
        t.bytes[id] += node_bytes(e.type);
    };
    while (!roots.empty()) {
        const StackEntry root = roots.front();
        roots.pop_front();
        if (t.of.count(root.addr)) continue;  // a BLAS shared by several instances
        const uint32_t id = uint32_t(t.nodes.size());
        t.nodes.emplace_back();
        t.bytes.push_back(0);
        if (headers && id == 0) add(id, StackEntry{0, NodeType::Header, kNoId});
        std::deque<StackEntry> frontier = {root};
        while (!frontier.empty()) {
            const StackEntry e = frontier.front();
            if (t.of.count(e.addr)) {
                frontier.pop_front();
                continue;
            }
            uint64_t blas_header = ~uint64_t(0);
            if (headers && e.type == NodeType::Instance) {
                const uint64_t h = decode_instance(img.at(e.addr, 2 * kBlockBytes)).blas_root - kBlockBytes;
                if (!t.of.count(h)) blas_header = h;  // a BLAS instanced twice: its header is in one treelet
            }
            const uint32_t size = node_bytes(e.type) + (blas_header != ~uint64_t(0) ? kBlockBytes : 0);
            // The root always goes in; growth stops at the first node that does not fit, and the
            // frontier from it on roots further treelets.
            if (t.of.count(root.addr) && t.bytes[id] + size > budget) {
                for (const StackEntry& f : frontier) roots.push_back(f);
                break;
            }
            frontier.pop_front();
            add(id, e);
            if (blas_header != ~uint64_t(0)) add(id, StackEntry{blas_header, NodeType::Header, kNoId});
            children(img, e, kids);
            for (const StackEntry& k : kids) frontier.push_back(k);
        }
    }
    if (contiguous) {
        // Treelets in the order of their roots' addresses (the Treelet code walks a map keyed by
        // the root), each in a block of budget + stride bytes.
        std::vector<uint32_t> order(t.nodes.size());
        for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
        std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return t.nodes[a][0].addr < t.nodes[b][0].addr; });
        const uint64_t base = (uint64_t(img.size()) + 4095) / 4096 * 4096;
        const uint64_t block = (uint64_t(budget) + stride + kBlockBytes - 1) / kBlockBytes * kBlockBytes;  // nodes stay 64 B aligned
        for (uint64_t k = 0; k < order.size(); ++k) {
            uint64_t at = base + k * block;
            for (const StackEntry& e : t.nodes[order[k]]) {
                t.moved[e.addr] = at;
                at += node_bytes(e.type);
            }
        }
    }
    return t;
}

}  // namespace rtu
