#pragma once
// A cyclic process-data session with one slave or a whole line of them (buffered SMs and FMMUs: ESC datasheet
// section I §8.1, §7; AL states: ETG.1000.6; distributed clocks: ESC datasheet section I §9, ETG.1020):
// discovers each slave's process-data layout (every SM of type 3 (outputs) and 4 (inputs) of the SII SyncM
// category, sizes from their PDO assignment 0x1C10+n and the mapping objects over CoE, or from the SII's
// RxPDO/TxPDO categories), sets up every process-data SM and one FMMU per SM that carries data (SMs adjacent
// in memory share one, ProcessDataLayout::fmmus()) into one
// logical image (the outputs of all slaves back to back, then their inputs; within a slave in SM order),
// optionally distributed clocks (delays and offsets measured over the line, SYNC0 on every slave with the
// same start time), and exchanges outputs and inputs with one LRW per cycle (split over several frames, sent
// back to back, only when the image does not fit one), plus an FRMW of the reference clock's system time when
// DC is on. Expected working counter: the sum over the slaves of 2 (outputs written) + 1 (inputs read),
// whatever the number of FMMUs: an ESC counts a datagram once per slave and direction when at least one of
// its FMMUs read or wrote (ESC datasheet section I, "Working counter"; ETG.1000.4 LRW). cycle() allocates
// nothing.
#include <chrono>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "master/bus.hpp"
#include "master/coe.hpp"
#include "master/master.hpp"

namespace master {

// One process-data SyncManager: an SM of type 3 (outputs, RxPDOs) or 4 (inputs, TxPDOs) in the SII SyncM
// category (ETG.1000.6; ETG.2000 Sm elements), with the PDOs assigned to it and their bytes.
struct ProcessDataSm {
    uint8_t index = 0;  // SM n
    bool outputs = true;
    uint16_t start = 0;
    uint16_t length = 0;  // bytes of the assigned PDOs; 0: the SM carries nothing and stays disabled
    uint8_t control = 0;
    std::vector<uint16_t> pdos;  // assigned PDOs (0x1C10+n, else the SII's PDOs of SM n), in order
};

struct ProcessDataLayout {
    // Every process-data SM of the slave, in SM order: SM2/SM3 (and SM4, SM5, ... on devices with several
    // per direction) with a mailbox, from SM0 on a device without one.
    std::vector<ProcessDataSm> sms;

    // Adds an SM (a layout made by hand, for set_layout()).
    ProcessDataLayout& add(uint8_t index, bool outputs, uint16_t start, uint16_t length, uint8_t control) {
        sms.push_back(ProcessDataSm{index, outputs, start, length, control, {}});
        return *this;
    }
    // Bytes of the outputs (inputs): the sum over the SMs of that direction.
    uint32_t bytes(bool outputs) const {
        uint32_t n = 0;
        for (const ProcessDataSm& sm : sms)
            if (sm.outputs == outputs) n += sm.length;
        return n;
    }
    uint32_t output_bytes() const { return bytes(true); }
    uint32_t input_bytes() const { return bytes(false); }
    // SMs that carry data.
    std::size_t sms_with_data() const {
        std::size_t n = 0;
        for (const ProcessDataSm& sm : sms)
            n += sm.length ? 1 : 0;
        return n;
    }
    // The first SM of this direction that carries data, else the first of this direction; nullptr: none.
    const ProcessDataSm* first(bool outputs) const {
        const ProcessDataSm* any = nullptr;
        for (const ProcessDataSm& sm : sms) {
            if (sm.outputs != outputs) continue;
            if (sm.length) return &sm;
            if (!any) any = &sm;
        }
        return any;
    }
    // The FMMUs the layout needs, in the order the session sets them up from FMMU0 on: the outputs SMs with
    // data (write) in SM order, then the inputs SMs (read), each at its offset within its direction's part
    // of the image; an SM that starts where the previous one of the list ends in memory shares its FMMU
    // (one logical range onto one physical range: FB1111's four one-byte outputs SMs 0x0F00..0x0F03 under
    // the one FMMU its ESI declares, as SOEM and TwinCAT map them).
    struct Fmmu {
        bool outputs = true;
        uint32_t offset = 0;  // within the outputs (inputs) of the slave
        uint16_t length = 0, physical = 0;
    };
    std::vector<Fmmu> fmmus() const {
        std::vector<Fmmu> r;
        for (const bool outputs : {true, false}) {
            uint32_t offset = 0;
            bool joinable = false;
            for (const ProcessDataSm& sm : sms) {
                if (sm.outputs != outputs || !sm.length) continue;
                if (joinable && r.back().physical + r.back().length == sm.start &&
                    r.back().length + sm.length <= 0xFFFF)
                    r.back().length = static_cast<uint16_t>(r.back().length + sm.length);
                else
                    r.push_back(Fmmu{outputs, offset, sm.length, sm.start});
                joinable = true;
                offset += sm.length;
            }
        }
        return r;
    }
    // The PDOs assigned to the SMs of this direction, in SM order.
    std::vector<uint16_t> pdos(bool outputs) const {
        std::vector<uint16_t> r;
        for (const ProcessDataSm& sm : sms)
            if (sm.outputs == outputs) r.insert(r.end(), sm.pdos.begin(), sm.pdos.end());
        return r;
    }
};

struct DcConfig {
    bool enable = false;
    uint32_t cycle_ns = 1'000'000;
    int32_t shift_ns = 0;                        // SYNC0 start offset within the cycle
    uint16_t assign_activate = 0x0300;           // 0x0980/0x0981 word: cyclic unit + SYNC0
    std::chrono::milliseconds start_delay{100};  // first SYNC0 this far in the future (IgH, SOEM)
    // Measure delays and offsets over the session's slaves (bus.hpp configure_dc; for more than one slave
    // they must be the whole line in position order). false: the caller did it already (configure_dc on
    // the scan of the bus) and the session only sets SYNC0 up.
    bool measure = true;
    DcMeasureOptions measure_options;
};

struct CycleStats {
    uint64_t cycles = 0;
    uint64_t wkc_errors = 0;  // cycles whose LRW came back with another working counter
    uint64_t lost = 0;        // cycles without a reply
    std::chrono::nanoseconds rtt_min{std::chrono::nanoseconds::max()};
    std::chrono::nanoseconds rtt_max{0};
    std::chrono::nanoseconds rtt_sum{0};
    // Longest time between the starts of two cycles: the master's own pauses, which a slave's process-data
    // watchdog or DC synchronisation check sees as a communication gap.
    std::chrono::nanoseconds gap_max{0};
};

class ProcessDataSession {
  public:
    static constexpr uint32_t kLogicalBase = 0x00010000;

    // One slave. slave must be a station address (the FRMW of DC needs one); sdo must run over its mailbox.
    ProcessDataSession(Master& master, Address slave, SdoClient& sdo);
    // Several slaves (station addresses) in one image, in this order. sdos: one per slave, or empty; a
    // slave without an SDO client (nullptr) gets its layout from set_layout() and no sync-mode objects.
    ProcessDataSession(Master& master, std::span<const Address> slaves,
                       std::span<SdoClient* const> sdos = {});

    std::size_t size() const { return slaves_.size(); }
    Address address(std::size_t k) const { return slaves_[k].address; }

    // Reads each slave's layout (SII + CoE). The slaves must be in PREOP.
    Error discover();
    // Slave k's layout from its SII alone (SyncM category, and the PDOs of the TxPDO/RxPDO categories
    // assigned to the process-data SMs): for a slave without mailbox.
    Error discover_sii(std::size_t k);
    const ProcessDataLayout& layout(std::size_t k = 0) const { return slaves_[k].layout; }
    void set_layout(std::size_t k, const ProcessDataLayout& layout) { slaves_[k].layout = layout; }
    // For each slave: sync mode objects (0x1C32:01, 0x1C33:01): DC SYNC0 (2) with dc.enable, else
    // SM-synchronous (1); every process-data SM (those without data disabled); the FMMUs of
    // ProcessDataLayout::fmmus() from FMMU0 on, the slave's other FMMUs disabled. A slave with fewer FMMUs
    // (ESC 0x0004) than that: Error::TooFewFmmus, before any slave is touched. With dc.enable also the delays
    // and offsets (dc.measure) and SYNC0 (0x0980/0x09A0/0x0990/0x0981) with one start time for all.
    Error configure(const DcConfig& dc = {});

    // One process-data exchange: outputs() go out, inputs() come back. Returns Error::WorkingCounter if
    // the LRW's working counter is not expected_wkc() (the data is still copied).
    Error cycle();
    // All slaves' outputs (inputs) back to back, in slave order; or those of slave k.
    std::span<uint8_t> outputs() { return {image_.data(), out_bytes_}; }
    std::span<const uint8_t> inputs() const { return {image_.data() + out_bytes_, in_bytes_}; }
    std::span<uint8_t> outputs(std::size_t k);
    std::span<const uint8_t> inputs(std::size_t k) const;
    uint16_t expected_wkc() const;
    uint16_t expected_wkc(std::size_t k) const;  // this slave's share: 2 with outputs + 1 with inputs
    uint16_t last_wkc() const { return last_wkc_; }
    // Frames per cycle: 1 unless the image is larger than one frame's LRW can carry.
    std::size_t frames_per_cycle() const { return chunks_.size(); }
    uint64_t reference_time() const { return ref_time_; }  // DC system time read in the last cycle
    const CycleStats& stats() const { return stats_; }
    void reset_gap_max() { stats_.gap_max = {}; }  // the longest pause is counted afresh from here
    // The slaves as the DC measurement saw them (topology, delays, offsets); empty without dc.measure.
    std::span<const SlaveInfo> dc_slaves() const { return dc_slaves_; }
    // AL status of every slave, read in as few frames as fit (after a working-counter error: who is gone or
    // not in the state). A slave that does not answer gets state 0.
    Error read_states(std::span<AlStatus> out);

    // Requests a state while cycling every `period` (SAFEOP -> OP needs valid outputs arriving);
    // each_cycle runs before every exchange (fill outputs). Returns like Master::request_state.
    Error request_state(AlState state, std::chrono::microseconds period, AlStatus* final = nullptr,
                        const std::function<void()>& each_cycle = {});
    // Runs `count` cycles at `period` (absolute-time sleeps), each_cycle before each exchange.
    Error run(uint64_t count, std::chrono::microseconds period, const std::function<void()>& each_cycle = {});

  private:
    struct Slave {
        Address address;
        SdoClient* sdo = nullptr;
        ProcessDataLayout layout;
        uint32_t out_offset = 0, in_offset = 0;  // in the image
        uint8_t fmmus = 0;                       // ESC 0x0004, read by configure()
    };
    // One frame of the cycle: an LRW over part of the image (the FRMW of DC rides in the first).
    struct Chunk {
        Datagram dg[2];  // the LRW, then the FRMW in the first frame with DC
        std::size_t count = 1;
        uint16_t expected_wkc = 0;
    };
    Error discover(Slave& s);
    Error pdo_bytes(SdoClient& sdo, uint16_t assign_index, std::vector<uint16_t>& pdos, uint16_t& bytes);
    Error check_fmmus();
    Error configure(Slave& s, const DcConfig& dc);
    Error configure_dc(const DcConfig& dc);
    Error write_al_control(AlState state, bool acknowledge, uint8_t current);
    Error states_reached(AlState state, AlStatus* final, bool& done);

    Master& m_;
    std::vector<Slave> slaves_;
    uint32_t out_bytes_ = 0, in_bytes_ = 0;
    bool dc_ = false;
    uint16_t reference_ = 0;  // station address of the reference clock
    std::vector<uint8_t> image_;
    std::vector<Chunk> chunks_;
    std::vector<std::span<Datagram>> frames_;  // the datagrams of each chunk, for Master::exchange_frames
    std::array<uint8_t, 8> time_{};
    uint16_t last_wkc_ = 0;
    uint64_t ref_time_ = 0;
    CycleStats stats_;
    std::chrono::steady_clock::time_point last_cycle_start_{};
    std::vector<SlaveInfo> dc_slaves_;
    std::vector<AlStatus> states_;
    std::vector<uint8_t> state_buf_;
};

}  // namespace master
