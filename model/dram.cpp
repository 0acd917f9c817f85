#include "dram.h"

#include <algorithm>
#include <iterator>

namespace rtu {

DramChannel::DramChannel(const DramConfig& c) : cfg_(c), banks_(c.banks) {}

bool DramChannel::schedule(uint64_t now, DramRequest* out, uint64_t* done) {
    if (queue_.empty()) return false;
    size_t pick = 0;
    if (cfg_.frfcfs) {
        for (size_t i = 0; i < queue_.size(); ++i) {
            const Bank& b = banks_[queue_[i].at.bank];
            if (b.open && b.row == queue_[i].at.row) {
                pick = i;
                break;
            }
        }
    }
    DramRequest r = queue_[pick];
    queue_.erase(queue_.begin() + long(pick));
    Bank& b = banks_[r.at.bank];
    uint64_t col;
    if (b.open && b.row == r.at.row) {
        ++stats_.row_hits;
        col = std::max({now, b.act + cfg_.tRCD, next_col_});
    } else {
        uint64_t act_ready = now;
        if (b.open) {
            ++stats_.row_conflicts;
            const uint64_t pre = std::max({now, b.act + cfg_.tRAS, b.write_done});
            act_ready = pre + cfg_.tRP;
        } else {
            ++stats_.row_misses;
        }
        uint64_t act = act_ready;
        if (b.activated) act = std::max(act, b.act + cfg_.tRC);
        if (any_act_) act = std::max(act, last_act_ + cfg_.tRRD);
        b.open = true;
        b.row = r.at.row;
        b.act = act;
        b.activated = true;
        last_act_ = act;
        any_act_ = true;
        col = std::max(act + cfg_.tRCD, next_col_);
    }
    const uint64_t xfer = transfer_cycles(r.bytes);
    const uint64_t data_start = std::max(col + (r.write ? cfg_.tWL : cfg_.tCL), bus_free_);
    const uint64_t data_end = data_start + xfer;
    bus_free_ = data_end;
    next_col_ = col + std::max<uint64_t>(cfg_.tCCD, xfer);
    if (r.write) b.write_done = data_end + cfg_.tWR;
    (r.write ? stats_.writes : stats_.reads)++;
    stats_.bytes += r.bytes;
    stats_.data_cycles += xfer;
    stats_.queue_wait += col - std::min(col, r.arrival);
    *out = r;
    *done = data_end;
    return true;
}

DramBookings::DramBookings(const DramConfig& c, const AddressMap& map)
    : cfg_(c), map_(map), banks_(c.channels, std::vector<Bank>(c.banks)), bus_(c.channels), commands_(c.channels),
      activations_(c.channels), stats_(c.channels), act_gap_(std::max<uint64_t>(c.tRC, uint64_t(c.tRAS) + c.tRP)) {}

uint64_t DramBookings::access(uint64_t addr, uint32_t bytes, uint64_t now, uint64_t horizon) {
    const DramCoord at = map_.dram(addr);
    Bank& b = banks_[at.channel][at.bank];
    DramStats& st = stats_[at.channel];
    std::deque<Epoch>& epochs = b.epochs;
    // Epochs closed by the horizon cannot take a read any more (no read comes before it); the
    // last stays, as the bank's open row.
    while (epochs.size() > 1 && epochs.front().until <= horizon) epochs.pop_front();
    // FR-FCFS: the earliest epoch of this row open at or after the read's arrival serves it.
    // FCFS (dram.scheduler fcfs): only the bank's last epoch, as reads are served in turn.
    const Epoch* open = nullptr;
    for (const Epoch& e : epochs) {
        if (e.row == at.row && e.until > now && (cfg_.frfcfs || e.until == ~0ull)) {
            open = &e;
            break;
        }
    }
    const uint64_t xfer = dram_transfer_cycles(cfg_, bytes);
    const uint64_t slot = std::max<uint64_t>(cfg_.tCCD, xfer);  // column-to-column
    uint64_t column;
    if (open) {
        ++st.row_hits;
        // The bank: a row hit holds it for one column command, not before its row is open.
        const uint64_t bank_start = b.busy.book(now, std::max<uint64_t>(cfg_.tCCD, 1), horizon);
        column = commands_[at.channel].book(std::max(bank_start, open->first_column), slot, horizon);
        st.queue_wait += column - now;  // beyond the unloaded latency
    } else {
        // An activation, after a precharge unless the bank was never opened. The bank is held
        // from its precharge to its first column command; on the channel's command sequence the
        // ACT overlaps the transfer ahead of it (tRCD), a conflict's precharge does not.
        const uint64_t pre = epochs.empty() ? 0 : cfg_.tRP;
        (epochs.empty() ? st.row_misses : st.row_conflicts)++;
        // The ACT (bank_start + pre) also keeps AT's spacing of activations: a bank's at least
        // act_gap apart (tRC from ACT to ACT, and tRAS from ACT to the precharge before the next
        // ACT: tRAS + tRP), a channel's at least tRRD apart. Each ACT books [ACT, ACT + gap) in
        // its bank's and its channel's activation calendars, so two ACTs booked in either order
        // are a gap apart. The earliest bank_start that all three calendars leave free: each
        // probe only moves it later, and a fixed point is a start none of them pushes further.
        const uint64_t hold = pre + cfg_.tRCD + cfg_.tCCD;
        Calendar& channel_acts = activations_[at.channel];
        uint64_t bank_start = now;
        for (;;) {
            const uint64_t s = b.busy.first_free(bank_start, hold);
            const uint64_t act = channel_acts.first_free(b.activations.first_free(s + pre, act_gap_), cfg_.tRRD);
            bank_start = act - pre;
            if (bank_start == s) break;
        }
        b.busy.book(bank_start, hold, horizon);
        b.activations.book(bank_start + pre, act_gap_, horizon);
        channel_acts.book(bank_start + pre, cfg_.tRRD, horizon);
        const uint64_t sequence = commands_[at.channel].book(bank_start + cfg_.tRCD, pre + slot, horizon);
        column = sequence + pre;
        st.queue_wait += column - now - pre - cfg_.tRCD;  // beyond the unloaded latency
        // The new epoch goes in at its decision; the one before it closes there.
        Epoch e{at.row, sequence - cfg_.tRCD, column, ~0ull};
        auto pos = std::upper_bound(epochs.begin(), epochs.end(), e.decision,
                                    [](uint64_t d, const Epoch& x) { return d < x.decision; });
        if (pos != epochs.end()) e.until = pos->decision;
        if (pos != epochs.begin()) std::prev(pos)->until = e.decision;
        epochs.insert(pos, e);
    }
    const uint64_t bus_start = bus_[at.channel].book(column + cfg_.tCL, xfer, horizon);
    ++st.reads;
    st.bytes += bytes;
    st.data_cycles += xfer;
    return bus_start + xfer;
}

}  // namespace rtu
