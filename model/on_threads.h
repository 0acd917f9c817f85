// Runs work on several host threads (the functional pass, the sampling pre-pass): body(t) for t in
// [0, threads), t = 0 on the calling thread; all are joined, then the first exception any of them
// threw (by thread index) is rethrown. What the threads compute must not depend on how many there
// are: each writes only its own results. Plain C++.
#pragma once
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

}  // namespace rtu
