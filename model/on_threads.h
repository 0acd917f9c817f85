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

// Runs body(i) for every i in [0, n) on `threads` threads (0 counts as 1; never more threads than
// blocks), in blocks of 64 taken in turn; a thread that throws makes the others stop at their
// next block. Each i must write only its own slots, so that the results do not depend on the
// thread count.
inline void for_each_index(unsigned threads, size_t n, const std::function<void(size_t)>& body) {
    constexpr size_t kBlock = 64;
    std::atomic<size_t> next{0};
    const unsigned used = unsigned(std::max<size_t>(1, std::min<size_t>(threads, (n + kBlock - 1) / kBlock)));
    on_threads(used, [&](unsigned) {
        try {
            for (size_t b; (b = next.fetch_add(kBlock)) < n;)
                for (size_t i = b; i < std::min(n, b + kBlock); ++i) body(i);
        } catch (...) {
            next = n;
            throw;
        }
    });
}

}  // namespace rtu
