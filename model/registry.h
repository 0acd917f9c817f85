// A registry of named kinds (policies, prefetchers): the built-in ones registered by the owner,
// more by anyone at any time (a new policy: one class and one registration). Thread-safe; a
// kind's reference stays valid until it is registered again under the same name. Plain C++.
#pragma once
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

namespace rtu {

template <class Kind>
class NamedRegistry {
public:
    // `what`: how an unknown name is reported ("DRAM scheduler 'x': allowed are ...").
    explicit NamedRegistry(std::string what) : what_(std::move(what)) {}
    void add(Kind kind) {
        std::lock_guard<std::mutex> g(lock_);
        const std::string name = kind.name;
        kinds_[name] = std::move(kind);
    }
    const Kind& at(const std::string& name) const {
        std::lock_guard<std::mutex> g(lock_);
        const auto it = kinds_.find(name);
        if (it != kinds_.end()) return it->second;
        std::string known;
        for (const auto& [n, k] : kinds_) known += (known.empty() ? "" : ", ") + n;
        throw std::invalid_argument(what_ + " '" + name + "': allowed are " + known);
    }
    std::vector<std::string> names() const {
        std::lock_guard<std::mutex> g(lock_);
        std::vector<std::string> v;
        for (const auto& [n, k] : kinds_) v.push_back(n);
        return v;
    }

private:
    std::string what_;
    mutable std::mutex lock_;
    std::map<std::string, Kind> kinds_;
};

}  // namespace rtu
