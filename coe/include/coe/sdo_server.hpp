#pragma once
// The CoE mailbox protocol (ETG.1000.6, CoE): SDO server (expedited, normal, segmented, complete
// access), SDO information service and the emergency sender, on top of the object model.
//
// Requests arrive through ecat::MailboxHandler::handle() as mailbox payloads (CoE header first). Every
// answer goes out through the MailboxSender; what the sender cannot take right now (queue full, SDO info
// fragments, emergencies) waits and is sent from poll(). Nothing on the request path allocates once the
// server is built (buffers are sized from the dictionary at construction).
//
// Wiring, as the runtime does it (the dictionary first in its final place, since hooks keep pointers to it):
//   coe::install_pdo_validators(dict);                          // 0x16xx/0x1Axx/0x1C12/0x1C13 checks
//   coe::CoeServer coe(dict, [&] { return stack.state(); });    // stack.add_handler(coe)
//   coe::DiagnosisHistory diag(dict, &coe.emergency());        // 0x10F3
//   coe::EventReporter events(coe.emergency(), &diag, dc_time); // behind the drive's EventSink
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "coe/emergency.hpp"
#include "coe/faults.hpp"
#include "ecat/mailbox_handler.hpp"
#include "od/dictionary.hpp"

namespace coe {

struct CoeConfig {
    // A segmented transfer the master leaves alone this long is dropped and answered with abort 0x05040000.
    uint64_t transfer_timeout_ns = 2'000'000'000;
    std::size_t emergency_queue = 8;
    // The device announces SDO complete access (SII General CoE details bit 5, ESI CoE CompleteAccess);
    // without it a complete-access request is aborted with 0x06010004 (ETG.1000.6), as such devices do.
    bool complete_access = true;
    CoeFaults faults;  // testing aid: deliberate deviations (coe/faults.hpp), all off
};

class CoeServer final : public ecat::MailboxHandler {
  public:
    using StateFn = std::function<od::AlState()>;

    CoeServer(od::Dictionary& dict, StateFn state, CoeConfig config = {});
    CoeServer(const CoeServer&) = delete;
    CoeServer& operator=(const CoeServer&) = delete;

    ecat::MailboxType type() const override { return ecat::MailboxType::CoE; }
    // CoE is served in Pre-Op, Safe-Op and Op (not in Init, not in Bootstrap).
    bool available(od::AlState state) const override;
    void handle(std::span<const uint8_t> payload, ecat::MailboxSender& out) override;
    void poll(uint64_t now_ns, ecat::MailboxSender& out) override;
    void on_state_change(od::AlState from, od::AlState to) override;

    Emergency& emergency() { return emergency_; }
    const Emergency& emergency() const { return emergency_; }

    // Introspection (tests, diagnostics).
    bool transfer_in_progress() const { return xfer_.kind != Transfer::None; }
    bool output_pending() const { return held_len_ > 0 || info_.active; }

  private:
    struct Transfer {
        enum Kind : uint8_t { None, Upload, Download } kind = None;
        uint16_t index = 0;
        uint8_t sub = 0;
        bool complete_access = false;
        bool size_known = false;
        uint8_t toggle = 0;     // expected toggle of the next segment
        std::size_t size = 0;   // total bytes (download: announced size if size_known)
        std::size_t done = 0;   // bytes sent / received so far
        uint64_t stamp_ns = 0;  // last activity (set from poll's clock)
        bool stamp_pending = true;
    };
    struct InfoReply {
        bool active = false;
        uint8_t opcode = 0;
        std::size_t length = 0;  // bytes of body in info_buf_
        std::size_t sent = 0;
        std::size_t chunk = 0;  // body bytes per fragment
        uint16_t fragments_left = 0;
    };

    // SDO
    void handle_sdo(std::span<const uint8_t> sdo, std::size_t frame_size, ecat::MailboxSender& out);
    void upload_initiate(uint16_t index, uint8_t sub, bool ca, ecat::MailboxSender& out);
    void upload_segment(uint8_t cmd, ecat::MailboxSender& out);
    void download_initiate(std::span<const uint8_t> sdo, ecat::MailboxSender& out);
    void download_segment(std::span<const uint8_t> sdo, ecat::MailboxSender& out);
    uint32_t commit_download();
    void send_upload_segment(ecat::MailboxSender& out);
    void send_abort(uint16_t index, uint8_t sub, uint32_t code, ecat::MailboxSender& out);
    void confirm_download(uint16_t index, uint8_t sub, ecat::MailboxSender& out);  // faults only
    od::AlState write_state(uint16_t index) const;
    bool is_pdo_object(uint16_t index) const;
    bool pdo_locked(uint16_t index) const;
    void cancel_transfer();

    // SDO information
    void handle_info(std::span<const uint8_t> body, ecat::MailboxSender& out);
    void info_od_list(uint16_t list_type, ecat::MailboxSender& out);
    void info_object(uint16_t index, ecat::MailboxSender& out);
    void info_entry(uint16_t index, uint8_t sub, uint8_t value_info, ecat::MailboxSender& out);
    void info_error(uint32_t code, ecat::MailboxSender& out);
    void start_info_reply(uint8_t opcode, std::size_t length, std::size_t item, ecat::MailboxSender& out);
    void pump_info(ecat::MailboxSender& out);

    // Output path
    bool send(std::span<const uint8_t> payload, ecat::MailboxSender& out);
    void send_mailbox_error(ecat::MailboxError e, ecat::MailboxSender& out);
    uint8_t* tx(std::size_t size);

    od::AlState state() const { return state_ ? state_() : od::AlState::PreOp; }

    od::Dictionary& dict_;
    StateFn state_;
    CoeConfig config_;
    Emergency emergency_;

    Transfer xfer_;
    std::vector<uint8_t> data_;      // whole value of the current transfer
    std::vector<uint8_t> scratch_;   // one entry
    std::vector<uint8_t> rollback_;  // complete-access download undo
    std::vector<uint8_t> tx_;        // message under construction
    std::vector<uint8_t> held_;      // a reply the sender could not take yet
    std::size_t held_len_ = 0;
    ecat::MailboxType held_type_ = ecat::MailboxType::CoE;
    std::vector<uint8_t> info_buf_;  // SDO info answer body
    InfoReply info_;
    uint64_t now_ns_ = 0;
    uint8_t abort_command_ = 0x80;  // command byte of the next abort (0x80; faults: the request's)
};

}  // namespace coe
