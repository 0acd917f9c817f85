// Per-thread BVH traversal that reads node bytes from the image (the RT unit's warp-buffer
// entry for one thread: ray, traversal stack or queue, closest hit so far).
//
// DFS follows the TTP authors' RT unit (paper section 3, Algorithm 1: "every memory read request
// is a pop from a traversal stack"): every child an internal node's ray-box tests hit is pushed,
// in child order, so the last one is popped next; the root and a BLAS root are pushed and popped
// too. With the next-node register of stock Vulkan-sim (an option, rt.next_node_register), the
// first hit child is taken next from the register instead and the others are pushed: that read
// is not a pop. A child whose entry distance is beyond the closest hit so far is culled. BFS
// keeps a FIFO queue: every hit child is appended in child order.
//
// As in the TTP authors' simulator (vulkan_ray_tracing.cc traceRay_BFS):
// - With an image whose headers are read (ImageHeader::has_headers), a ray first reads the image
//   header (its fetch), tests the root box it holds and pushes the root if hit; an instance leaf
//   is followed by its BLAS's header, after which the BLAS root is pushed without a box test
//   (the instance's box in its parent was the test). A header read is not a pop and not a node
//   visit.
// - A procedural leaf's hit does not cull: the simulator runs intersection shaders after the
//   traversal, so only triangle hits shorten the ray for the box tests that decide what is pushed
//   (l.1801, l.1966, and procedural leaves are recorded, never accepted, l.2189). The hit
//   reported is still the closest of all, procedural or not. An any-hit ray stops at its first
//   triangle hit; a procedural hit is kept and the traversal goes on.
// - Robust tests decide whether a primitive is hit; the simulator's and the application's float
//   arithmetic give the t by which hits are ordered and accepted (Hit::app_t): a triangle's
//   Moller-Trumbore t must be at or beyond tmin and strictly closer than the closest triangle
//   hit so far, so that of two coincident triangles (the ship's double-sided sails) the one the
//   simulator takes wins.
#pragma once
#include <cstdint>
#include <deque>

#include "bvh_image.h"
#include "ray.h"

namespace rtu {

// DFS and BFS as described above; Treelet: DFS within the current treelet, with children in
// other treelets deferred on a second stack until the current treelet is finished (Chou et al.);
// where it goes then is the treelets' TreeletOrder (model/prefetch_config.h).
enum class TraversalOrder : uint8_t { DFS, BFS, Treelet };

struct Treelets;

// The TTP authors' simulator's t of a triangle hit, in its float arithmetic: Moller-Trumbore
// (vulkan_ray_tracing.cc mt_ray_triangle_test, l.2350-2379) on the ray with its direction made
// unit (make_transformed_ray, l.148-161), back in the ray's own units (l.2078). False where it
// is not a number (a ray parallel to the triangle's plane). It orders hits (Hit::app_t).
bool moller_trumbore_t(const glm::vec3& o, const glm::vec3& dir, const TriangleLeaf& tl, float* t);

struct StackEntry {
    uint64_t addr = 0;
    NodeType type = NodeType::Empty;
    uint32_t inst_block = kNoId;  // instance leaf (block index) whose BLAS this node is in
};

struct StepInfo {
    NodeType type = NodeType::Empty;  // what was fetched and tested
    uint32_t pushed = 0;              // entries pushed on the stack / queue
    bool from_stack = false;          // popped from the stack (false: taken from the next-node register)
    bool hit = false;                 // a primitive test accepted a hit
};

// How a thread chooses its next node besides the order.
struct TraversalRule {
    TraversalOrder order = TraversalOrder::DFS;
    bool next_node_register = false;  // DFS and treelet: stock Vulkan-sim's register for the first hit child
};

class TraversalThread {
public:
    // Prepares the ray and tests the root box (a register in the RT unit, not a memory read);
    // the root, if hit, is pushed (or put in the next-node register). The ray must be valid
    // (is_valid_ray). `treelets` is required for TraversalOrder::Treelet and ignored otherwise.
    void start(const Ray& ray, const ImageHeader& header, TraversalOrder order, const Treelets* treelets = nullptr,
               bool next_node_register = false);
    bool done() const { return !has_next_ && stack_.empty() && deferred_.empty(); }
    // The node the thread reads next; only when !done().
    // True when the next node comes off the stack / queue (a pop), false when it is the
    // next-node register (with rt.next_node_register: the first hit child, the root, a BLAS root).
    bool next_is_pop() const { return !has_next_; }
    const StackEntry& peek() const {
        if (has_next_) return next_;
        if (order_ == TraversalOrder::BFS) return stack_.front();
        return stack_.empty() ? deferred_.back() : stack_.back();
    }
    // Treelet traversal: the treelet the thread works in (kNoTreelet once the root treelet is
    // finished under TreeletOrder::RootThenDfs), and the one it will move to next (~0 when it has
    // none waiting).
    uint32_t current_treelet() const { return current_treelet_; }
    uint32_t next_treelet() const;
    // Takes the next node, reads its bytes from the image and runs its tests.
    StepInfo step(const BvhImage& image);

    const Hit& hit() const { return hit_; }
    const Ray& ray() const { return ray_; }
    uint32_t nodes_visited() const { return nodes_visited_; }
    // Procedural leaves read so far: the candidates the shader code tests after the trace
    // (RetiredRay::candidates).
    uint32_t candidates() const { return candidates_; }
    const std::deque<StackEntry>& stack() const { return stack_; }

private:
    // The ray in the space of `inst_block` (kNoId: the world's), as the node to be tested needs;
    // most steps stay in the space of the step before, tested here inline.
    void select_space(const BvhImage& image, uint32_t inst_block) {
        if (inst_block != space_inst_) enter_space(image, inst_block);
    }
    void enter_space(const BvhImage& image, uint32_t inst_block);
    // Tests an internal node's child boxes and pushes the children hit (see the file comment).
    void push_children(const InternalNode& n, uint32_t inst_block, StepInfo& info);
    void finish() {
        has_next_ = false;
        stack_.clear();
        deferred_.clear();
    }
    // Pushes an entry taken after the current step: the stack (or deferred stack), or with the
    // next-node register the register.
    void push_next(const StackEntry& e, StepInfo& info);
    // Takes `t` (ray parameter) at primitive (geom, prim) as the hit if it is the closest so far.
    bool take_hit(float t, float app_t, float u, float v, uint32_t geom, uint32_t prim, const glm::vec3& ng);
    glm::vec3 normal_to_world(const BvhImage& image, const glm::vec3& n) const;

    Ray ray_;  // tfar: the closest triangle hit so far (its Hit::app_t), the bound the box tests cull by
    float tmax_ = 0.0f;  // the ray's own tfar: the window of the robust primitive tests
    TraversalOrder order_ = TraversalOrder::DFS;
    bool register_ = false;  // the next-node register is in use
    Hit hit_;
    std::deque<StackEntry> stack_, deferred_;  // deferred: entries of other treelets (Treelet order)
    const Treelets* treelets_ = nullptr;
    uint32_t current_treelet_ = ~0u;
    static constexpr uint32_t kNoTreelet = ~0u - 1;  // matches no node (TreeletOrder::RootThenDfs)
    StackEntry next_;
    bool has_next_ = false;
    bool headers_ = false;   // the image's headers are read (ImageHeader::has_headers)
    Aabb root_box_;          // with headers: the image header's, tested when it is read
    uint64_t root_ = 0;
    uint32_t nodes_visited_ = 0, candidates_ = 0;

    // Ray in the space of the node being processed (world, or an instance's object space).
    uint32_t space_inst_ = kNoId;
    glm::vec3 org_, dir_;
    BoxTestRay box_ray_, world_box_ray_;
};

// Bit i set: the ray overlaps child i's box within [tmin, tmax], as intersect_box (robust.h)
// decides it for n.box(i) (the same bits; four children at a time where the host has SSE2).
unsigned child_hits(const BoxTestRay& r, const InternalNode& n, float tmin, float tmax);

// Traces one ray to completion. Invalid rays return a miss without touching the image.
struct TraceResult {
    Hit hit;
    uint32_t nodes_visited = 0;
    uint32_t candidates = 0;  // procedural leaves read (TraversalThread::candidates)
};
// `fetched`, when given, receives every node the traversal reads, in order. More than
// `max_nodes` node visits throw std::length_error: an image from untrusted memory (an SoC
// peripheral's) may link its nodes into a cycle.
TraceResult trace_ray(const BvhImage& image, const Ray& ray, TraversalOrder order, const Treelets* treelets = nullptr,
                      std::vector<StackEntry>* fetched = nullptr, bool next_node_register = false, uint64_t max_nodes = ~0ull);

}  // namespace rtu
