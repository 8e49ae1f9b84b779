#pragma once
// A cyclic process-data session with one slave (buffered SMs and FMMUs: ESC datasheet section I §8.1, §7; AL
// states: ETG.1000.6; distributed clocks: ESC datasheet section I §9): discovers the process-data layout
// (SM2/SM3 from the SII SyncM category, sizes from the PDO assignment 0x1C12/0x1C13 and the mapping objects
// over CoE), sets up SM2/SM3 and two FMMUs, optionally distributed clocks with SYNC0, and exchanges outputs
// and inputs with one LRW per cycle (plus an FRMW of the reference clock's system time when DC is on).
// cycle() allocates nothing.
#include <chrono>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "master/coe.hpp"
#include "master/master.hpp"

namespace master {

struct ProcessDataLayout {
    uint16_t sm2_start = 0, sm2_length = 0;  // outputs (RxPDOs), bytes
    uint8_t sm2_control = 0x64;
    uint16_t sm3_start = 0, sm3_length = 0;  // inputs (TxPDOs), bytes
    uint8_t sm3_control = 0x20;
    std::vector<uint16_t> rx_pdos, tx_pdos;  // assigned PDOs
};

struct DcConfig {
    bool enable = false;
    uint32_t cycle_ns = 1'000'000;
    int32_t shift_ns = 0;                        // SYNC0 start offset within the cycle
    uint16_t assign_activate = 0x0300;           // 0x0980/0x0981 word: cyclic unit + SYNC0
    std::chrono::milliseconds start_delay{100};  // first SYNC0 this far in the future (IgH, SOEM)
};

struct CycleStats {
    uint64_t cycles = 0;
    uint64_t wkc_errors = 0;  // cycles whose LRW came back with another working counter
    uint64_t lost = 0;        // cycles without a reply
    std::chrono::nanoseconds rtt_min{std::chrono::nanoseconds::max()};
    std::chrono::nanoseconds rtt_max{0};
    std::chrono::nanoseconds rtt_sum{0};
};

class ProcessDataSession {
  public:
    static constexpr uint32_t kLogicalBase = 0x00010000;

    // slave must be a station address (the FRMW of DC needs one); sdo must run over its mailbox.
    ProcessDataSession(Master& master, Address slave, SdoClient& sdo);

    // Reads the layout (SII + CoE). The slave must be in PREOP.
    Error discover();
    const ProcessDataLayout& layout() const { return layout_; }
    // Sync mode objects (0x1C32:01, 0x1C33:01): DC SYNC0 (2) with dc.enable, else SM-synchronous (1).
    // Then SM2/SM3, FMMU0 (outputs, write) and FMMU1 (inputs, read); with dc.enable also the clock
    // offset and SYNC0 (0x0980/0x09A0/0x0990/0x0981).
    Error configure(const DcConfig& dc = {});

    // One process-data exchange: outputs() go out, inputs() come back. Returns Error::WorkingCounter if
    // the LRW's working counter is not expected_wkc() (the data is still copied).
    Error cycle();
    std::span<uint8_t> outputs() { return {image_.data(), layout_.sm2_length}; }
    std::span<const uint8_t> inputs() const {
        return {image_.data() + layout_.sm2_length, layout_.sm3_length};
    }
    uint16_t expected_wkc() const;
    uint16_t last_wkc() const { return lrw_.wkc; }
    uint64_t reference_time() const { return ref_time_; }  // DC system time read in the last cycle
    const CycleStats& stats() const { return stats_; }

    // Requests a state while cycling every `period` (SAFEOP -> OP needs valid outputs arriving);
    // each_cycle runs before every exchange (fill outputs). Returns like Master::request_state.
    Error request_state(AlState state, std::chrono::microseconds period, AlStatus* final = nullptr,
                        const std::function<void()>& each_cycle = {});
    // Runs `count` cycles at `period` (absolute-time sleeps), each_cycle before each exchange.
    Error run(uint64_t count, std::chrono::microseconds period, const std::function<void()>& each_cycle = {});

  private:
    Error pdo_bytes(uint16_t assign_index, std::vector<uint16_t>& pdos, uint16_t& bytes);
    Error configure_dc(const DcConfig& dc);

    Master& m_;
    Address slave_;
    SdoClient& sdo_;
    ProcessDataLayout layout_;
    bool dc_ = false;
    std::vector<uint8_t> image_;
    std::array<uint8_t, 8> time_{};
    Datagram dg_[2];
    Datagram& lrw_ = dg_[0];
    uint64_t ref_time_ = 0;
    CycleStats stats_;
};

}  // namespace master
