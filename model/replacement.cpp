#include "replacement.h"

#include "registry.h"

namespace rtu {
namespace {

// Least recently used: per set a recency list, most recently used at its head, evicted from its
// tail (GPGPU-Sim's LRU, and the paper's Table 2 for L1 and L2).
class Lru : public ReplacementPolicy {
public:
    Lru(uint32_t sets, uint32_t assoc) : links_(size_t(sets) * assoc), ends_(sets) {}
    void touched(uint32_t set, uint32_t way) override {
        Ends& s = ends_[set];
        if (s.head == way) return;
        Link& w = links_[way];
        if (w.prev != kNone) {  // in the list (not its head): unlinked first
            links_[w.prev].next = w.next;
            if (w.next != kNone) links_[w.next].prev = w.prev;
            else s.tail = w.prev;
        }
        w.prev = kNone;
        w.next = s.head;
        if (s.head != kNone) links_[s.head].prev = way;
        s.head = way;
        if (s.tail == kNone) s.tail = way;
    }
    uint32_t first_victim(uint32_t set) const override { return ends_[set].tail; }
    uint32_t next_victim(uint32_t, uint32_t way) const override { return links_[way].prev; }
    void clear() override {
        for (Link& l : links_) l = Link{};
        for (Ends& e : ends_) e = Ends{};
    }

private:
    struct Link {
        uint32_t prev = kNone, next = kNone;  // towards the head (more recent), towards the tail
    };
    struct Ends {
        uint32_t head = kNone, tail = kNone;
    };
    std::vector<Link> links_;
    std::vector<Ends> ends_;
};

// First in, first out: per set the ways in the order they took their lines, the oldest evicted
// first; a use changes nothing (GPGPU-Sim's `F`).
class Fifo : public ReplacementPolicy {
public:
    Fifo(uint32_t sets, uint32_t assoc) : lru_(sets, assoc) {}
    void inserted(uint32_t set, uint32_t way) override { lru_.touched(set, way); }  // the newest line at the list's head
    void touched(uint32_t, uint32_t) override {}
    uint32_t first_victim(uint32_t set) const override { return lru_.first_victim(set); }
    uint32_t next_victim(uint32_t set, uint32_t way) const override { return lru_.next_victim(set, way); }
    void clear() override { lru_.clear(); }

private:
    Lru lru_;  // its list, ordered by insertion instead of use
};

NamedRegistry<ReplacementKind>& policies() {
    static NamedRegistry<ReplacementKind> r("replacement policy");
    static const bool built_in = [] {
        r.add({"lru", "least recently used (GPGPU-Sim's; the paper's Table 2)", uint32_t(sizeof(uint32_t) * 2), uint32_t(sizeof(uint32_t) * 2),
               [](uint32_t sets, uint32_t assoc) { return std::make_unique<Lru>(sets, assoc); }});
        r.add({"fifo", "first in, first out (GPGPU-Sim's F)", uint32_t(sizeof(uint32_t) * 2), uint32_t(sizeof(uint32_t) * 2),
               [](uint32_t sets, uint32_t assoc) { return std::make_unique<Fifo>(sets, assoc); }});
        return true;
    }();
    (void)built_in;
    return r;
}

}  // namespace

bool register_replacement(ReplacementKind kind) {
    policies().add(std::move(kind));
    return true;
}

const ReplacementKind& replacement_kind(const std::string& name) { return policies().at(name); }

std::vector<std::string> replacement_names() { return policies().names(); }

}  // namespace rtu
