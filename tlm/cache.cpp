#include "cache.h"

namespace rtu {

using namespace sc_core;

Cache::Cache(sc_module_name name, CacheRole role, const CacheConfig& cfg, uint32_t hit_latency, PayloadPool& pool,
             const ClockDomain& clock, Fidelity fidelity, OrderedEvents& events)
    : sc_module(name), in("in"), out("out"), role_(role), cfg_(cfg), hit_latency_(hit_latency),
      // LT: the L1 takes its RT unit's requests, one per cycle, in order; an L2 slice books its lookups.
      lt_(cfg, hit_latency, role == CacheRole::L2), tags_(lt_.tags()), pool_(pool),
      clock_(clock), fidelity_(fidelity), respond_(events, [this] { send_responses(); }), miss_event_(events, [this] { send_misses(); }),
      hit_peq_(respond_, resp_seq_), fill_peq_(respond_, resp_seq_), no_data_(cfg.sector) {
    if (fidelity == Fidelity::AT) {
        in.register_nb_transport_fw(this, &Cache::nb_transport_fw);
        out.register_nb_transport_bw(this, &Cache::nb_transport_bw);
    } else {
        in.register_b_transport(this, &Cache::b_transport);
    }
}

// ---- AT ---------------------------------------------------------------------------------------

// A read of the sector at `addr` for `up`; null: a shader read (shader_read), which nobody waits
// for and whose miss carries no data of the image.
bool Cache::lookup(uint64_t addr, const RtExtension& e, tlm::tlm_generic_payload* up) {
    if (miss_queue_full() && tags_.would_miss(addr)) {
        tags_.count_reservation_fail(e.kind);
        return false;
    }
    const uint64_t token = next_token_++;
    switch (tags_.read(addr, token, e.kind)) {
        case CacheOutcome::ReservationFail:
            return false;
        case CacheOutcome::Hit:
            if (up) respond_later(*up, true);
            return true;
        case CacheOutcome::MshrHit:
            waiting_[token] = up;
            return true;
        case CacheOutcome::SectorMiss:
        case CacheOutcome::LineMiss: {
            waiting_[token] = up;
            const uint64_t sector = tags_.sector_of(addr);
            tlm::tlm_generic_payload* down =
                pool_.acquire(sector, cfg_.sector, up ? up->get_data_ptr() - (addr - sector) : no_data_.data());
            RtExtension& de = ext(*down);
            de = e;
            de.requester = role_ == CacheRole::L1 ? Requester::L1 : Requester::L2;
            de.l1_miss = de.dram = false;
            de.id = sector;
            // The tag lookup takes the hit latency before the miss leaves.
            const uint64_t leave = clock_.cycle_at_or_after(sc_time_stamp()) + hit_latency_;
            miss_queue_.push_back({leave, down});
            if (miss_queue_.size() == 1) miss_event_.notify(clock_.time_of(leave) - sc_time_stamp());
            return true;
        }
    }
    return false;
}

bool Cache::shader_read(uint64_t addr, uint64_t cycle) {
    RtExtension e;
    e.kind = ReqKind::Shader;
    if (fidelity_ == Fidelity::AT) return lookup(addr, e, nullptr);
    tlm::tlm_generic_payload* t = pool_.acquire(tags_.sector_of(addr), cfg_.sector, no_data_.data());
    ext(*t) = e;
    sc_time d = clock_.time_of(cycle) - sc_time_stamp();
    b_transport(*t, d);
    t->release();
    return true;
}

// GPGPU-Sim's miss_queue_full(1) (CacheConfig::miss_queue): `miss_queue` - 1 misses or more wait to
// leave. A miss joins the queue once its tag lookup's hit latency is over (GPGPU-Sim times the L2's
// latency before the lookup, in its ROP queue); misses queue in the order they may leave.
bool Cache::miss_queue_full() const {
    if (!cfg_.miss_queue || miss_queue_.size() + 1 < cfg_.miss_queue) return false;
    const uint64_t now = clock_.cycle_at_or_after(sc_time_stamp());
    size_t waiting = 0;
    for (auto it = miss_queue_.begin(); it != miss_queue_.end() && it->first <= now && waiting + 1 < cfg_.miss_queue; ++it) ++waiting;
    return waiting + 1 >= cfg_.miss_queue;
}

void Cache::respond_later(tlm::tlm_generic_payload& t, bool hit) {
    if (hit) hit_peq_.notify(t, clock_.period() * double(hit_latency_));
    else fill_peq_.notify(t, SC_ZERO_TIME);
}

tlm::tlm_sync_enum Cache::nb_transport_fw(tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_time& d) {
    if (ph == tlm::BEGIN_REQ) {
        t.acquire();
        if (lookup(t.get_address(), ext(t), &t)) {
            ph = tlm::END_REQ;
            return tlm::TLM_UPDATED;
        }
        blocked_ = &t;  // END_REQ withheld until an MSHR or a way frees
        return tlm::TLM_ACCEPTED;
    }
    if (ph == tlm::END_RESP) {
        // The requester took a response it had held back: the next one may go.
        if (&t != resp_open_) SC_REPORT_FATAL(name(), "END_RESP for a response not held");
        resp_open_ = nullptr;
        t.release();
        if (!resp_queue_.empty()) respond_.notify(SC_ZERO_TIME);
        return tlm::TLM_COMPLETED;
    }
    SC_REPORT_FATAL(name(), "unexpected phase on the forward path");
    return tlm::TLM_COMPLETED;
}

void Cache::send_responses() {
    while (tlm::tlm_generic_payload* t = FifoPeq<tlm::tlm_generic_payload>::merge_next(hit_peq_, fill_peq_)) resp_queue_.push_back(t);
    if (resp_queue_.empty() || resp_open_) return;  // none, or the last one not ended yet
    const uint64_t c = clock_.cycle_at_or_after(sc_time_stamp());
    if (c == last_resp_cycle_ || clock_.time_of(c) != sc_time_stamp()) {
        respond_.notify(clock_.time_of(c == last_resp_cycle_ ? c + 1 : c) - sc_time_stamp());
        return;
    }
    last_resp_cycle_ = c;
    tlm::tlm_generic_payload* t = resp_queue_.front();
    resp_queue_.pop_front();
    t->set_response_status(tlm::TLM_OK_RESPONSE);
    tlm::tlm_phase ph = tlm::BEGIN_RESP;
    sc_time d = SC_ZERO_TIME;
    const tlm::tlm_sync_enum r = in->nb_transport_bw(*t, ph, d);
    if (r == tlm::TLM_ACCEPTED) {
        resp_open_ = t;  // the requester (an RT unit with a full response FIFO) ends it later
        return;
    }
    if (r != tlm::TLM_COMPLETED) SC_REPORT_FATAL(name(), "unexpected reply to BEGIN_RESP");
    t->release();
    if (!resp_queue_.empty()) respond_.notify(clock_.period());
}

void Cache::send_misses() {
    if (down_waiting_end_req_ || miss_queue_.empty()) return;
    const uint64_t c = clock_.cycle_at_or_after(sc_time_stamp());
    const uint64_t due = std::max(miss_queue_.front().first, c == last_miss_cycle_ ? c + 1 : c);
    if (clock_.time_of(due) != sc_time_stamp()) {
        miss_event_.notify(clock_.time_of(due) - sc_time_stamp());
        return;
    }
    last_miss_cycle_ = c;
    tlm::tlm_generic_payload* t = miss_queue_.front().second;
    tlm::tlm_phase ph = tlm::BEGIN_REQ;
    sc_time d = SC_ZERO_TIME;
    const tlm::tlm_sync_enum s = out->nb_transport_fw(*t, ph, d);
    if (s == tlm::TLM_UPDATED && ph == tlm::END_REQ) {
        miss_queue_.pop_front();
        if (!miss_queue_.empty()) miss_event_.notify(clock_.period());  // send_misses waits for its due cycle
        retry_blocked();
    } else if (s == tlm::TLM_ACCEPTED) {
        down_waiting_end_req_ = true;
    } else {
        SC_REPORT_FATAL(name(), "unexpected reply to BEGIN_REQ");
    }
}

tlm::tlm_sync_enum Cache::nb_transport_bw(tlm::tlm_generic_payload& t, tlm::tlm_phase& ph, sc_time& d) {
    if (ph == tlm::END_REQ) {
        down_waiting_end_req_ = false;
        miss_queue_.pop_front();
        if (!miss_queue_.empty()) miss_event_.notify(clock_.period());
        retry_blocked();
        return tlm::TLM_ACCEPTED;
    }
    if (ph != tlm::BEGIN_RESP) {
        SC_REPORT_FATAL(name(), "unexpected phase on the backward path");
        return tlm::TLM_COMPLETED;
    }
    // A sector arrived: every request waiting on it gets its response.
    const bool from_dram = role_ == CacheRole::L2 || ext(t).dram;
    for (uint64_t token : tags_.fill(t.get_address())) {
        tlm::tlm_generic_payload* up = waiting_.at(token);
        waiting_.erase(token);
        if (!up) continue;  // a shader read's: nobody waits
        RtExtension& e = ext(*up);
        if (role_ == CacheRole::L1) e.l1_miss = true;
        e.dram = e.dram || from_dram;
        respond_later(*up, false);
    }
    t.release();
    retry_blocked();  // an MSHR freed
    return tlm::TLM_COMPLETED;
}

// An MSHR freed or a miss left: the request held by a reservation fail tries again.
void Cache::retry_blocked() {
    if (blocked_ && lookup(blocked_->get_address(), ext(*blocked_), blocked_)) {
        tlm::tlm_generic_payload* b = blocked_;
        blocked_ = nullptr;
        send_end_request(in.operator->(), *b);
    }
}

// ---- LT ---------------------------------------------------------------------------------------

void Cache::b_transport(tlm::tlm_generic_payload& t, sc_time& d) {
    RtExtension& e = ext(t);
    lt_.advance(clock_.cycle_at_or_before(sc_time_stamp()));  // no requester is behind simulated time
    const CacheBookings::Lookup l = lt_.lookup(t.get_address(), clock_.cycle_at_or_after(sc_time_stamp() + d), e.kind);
    uint64_t done = l.ready;
    if (role_ == CacheRole::L1) e.accepted_at = l.retry_at;  // a reservation fail: the port waits, as in AT
    if (l.outcome == CacheBookings::Lookup::InFlight) {  // waits for a miss on its way
        if (role_ == CacheRole::L1) e.l1_miss = true;
        e.dram = e.dram || l.dram;
    } else if (l.outcome == CacheBookings::Lookup::Miss) {
        const uint64_t sector = tags_.sector_of(t.get_address());
        tlm::tlm_generic_payload* down = pool_.acquire(sector, cfg_.sector, t.get_data_ptr() - (t.get_address() - sector));
        ext(*down) = e;
        ext(*down).requester = role_ == CacheRole::L1 ? Requester::L1 : Requester::L2;
        ext(*down).dram = false;
        sc_time dd = clock_.time_of(l.ready) - sc_time_stamp();
        out->b_transport(*down, dd);
        done = clock_.cycle_at_or_after(sc_time_stamp() + dd);
        const bool dram = role_ == CacheRole::L2 || ext(*down).dram;
        e.dram = e.dram || dram;
        if (role_ == CacheRole::L1) e.l1_miss = true;
        down->release();
        lt_.fill(t.get_address(), l, done, dram, e.kind);
    }
    t.set_response_status(tlm::TLM_OK_RESPONSE);
    d = clock_.time_of(done) - sc_time_stamp();
}

}  // namespace rtu
