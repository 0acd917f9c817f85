#include "dram.h"

#include <algorithm>
#include <iterator>

namespace rtu {

DramChannel::DramChannel(const DramConfig& c) : cfg_(c), banks_(c.banks) {}

uint64_t DramChannel::next_decision() const {
    if (!cfg_.per_bank()) return next_col_ > cfg_.tRCD ? next_col_ - cfg_.tRCD : 0;
    if (!ran_) return 0;
    // The earliest cycle after the last run at which a bank without a request can take one, or a
    // bank's next command is allowed by its timing. A command may still lose that cycle to
    // another's (one of each kind a cycle); the channel then runs again the cycle after.
    const uint64_t after = last_cycle_ + 1;
    uint64_t next = ~0ull;
    for (const Bank& b : banks_) {
        uint64_t t;
        if (!b.serving) {
            if (!b.queued) continue;
            t = after;
        } else if (b.open && b.row == b.req.at.row) {
            t = std::max(b.column_ok, next_col_);
        } else if (!b.open) {
            t = std::max(b.act_ok, channel_act_ok_);
        } else {
            t = b.precharge_ok;
        }
        next = std::min(next, std::max(t, after));
    }
    return next == ~0ull ? after : next;
}

bool DramChannel::schedule(uint64_t now, DramRequest* out, uint64_t* done) {
    return cfg_.per_bank() ? schedule_banks(now, out, done) : schedule_channel(now, out, done);
}

// GPGPU-Sim's dram_t::cycle for one memory cycle (single command bus): a bank takes a request,
// then the banks in priority order try a column command, and a row command while none has issued.
bool DramChannel::schedule_banks(uint64_t now, DramRequest* out, uint64_t* done) {
    last_cycle_ = now;
    ran_ = true;
    take_request();
    bool column = false, row = false, finished = false;
    const uint32_t n = uint32_t(banks_.size());
    for (uint32_t i = 0; i < n; ++i) {
        // prio_ moves when a row command issues; GPGPU-Sim reads it afresh for every bank.
        const uint32_t j = (i + prio_) % n;
        Bank& b = banks_[j];
        if (!column) column = column_command(now, b, &finished, out, done);
        if (!column && !row) row = row_command(now, b, j);
    }
    return finished;
}

// The first bank, in priority order, without a request takes one (GPGPU-Sim's
// frfcfs_scheduler::schedule; one bank a cycle): the scheduler picks among the bank's requests
// in arrival order, those to the row it last took (which is the bank's row: a bank takes its next
// request only once the last has had its columns) marked as row hits.
void DramChannel::take_request() {
    const uint32_t n = uint32_t(banks_.size());
    uint32_t j = n;
    for (uint32_t i = 0; i < n && j == n; ++i)
        if (!banks_[(i + prio_) % n].serving && banks_[(i + prio_) % n].queued) j = (i + prio_) % n;
    if (j == n) return;
    Bank& b = banks_[j];
    candidates_.clear();
    bool* hit = row_hits(b.queued);
    for (size_t q = 0; q < queue_.size(); ++q)
        if (queue_[q].at.bank == j) {
            hit[candidates_.size()] = b.activated && b.row == queue_[q].at.row;
            candidates_.push_back(q);
        }
    const size_t q = candidates_[cfg_.scheduler->pick(candidates_.size(), hit)];
    b.req = queue_[q];
    queue_.erase(queue_.begin() + long(q));
    --b.queued;
    if (!b.open) ++stats_.row_misses;  // closed only before its first ACT: no request pending now
    else if (b.row == b.req.at.row) ++stats_.row_hits;
    else ++stats_.row_conflicts;
    b.columns_left = columns(b.req.bytes);
    b.serving = true;
    ++serving_;
    prio_ = (prio_ + 1) % n;
}

bool* DramChannel::row_hits(size_t n) {
    if (row_hit_size_ < n) row_hit_.reset(new bool[row_hit_size_ = std::max<size_t>(n, 2 * row_hit_size_)]);
    return row_hit_.get();
}

// A column command for the bank's request if its row is open, tRCD has passed since the ACT
// and tCCD since the channel's last column command. Each moves bus_bytes x burst bytes in
// burst / beats_per_cycle data cycles, tCL (writes: tWL) after it, on the channel's data bus.
bool DramChannel::column_command(uint64_t now, Bank& b, bool* finished, DramRequest* out, uint64_t* done) {
    if (!b.serving || !b.open || b.row != b.req.at.row || now < b.column_ok || now < next_col_) return false;
    const uint64_t data = (uint64_t(cfg_.burst) + cfg_.beats_per_cycle - 1) / cfg_.beats_per_cycle;
    const DramRequest& r = b.req;
    next_col_ = now + cfg_.tCCD;
    // A precharge waits for a read's burst (GPGPU-Sim's RTPc), a write's recovery (WTPc).
    b.precharge_ok = std::max(b.precharge_ok, now + (r.write ? cfg_.tWL + data + cfg_.tWR : data));
    if (b.columns_left == columns(r.bytes)) stats_.queue_wait += now - std::min(now, r.arrival);  // its first column
    const uint64_t start = std::max(now + (r.write ? cfg_.tWL : cfg_.tCL), bus_free_);
    bus_free_ = start + data;
    if (--b.columns_left == 0) {
        (r.write ? stats_.writes : stats_.reads)++;
        stats_.bytes += r.bytes;
        stats_.data_cycles += transfer_cycles(r.bytes);
        *out = r;
        *done = bus_free_;
        *finished = true;
        b.serving = false;
        --serving_;
    }
    return true;
}

// An ACT for the bank's request if the bank is closed (tRP after its precharge, tRC after its
// last ACT, tRRD after the channel's last), or a precharge if it is open on another row (tRAS
// after its ACT and after its last column's burst or write recovery).
bool DramChannel::row_command(uint64_t now, Bank& b, uint32_t j) {
    if (!b.serving) return false;
    const uint32_t n = uint32_t(banks_.size());
    if (!b.open) {
        if (now < b.act_ok || now < channel_act_ok_) return false;
        b.open = true;
        b.activated = true;
        b.row = b.req.at.row;
        b.act = now;
        b.column_ok = now + cfg_.tRCD;
        b.precharge_ok = std::max(b.precharge_ok, now + cfg_.tRAS);
        b.act_ok = now + cfg_.tRC;
        channel_act_ok_ = now + cfg_.tRRD;
        prio_ = (j + 1) % n;
        return true;
    }
    if (b.row == b.req.at.row || now < b.precharge_ok) return false;
    b.open = false;
    b.act_ok = std::max(b.act_ok, now + cfg_.tRP);
    prio_ = (j + 1) % n;
    return true;
}

bool DramChannel::schedule_channel(uint64_t now, DramRequest* out, uint64_t* done) {
    if (queue_.empty()) return false;
    bool* hit = row_hits(queue_.size());
    for (size_t i = 0; i < queue_.size(); ++i) {
        const Bank& b = banks_[queue_[i].at.bank];
        hit[i] = b.open && b.row == queue_[i].at.row;
    }
    const size_t pick = cfg_.scheduler->pick(queue_.size(), hit);
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
      activations_(c.channels), stats_(c.channels), act_gap_(std::max<uint64_t>(c.tRC, uint64_t(c.tRAS) + c.tRP)),
      row_hits_first_(c.scheduler->row_hits_first()) {}

uint64_t DramBookings::access(uint64_t addr, uint32_t bytes, uint64_t now, uint64_t horizon) {
    const DramCoord at = map_.dram(addr);
    Bank& b = banks_[at.channel][at.bank];
    DramStats& st = stats_[at.channel];
    std::deque<Epoch>& epochs = b.epochs;
    // Epochs closed by the horizon cannot take a read any more (no read comes before it); the
    // last stays, as the bank's open row.
    while (epochs.size() > 1 && epochs.front().until <= horizon) epochs.pop_front();
    // A scheduler that takes a row hit ahead of older requests (FR-FCFS): the earliest epoch of
    // this row open at or after the read's arrival serves it. Else (FCFS) only the bank's last
    // epoch, as reads are served in turn.
    const Epoch* open = nullptr;
    for (const Epoch& e : epochs) {
        if (e.row == at.row && e.until > now && (row_hits_first_ || e.until == ~0ull)) {
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
        // The decision: the cycle the scheduler takes the request. frfcfs_channel and fcfs: the channel's
        // command sequence holds the precharge too, and the ACT overlaps the transfer ahead.
        // frfcfs_banks: the bank takes it at bank_start and precharges on its own; the channel
        // gives only the column slot, after the ACT's tRCD.
        uint64_t decision;
        if (cfg_.per_bank()) {
            column = commands_[at.channel].book(bank_start + pre + cfg_.tRCD, slot, horizon);
            decision = bank_start;
        } else {
            const uint64_t sequence = commands_[at.channel].book(bank_start + cfg_.tRCD, pre + slot, horizon);
            column = sequence + pre;
            decision = sequence - cfg_.tRCD;
        }
        st.queue_wait += column - now - pre - cfg_.tRCD;  // beyond the unloaded latency
        // The new epoch goes in at its decision; the one before it closes there.
        Epoch e{at.row, decision, column, ~0ull};
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
