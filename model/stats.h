// Statistics declared once. A counter group is a struct of uint64_t counters that lists each
// field once, with its name, unit and description, in `kCounters` (and its sub-groups in
// `parts`). From that list come the summing over instances (add), the JSON that rtsim writes
// (StatsOut::counters) and the schema that `rtsim --stats-schema` prints: the same words in all
// three. Derived figures (rates, shares, energies) are written beside the counters through
// StatsOut::value with their unit and description, so the schema holds every key.
// Plain C++ (no SystemC).
//
// A group:
//   struct PopStreakCounts {
//       uint64_t node_fetches = 0, l1_misses = 0;
//       static constexpr Counter<PopStreakCounts> kCounters[] = {
//           {"node_fetches", &PopStreakCounts::node_fetches, "node reads", "node reads of this class"}, ...};
//   };
// and, for sub-groups, `static constexpr bool kParts = true;` with
//   template <class F> static void parts(F&& f) { f("demand", &CacheCounts::demand, "..."); ... }
#pragma once
#include <algorithm>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include <nlohmann/json.hpp>

namespace rtu {

enum class Merge : uint8_t { Sum, Max };  // how instances combine into the total

template <class G>
struct Counter {
    const char* name;
    uint64_t G::*member;
    const char* unit;
    const char* what;
    Merge merge = Merge::Sum;
};

template <class G, class = void>
struct HasCounters : std::false_type {};
template <class G>
struct HasCounters<G, std::void_t<decltype(G::kCounters)>> : std::true_type {};
template <class G, class = void>
struct HasParts : std::false_type {};
template <class G>
struct HasParts<G, std::void_t<decltype(G::kParts)>> : std::true_type {};

// a += b, counter by counter (a maximum for Merge::Max counters), sub-groups included.
template <class G>
void add(G& a, const G& b) {
    if constexpr (HasCounters<G>::value)
        for (const Counter<G>& c : G::kCounters)
            a.*c.member = c.merge == Merge::Sum ? a.*c.member + b.*c.member : std::max(a.*c.member, b.*c.member);
    if constexpr (HasParts<G>::value) G::parts([&](const char*, auto member, const char*) { add(a.*member, b.*member); });
}

// The sum of per-instance values.
template <class G>
G total(const std::vector<G>& v) {
    G t{};
    for (const G& g : v) add(t, g);
    return t;
}

// One key of the statistics: its dotted path ("timing.l1.demand.hits"; list items as "[]"),
// unit and description.
struct StatKey {
    std::string key, unit, what;
};

// Writes statistics into a JSON object and, when given a schema, notes every key it writes.
class StatsOut {
public:
    explicit StatsOut(nlohmann::ordered_json& j, std::vector<StatKey>* schema = nullptr, std::string path = {})
        : j_(j), schema_(schema), path_(std::move(path)) {}

    template <class T>
    void value(const char* name, const T& v, const char* unit, const char* what) {
        j_[name] = v;
        note(name, unit, what);
    }
    // The object `name` (created if needed), for its keys.
    StatsOut child(const char* name, const char* what = nullptr) {
        nlohmann::ordered_json& c = j_[name];
        if (c.is_null()) c = nlohmann::ordered_json::object();
        if (what) note(name, "", what);
        return StatsOut(c, schema_, key(name));
    }
    // Every counter of group `g`, and its sub-groups as objects.
    template <class G>
    void counters(const G& g) {
        if constexpr (HasCounters<G>::value)
            for (const Counter<G>& c : G::kCounters) value(c.name, g.*c.member, c.unit, c.what);
        if constexpr (HasParts<G>::value)
            G::parts([&](const char* name, auto member, const char* what) { child(name, what).counters(g.*member); });
    }
    // A list of per-instance groups (per SM, per slice, per channel) under `name`.
    template <class G>
    void instances(const char* name, const std::vector<G>& items, const char* what) {
        nlohmann::ordered_json list = nlohmann::ordered_json::array();
        for (const G& g : items) {
            nlohmann::ordered_json item = nlohmann::ordered_json::object();
            StatsOut(item).counters(g);
            list.push_back(std::move(item));
        }
        j_[name] = std::move(list);
        if (!schema_) return;
        note(name, "", what);
        nlohmann::ordered_json scratch = nlohmann::ordered_json::object();
        StatsOut(scratch, schema_, key(name) + "[]").counters(G{});
    }
    // Notes a key written by other means (a whole JSON value) in the schema.
    void note(const char* name, const char* unit, const char* what) {
        if (schema_) schema_->push_back({key(name), unit, what});
    }
    nlohmann::ordered_json& json() { return j_; }

private:
    std::string key(const char* name) const { return path_.empty() ? name : path_ + "." + name; }
    nlohmann::ordered_json& j_;
    std::vector<StatKey>* schema_;
    std::string path_;
};

}  // namespace rtu
