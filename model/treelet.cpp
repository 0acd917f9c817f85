#include "treelet.h"

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

Treelets form_treelets(const BvhImage& img, uint32_t budget) {
    Treelets t;
    std::deque<StackEntry> roots = {{img.header().root, NodeType::Internal, kNoId}};
    std::vector<StackEntry> kids;
    while (!roots.empty()) {
        const StackEntry root = roots.front();
        roots.pop_front();
        if (t.of.count(root.addr)) continue;  // a BLAS shared by several instances
        const uint32_t id = uint32_t(t.nodes.size());
        t.nodes.emplace_back();
        t.bytes.push_back(0);
        std::deque<StackEntry> frontier = {root};
        while (!frontier.empty()) {
            const StackEntry e = frontier.front();
            frontier.pop_front();
            if (t.of.count(e.addr)) continue;
            const uint32_t size = node_bytes(e.type);
            // The root always goes in; others only while the budget holds. Breadth-first order
            // means a node that does not fit starts a treelet of its own.
            if (!t.nodes[id].empty() && t.bytes[id] + size > budget) {
                roots.push_back(e);
                continue;
            }
            t.of[e.addr] = id;
            t.nodes[id].push_back(e);
            t.bytes[id] += size;
            children(img, e, kids);
            for (const StackEntry& k : kids) frontier.push_back(k);
        }
    }
    return t;
}

}  // namespace rtu
