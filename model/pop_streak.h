// The pop streak of a thread's traversal stack (paper section 3.1, Figure 'pop_miss_rates'): every
// node read is a pop, and a pop's class is its position in a run of consecutive pops: the 1st
// (the pop right after a push: downward traversal), 2nd, 3rd or 4th and later (upward or
// same-level traversal). A push ends the streak. Class 0 is a node read that is not a pop (the
// root, or the "next node" register of stock Vulkan-sim). Plain C++.
#pragma once
#include <algorithm>
#include <cstdint>

namespace rtu {

class PopStreak {
public:
    static constexpr int kClasses = 5;  // not a pop, 1st, 2nd, 3rd, 4th or later
    // A node read that pops: its class (1..4).
    uint8_t pop() { return n_ = uint8_t(std::min(n_ + 1, 4)); }
    void push() { n_ = 0; }

private:
    uint8_t n_ = 0;
};

inline const char* pop_streak_class_name(int c) {
    static const char* names[PopStreak::kClasses] = {"not_a_pop", "pop_1", "pop_2", "pop_3", "pop_4_or_more"};
    return names[c];
}

}  // namespace rtu
