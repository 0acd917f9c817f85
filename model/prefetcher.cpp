#include "prefetcher.h"

#include <stdexcept>

namespace rtu {

PrefetcherKind parse_prefetcher(const std::string& n) {
    if (n == "none") return PrefetcherKind::None;
    if (n == "ttp") return PrefetcherKind::Ttp;
    if (n == "park") return PrefetcherKind::Park;
    if (n == "treelet") return PrefetcherKind::Treelet;
    if (n == "perfect-up") return PrefetcherKind::PerfectUp;
    if (n == "perfect-down") return PrefetcherKind::PerfectDown;
    throw std::invalid_argument("--prefetcher '" + n + "': allowed are none, ttp, park, treelet, perfect-up, perfect-down");
}

const char* prefetcher_name(PrefetcherKind k) {
    switch (k) {
        case PrefetcherKind::None: return "none";
        case PrefetcherKind::Ttp: return "ttp";
        case PrefetcherKind::Park: return "park";
        case PrefetcherKind::Treelet: return "treelet";
        case PrefetcherKind::PerfectUp: return "perfect-up";
        case PrefetcherKind::PerfectDown: return "perfect-down";
    }
    return "?";
}

}  // namespace rtu
