#pragma once
// The cycle of ecat::Stack: the poll loop (AL event request 0x0220 and its dispatch to the state machine,
// the mailbox and the process data), the ESC-reset restart, the process-data watchdog, and the process data
// exchange itself (SM2 outputs into the dictionary, the application cycle, inputs out through SM3; other SMs
// where the description puts the process data, every SM of a direction where it has several) at the moments
// SyncControl says. It owns the process-data images (sized at Safe-Op, never per frame) and the
// interrupt-line bookkeeping.
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "ecat/stack_context.hpp"

namespace ecat {

class StateMachine;
class SyncControl;

class Cycle {
  public:
    using IrqLine = std::function<bool()>;

    // Housekeeping period for the mailbox handlers' poll() (transfer timeouts).
    static constexpr uint64_t kHousekeepingNs = 10'000'000;
    // AL event mask written at start: AL control, SYNC0, SM activation, PD watchdog, SM0, SM2, SM3. Not SM1:
    // its event ("buffer read by the master") stays set until the PDI writes the next message (ESC
    // datasheet, SM status 0x0805 bit 1), so after the last reply it would hold the interrupt line high for
    // good and every pass would poll the stack. While messages wait for SM1, quiet() is false anyway.
    // That is the mask of a device with mailbox and process data in SM2/SM3; a device without mailbox or
    // with its process data in other SMs (ProcessDataSms) gets the SM events of those.
    static constexpr uint32_t kEventMask = 0x00000D55;
    uint32_t event_mask() const { return event_mask_; }
    // The mask as written into 0x0204 now. In Op, DC-synchronous, with SYNC0 mapped to the AL event
    // register (0x0151 bit 3), the process-data SM events are left out of it: the cycle runs at SYNC0 and
    // reads the SM2 status there, so each frame's SM2/SM3 events would only wake the stack for a poll with
    // nothing to do (the interrupt mask of a DC-synchronous firmware on a hardware ESC; ESC datasheet, AL
    // event mask 0x0204). event_mask() in every other state.
    uint32_t written_mask() const { return written_mask_; }
    // Writes the mask the state asks for (after every state change).
    void update_event_mask();

    Cycle(StackContext& ctx, StateMachine& esm, SyncControl& sync, IrqLine irq);
    Cycle(const Cycle&) = delete;
    Cycle& operator=(const Cycle&) = delete;

    // The register set-up of a fresh start (and after an ESC reset): event mask, SMs deactivated on the PDI.
    void set_up_registers();

    void poll(uint64_t now_ns);
    // True if poll(now_ns) would return at once: the interrupt line is usable and low, no mailbox message
    // waits to be sent, and no deadline is due. registers_unchanged: the caller knows that no frame and no
    // timer event of the ESC changed its registers since the last poll (esc::EscSignals::activity); a stack
    // without a usable interrupt line, which reads the registers themselves, would find what its last poll
    // left there, so that alone does not keep it busy.
    bool quiet(uint64_t now_ns, bool registers_unchanged = false) const;
    uint64_t next_deadline_ns() const;
    uint64_t last_now_ns() const { return last_now_ns_; }

    // Process data, started at Safe-Op entry and stopped when leaving the process-data states.
    // The start address of each SM as the master configured it (SM n at [n]).
    void set_sm_starts(const std::array<uint16_t, ProcessData::kMaxSms>& starts) { sm_start_ = starts; }
    void start_process_data(uint64_t now_ns);
    void stop_process_data();
    // The whole output/input image (every SM of the direction, ctx_.pd's SmImage parts).
    std::size_t output_bytes() const { return sm2_buf_.size(); }
    std::size_t input_bytes() const { return sm3_buf_.size(); }
    uint16_t sm_start(unsigned n) const { return n < sm_start_.size() ? sm_start_[n] : 0; }
    bool outputs_seen() const { return outputs_seen_; }

    // Whether the interrupt line covers every SM event the stack waits on (SM control bit 5 set).
    void update_irq_usable();

  private:
    // mask: the AL event mask 0x0204 as read now.
    bool esc_was_reset(uint32_t mask) const;
    void write_mask(uint32_t mask);
    void restart_after_esc_reset(uint64_t now_ns);
    void process_data_events(uint32_t events, uint64_t now_ns);
    void run_cycle(uint64_t now_ns, bool fresh_outputs);
    void write_inputs();

    StackContext& ctx_;
    StateMachine& esm_;
    SyncControl& sync_;
    IrqLine irq_;

    uint32_t event_mask_ = kEventMask;
    uint32_t base_event_mask_ = kEventMask;  // outside the process-data states
    uint32_t written_mask_ = 0;              // 0x0204 as this stack last wrote it
    bool sync0_event_ = false;  // process data runs DC-synchronous and 0x0151 maps SYNC0 to 0x0220
    // The SMs whose events drive the cycle: ctx_.sms (kNoSm mapped to an SM that is never used, its buffer
    // stays empty), in the process-data states the first of each direction that carries PDOs.
    unsigned out_sm_ = 2;
    unsigned in_sm_ = 3;
    std::vector<uint8_t> sm2_buf_;  // the output image: every output SM's part (ProcessData::rx_sms())
    std::vector<uint8_t> sm3_buf_;  // the input image: every input SM's part (ProcessData::tx_sms())
    std::array<uint16_t, ProcessData::kMaxSms> sm_start_{};
    bool outputs_seen_ = false;
    // Device emulation, digital I/O configuration 0x0150 bit 3: the outputs are reset with the next output
    // event after a watchdog expiry rather than at the expiry (ESC datasheet section II, 0x0150).
    static constexpr uint8_t kOutputsResetAtNextEvent = 0x08;
    bool outputs_reset_pending_ = false;

    bool irq_usable_ = true;
    uint64_t housekeeping_at_ns_ = 0;
    uint64_t last_now_ns_ = 0;
    bool first_poll_ = true;
};

}  // namespace ecat
