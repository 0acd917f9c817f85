// Where an address lives in the memory system: its L2 slice, its DRAM channel, bank and row, and
// its address within the slice (what the slice's sets are indexed with). One home for the
// crossbar, the L2 slices, the DRAM and the interval fidelity. Plain C++ (no SystemC).
//
// Two maps (key dram.address_map):
//  - "line": consecutive lines go round robin over the slices and, independently, over the
//    channels; within a channel, consecutive lines fill a row, then move to the next bank.
//  - a GPGPU-Sim mapping, "dramid@S;" then 64 letters, most significant bit first (separators
//    '.', '|' and ' ' ignored): R row, B bank, C column, S column bits within a burst, 0 unused.
//    The channel is the address's digit at bit S (log2(channels) bits inserted there when the
//    channels are a power of two; (addr >> S) % channels, the rest stitched together, when not),
//    and the letters describe the address with that digit taken out. An L2 slice is a channel's
//    sub-partition: channel x (slices / channels) + the bank's lowest bits (GPGPU-Sim's
//    addrdec.cc, consecutive partition indexing). This is how the TTP authors' configurations
//    place memory (gpgpusim.config -gpgpu_mem_addr_mapping).
#pragma once
#include <array>
#include <cstdint>
#include <string>

namespace rtu {

struct DramCoord {
    uint32_t channel, bank;
    uint64_t row;
};

// The bits of `value` where `mask` has ones, packed towards bit 0 in order (the reference: one
// step per bit of the mask; BitPacker does the same in a step per run of ones).
uint64_t pack_bits(uint64_t mask, uint64_t value);

// pack_bits(mask, value) for one mask, as one and-shift-or per run of consecutive ones in the
// mask. pack_bits walks the mask bit by bit: the `paper` preset's row (13 bits in 2 runs) and
// bank (4 bits in 2 runs) on every DRAM access, `desktop`'s slice address (63 bits in 2 runs) on
// every L2 allocation.
class BitPacker {
public:
    BitPacker() = default;  // the empty mask: every value packs to 0
    explicit BitPacker(uint64_t mask);
    uint64_t operator()(uint64_t value) const {
        uint64_t out = 0;
        for (uint32_t i = 0; i < runs_; ++i) out |= (value & run_[i].mask) >> run_[i].shift;
        return out;
    }

private:
    struct Run {
        uint64_t mask = 0;   // the run's bits in the value
        uint32_t shift = 0;  // how far down they move: the run's lowest bit less the bits packed below it
    };
    std::array<Run, 32> run_{};  // a 64-bit mask has at most 32 runs
    uint32_t runs_ = 0;
};

// A slice's own address: the digit of `radix` at bit `at` (the slice or channel number) taken
// out, then the bits of `drop` (a sub-partition's bank bits) squeezed out. Indexing a slice's sets
// with it uses all of them; indexing with the full address would leave the sets whose index
// bits carry the slice number unused (set camping).
struct SliceLocal {
    SliceLocal() = default;  // the full address
    SliceLocal(uint32_t at_bit, uint64_t digit_radix, uint64_t drop_bits)
        : at(at_bit), radix(digit_radix), drop(drop_bits), keep(~drop_bits) {}
    uint32_t at = 0;
    uint64_t radix = 1;
    uint64_t drop = 0;
    uint64_t operator()(uint64_t addr) const;

private:
    BitPacker keep{~uint64_t(0)};  // pack_bits(~drop, .)
};

class AddressMap {
public:
    // Throws std::invalid_argument saying what is wrong with `spec` against the other keys.
    AddressMap(const std::string& spec, uint32_t channels, uint32_t banks, uint32_t row_bytes, uint32_t slices, uint32_t line);

    uint32_t slice(uint64_t addr) const;
    DramCoord dram(uint64_t addr) const;
    const SliceLocal& slice_local() const { return local_; }

private:
    uint64_t without_channel(uint64_t addr) const;  // the address with the channel digit taken out
    bool line_map_ = true;
    uint32_t channels_, banks_, slices_, line_, lines_per_row_;
    // GPGPU-Sim map: masks of the address without the channel digit.
    uint32_t at_ = 0, sub_ = 1;  // channel digit's bit; slices per channel
    uint64_t bank_mask_ = 0, row_mask_ = 0, sub_mask_ = 0;
    BitPacker bank_, row_, sub_bits_;  // pack_bits of bank_mask_, row_mask_, sub_mask_
    SliceLocal local_;
};

// GPGPU-Sim's IPOLY set index (Rau, ISCA 1991; the polynomials of Khairy et al., TPDS 2017) for
// 16, 32 or 64 sets: each index bit XORed with a fixed set of the bits above the index.
// `higher`: the address above the index bits; `index`: the linear index.
uint32_t ipoly_index(uint64_t higher, uint32_t index, uint32_t sets);

}  // namespace rtu
