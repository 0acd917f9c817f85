#include "address_map.h"

#include <initializer_list>
#include <stdexcept>

namespace rtu {

namespace {

bool power_of_two(uint64_t v) { return v && !(v & (v - 1)); }
uint32_t ones(uint64_t v) { return uint32_t(__builtin_popcountll(v)); }
uint32_t log2_exact(uint64_t v) { return uint32_t(__builtin_ctzll(v)); }  // v a power of two

}  // namespace

uint64_t pack_bits(uint64_t mask, uint64_t value) {
    uint64_t out = 0;
    for (uint32_t k = 0; mask; mask &= mask - 1, ++k)
        if (value & (mask & -mask)) out |= uint64_t(1) << k;
    return out;
}

BitPacker::BitPacker(uint64_t mask) {
    uint32_t packed = 0;  // bits of the mask below the run
    while (mask) {
        const uint32_t low = uint32_t(__builtin_ctzll(mask));
        const uint64_t above = mask >> low;  // the run starts at bit 0 of `above`
        const uint32_t len = ~above ? uint32_t(__builtin_ctzll(~above)) : 64 - low;
        const uint64_t bits = (len == 64 ? ~uint64_t(0) : (uint64_t(1) << len) - 1) << low;
        run_[runs_++] = {bits, low - packed};
        packed += len;
        mask &= ~bits;
    }
}

uint64_t SliceLocal::operator()(uint64_t addr) const {
    if (radix == 1 && !drop) return addr;
    const uint64_t low = addr & ((uint64_t(1) << at) - 1);
    const uint64_t taken = (((addr >> at) / radix) << at) | low;
    return drop ? keep(taken) : taken;
}

AddressMap::AddressMap(const std::string& spec, uint32_t channels, uint32_t banks, uint32_t row_bytes, uint32_t slices, uint32_t line)
    : channels_(channels), banks_(banks), slices_(slices), line_(line), lines_per_row_(row_bytes / line) {
    auto bad = [&](const std::string& why) { throw std::invalid_argument("'dram.address_map' = '" + spec + "': " + why); };
    if (!power_of_two(line)) bad("the line (" + std::to_string(line) + " B) must be a power of two");
    if (spec == "line") {
        if (lines_per_row_ == 0) bad("dram.row_bytes is smaller than a line");
        local_ = {log2_exact(line), slices, 0};
        return;
    }
    line_map_ = false;
    const std::string prefix = "dramid@";
    const size_t semi = spec.find(';');
    if (spec.compare(0, prefix.size(), prefix) != 0 || semi == std::string::npos)
        bad("allowed are 'line' or a GPGPU-Sim mapping 'dramid@<bit>;<64 letters of R B C S 0>'");
    try {
        size_t used = 0;
        const std::string digits = spec.substr(prefix.size(), semi - prefix.size());
        at_ = uint32_t(std::stoul(digits, &used));
        if (used != digits.size()) throw std::invalid_argument(digits);
    } catch (const std::exception&) {
        bad("the channel bit after 'dramid@' is not a number");
    }
    if (at_ > 40) bad("the channel bit " + std::to_string(at_) + " is above 40");
    uint64_t col_mask = 0;
    int bit = 63;
    for (size_t i = semi + 1; i < spec.size(); ++i) {
        const char ch = spec[i];
        if (ch == '.' || ch == '|' || ch == ' ') continue;
        if (bit < 0) bad("more than 64 letters");
        const uint64_t b = uint64_t(1) << bit--;
        switch (ch) {
            case 'R': case 'r': row_mask_ |= b; break;
            case 'B': case 'b': bank_mask_ |= b; break;
            case 'C': case 'c': case 'S': case 's': col_mask |= b; break;
            case '0': break;
            default: bad(std::string("letter '") + ch + "' (allowed: R B C S 0, and . | or space between)");
        }
    }
    if (bit != -1) bad(std::to_string(63 - bit) + " letters; there must be 64");
    if (!power_of_two(banks) || ones(bank_mask_) != log2_exact(banks))
        bad(std::to_string(ones(bank_mask_)) + " bank bits for dram.banks = " + std::to_string(banks));
    if (uint64_t(1) << ones(col_mask) != row_bytes)
        bad(std::to_string(ones(col_mask)) + " column bits (C and S) for dram.row_bytes = " + std::to_string(row_bytes));
    if (!row_mask_) bad("no row bits");
    if (slices % channels || !power_of_two(slices / channels))
        bad("l2.slices (" + std::to_string(slices) + ") must be dram.channels (" + std::to_string(channels) +
            ") times a power of two: each slice is a sub-partition of one channel");
    sub_ = slices / channels;
    // The sub-partition: the bank's lowest log2(sub_) bits.
    for (uint64_t m = bank_mask_, k = 0; m && k < log2_exact(sub_); m &= m - 1, ++k) sub_mask_ |= m & -m;
    // Line-granular: a line must not straddle slices, channels or banks.
    const uint64_t placed = sub_mask_ | (uint64_t(1) << at_);
    if (placed & (line - 1)) bad("a slice, channel or sub-partition bit lies inside a " + std::to_string(line) + " B line");
    local_ = {at_, channels, sub_mask_};
    bank_ = BitPacker(bank_mask_);
    row_ = BitPacker(row_mask_);
    sub_bits_ = BitPacker(sub_mask_);
}

uint64_t AddressMap::without_channel(uint64_t addr) const {
    const uint64_t low = addr & ((uint64_t(1) << at_) - 1);
    return (((addr >> at_) / channels_) << at_) | low;
}

uint32_t AddressMap::slice(uint64_t addr) const {
    if (line_map_) return uint32_t((addr / line_) % slices_);
    const uint32_t channel = uint32_t((addr >> at_) % channels_);
    return channel * sub_ + uint32_t(sub_bits_(without_channel(addr)));
}

DramCoord AddressMap::dram(uint64_t addr) const {
    DramCoord d;
    if (line_map_) {
        const uint64_t l = addr / line_;
        d.channel = uint32_t(l % channels_);
        const uint64_t row_block = l / channels_ / lines_per_row_;
        d.bank = uint32_t(row_block % banks_);
        d.row = row_block / banks_;
        return d;
    }
    // For a power-of-two number of channels this equals GPGPU-Sim's masks with the channel bits
    // inserted at bit at_ (the address's bits above them shifted down is the same as the masks'
    // bits shifted up); with a remainder it is its 'gap' path. One formula for both.
    const uint64_t rest = without_channel(addr);
    d.channel = uint32_t((addr >> at_) % channels_);
    d.bank = uint32_t(bank_(rest));
    d.row = row_(rest);
    return d;
}

uint32_t ipoly_index(uint64_t higher, uint32_t index, uint32_t sets) {
    // Bits of `higher` XORed into each index bit, from GPGPU-Sim's hashing.cc (IPOLY(5), (37), (67)).
    static const std::initializer_list<std::initializer_list<int>> k16 = {
        {11, 10, 9, 8, 6, 4, 3, 0}, {12, 8, 7, 6, 5, 3, 1, 0}, {9, 8, 7, 6, 4, 2, 1}, {10, 9, 8, 7, 5, 3, 2}};
    static const std::initializer_list<std::initializer_list<int>> k32 = {
        {13, 12, 11, 10, 9, 6, 5, 3, 0}, {14, 13, 12, 11, 10, 7, 6, 4, 1}, {14, 10, 9, 8, 7, 6, 3, 2, 0},
        {11, 10, 9, 8, 7, 4, 3, 1}, {12, 11, 10, 9, 8, 5, 4, 2}};
    static const std::initializer_list<std::initializer_list<int>> k64 = {
        {18, 17, 16, 15, 12, 10, 6, 5, 0}, {15, 13, 12, 11, 10, 7, 5, 1, 0}, {16, 14, 13, 12, 11, 8, 6, 2, 1},
        {17, 15, 14, 13, 12, 9, 7, 3, 2}, {18, 16, 15, 14, 13, 10, 8, 4, 3}, {17, 16, 15, 14, 11, 9, 5, 4}};
    // Each index bit's list as a mask: the XOR of the listed bits is the parity of `higher` under it.
    struct Masks {
        uint64_t bit[6] = {};
        uint32_t n = 0;
        explicit Masks(const std::initializer_list<std::initializer_list<int>>& table) {
            for (const auto& bits : table) {
                for (int h : bits) bit[n] |= uint64_t(1) << h;
                ++n;
            }
        }
    };
    static const Masks m16(k16), m32(k32), m64(k64);
    const Masks& m = sets == 16 ? m16 : sets == 32 ? m32 : sets == 64 ? m64 : throw std::invalid_argument("IPOLY needs 16, 32 or 64 sets");
    uint32_t out = 0;
    for (uint32_t k = 0; k < m.n; ++k) out |= (((index >> k) & 1) ^ uint32_t(__builtin_parityll(higher & m.bit[k]))) << k;
    return out;
}

}  // namespace rtu
