// Runs work on several host threads (the functional pass, the sampling pre-pass, --verify):
// body(t) for t in [0, threads), t = 0 on the calling thread; all are joined, then the first
// exception any of them threw (by thread index) is rethrown. What the threads compute must not
// depend on how many there are: each writes only its own results. Plain C++.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <thread>
#include <vector>

namespace rtu {

inline void on_threads(unsigned threads, const std::function<void(unsigned)>& body) {
    std::vector<std::thread> pool;
    std::vector<std::exception_ptr> failed(threads ? threads : 1);
    for (unsigned t = 1; t < threads; ++t)
        pool.emplace_back([&, t] {
            try {
                body(t);
            } catch (...) {
                failed[t] = std::current_exception();
            }
        });
    try {
        body(0);
    } catch (...) {
        failed[0] = std::current_exception();
    }
    for (std::thread& th : pool) th.join();
    for (const std::exception_ptr& e : failed)
        if (e) std::rethrow_exception(e);
}

// for_each_index's threads for `n` indices: `threads` (0 counts as 1), never more than blocks.
constexpr size_t kIndexBlock = 64;
inline unsigned index_threads(unsigned threads, size_t n) {
    return unsigned(std::max<size_t>(1, std::min<size_t>(threads, (n + kIndexBlock - 1) / kIndexBlock)));
}

// Runs body(t, i) for every i in [0, n) on index_threads(threads, n) threads, in blocks of 64
// taken in turn, each the next block not yet taken (so a costly part of [0, n) does not leave the
// other threads waiting); t is the thread running it, for state a thread keeps across its indices.
// A thread that throws makes the others stop at their next block. Each i must write only its own
// slots, so that the results do not depend on the thread count.
inline void for_each_index(unsigned threads, size_t n, const std::function<void(unsigned, size_t)>& body) {
    std::atomic<size_t> next{0};
    on_threads(index_threads(threads, n), [&](unsigned t) {
        try {
            for (size_t b; (b = next.fetch_add(kIndexBlock)) < n;)
                for (size_t i = b; i < std::min(n, b + kIndexBlock); ++i) body(t, i);
        } catch (...) {
            next = n;
            throw;
        }
    });
}

// The same, for a body without state per thread.
inline void for_each_index(unsigned threads, size_t n, const std::function<void(size_t)>& body) {
    for_each_index(threads, n, std::function<void(unsigned, size_t)>([&](unsigned, size_t i) { body(i); }));
}

}  // namespace rtu
