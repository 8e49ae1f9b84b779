#pragma once
// The mailbox layer (ETG.1000.4 mailbox; ESC datasheet, SyncManager mailbox mode and repeat): SM0 (master ->
// slave) is read to its last byte whenever it is full, the 6-byte header is checked, counters are
// de-duplicated, the payload is dispatched to the registered MailboxHandler; replies wait in a fixed-capacity
// queue and are written into SM1 (whole SM1 length, so the last byte completes the buffer) whenever SM1 is
// empty. The last message read by the master is kept for the repeat request/acknowledge handshake. Nothing is
// allocated per message.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "ecat/faults.hpp"
#include "ecat/mailbox_handler.hpp"
#include "esc/pdi.hpp"
#include "od/device.hpp"
#include "od/types.hpp"

namespace ecat {

struct MailboxStats {
    uint64_t received = 0;     // requests read from SM0
    uint64_t dispatched = 0;   // requests handed to a handler
    uint64_t duplicates = 0;   // repeated requests (same non-zero counter) dropped
    uint64_t errors_sent = 0;  // mailbox error replies queued
    uint64_t sent = 0;         // messages written into SM1 (first time)
    uint64_t repeats = 0;      // repeat requests served
    uint64_t queue_full = 0;   // messages refused because the queue was full
};

class Mailbox final : public MailboxSender {
  public:
    static constexpr std::size_t kQueueCapacity = 16;
    static constexpr std::size_t kMaxHandlers = 8;

    // max_size: largest SM0/SM1 length this mailbox will ever be started with (standard or bootstrap).
    Mailbox(esc::Pdi& pdi, std::size_t max_size);

    // Registers a protocol handler (at most one per mailbox type; a later one replaces an earlier one).
    void add_handler(MailboxHandler& handler);

    // Starts the mailbox on the given SM0/SM1 layout (I->P or I->B): empty queue, counters reset, SM0/SM1
    // PDI-activated. state is the AL state the mailbox serves (PreOp or Boot).
    void start(const od::MailboxLayout& layout, od::AlState state);
    // Stops it (P->I, B->I, ...): queue dropped, SM0/SM1 deactivated from the PDI side.
    void stop();
    bool running() const { return running_; }
    // Tells the mailbox (and the handlers) the AL state changed.
    void set_state(od::AlState from, od::AlState to);

    // One pass: serves a repeat request, reads and dispatches a request from SM0, gives the handlers time,
    // writes the next queued message into SM1 if it is empty.
    void poll(uint64_t now_ns);
    // Whether a message is waiting in the queue.
    std::size_t queued() const { return count_; }
    const MailboxStats& stats() const { return stats_; }

    // ---- MailboxSender -----------------------------------------------------------------------------
    bool send(MailboxType type, std::span<const uint8_t> payload) override;
    std::size_t max_payload() const override;

    // Queues a mailbox error reply (type 0) with the given detail code.
    bool send_error(MailboxError detail);
    // Testing aid: deliberate deviations (ecat/faults.hpp); none by default.
    void set_faults(const MailboxFaults& faults) { faults_ = faults; }

  private:
    void receive();
    void dispatch(std::span<const uint8_t> message);
    void serve_repeat_request();
    void transmit();
    void write_sm1(std::span<const uint8_t> message);
    uint8_t next_counter();
    uint8_t* slot(std::size_t i) { return storage_.data() + i * max_size_; }
    uint16_t sm1_base() const;

    esc::Pdi& pdi_;
    std::size_t max_size_;
    std::array<MailboxHandler*, kMaxHandlers> handlers_{};
    std::size_t handler_count_ = 0;

    od::MailboxLayout layout_{};
    od::AlState state_ = od::AlState::Init;
    bool running_ = false;

    // Outgoing queue: kQueueCapacity slots of max_size_ bytes, each a complete message (header + payload).
    std::vector<uint8_t> storage_;
    std::array<uint16_t, kQueueCapacity> lengths_{};
    std::size_t head_ = 0;
    std::size_t count_ = 0;

    // What SM1 holds (or last held) and the message before it, for the repeat handshake.
    std::vector<uint8_t> current_;
    std::vector<uint8_t> previous_;
    std::size_t current_len_ = 0;
    std::size_t previous_len_ = 0;
    bool repeat_ack_ = false;

    std::vector<uint8_t> rx_;
    uint8_t last_rx_counter_ = 0;
    uint8_t tx_counter_ = 0;
    // Address of the request being handled (echoed in the reply); 0 for spontaneous messages.
    uint16_t reply_address_ = 0;
    MailboxStats stats_;
    MailboxFaults faults_;
};

}  // namespace ecat
