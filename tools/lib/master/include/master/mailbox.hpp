#pragma once
// The master's side of the EtherCAT mailbox (ESC datasheet section I §8.2, §8.6; ETG.1000.4 mailbox header):
// SM0 (master -> slave) and SM1 (slave -> master) set up from the SII, the 6-byte header with the 1..7
// counter, the full-length SM writes and reads the ESC requires, and the repeat request when a read reply is
// lost. Buffers are allocated once, at configure(); send/receive allocate nothing.
#include <chrono>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "ecat/wire/mailbox.hpp"
#include "master/master.hpp"

namespace master {

using MailboxType = ecat::MailboxType;  // the mailbox vocabulary (ecat/wire/mailbox.hpp)

struct MailboxConfig {
    uint16_t out_start = 0;  // SM0
    uint16_t out_size = 0;
    uint16_t in_start = 0;  // SM1
    uint16_t in_size = 0;
    uint16_t protocols = 0;  // SII word 0x1C (0 if unknown)
    bool valid() const { return out_size >= 8 && in_size >= 8; }
};

struct MailboxMessage {
    MailboxType type = MailboxType::Error;
    uint8_t counter = 0;
    uint16_t address = 0;
    uint8_t channel = 0;
    uint8_t priority = 0;
    std::span<const uint8_t> payload;  // valid until the next receive()
};

class Mailbox {
  public:
    static constexpr uint8_t kSm0ControlDefault = 0x26;  // mailbox, write, PDI IRQ on
    static constexpr uint8_t kSm1ControlDefault = 0x22;  // mailbox, read, PDI IRQ on

    Mailbox(Master& master, Address slave,
            std::chrono::milliseconds timeout = std::chrono::milliseconds(1000));

    // Reads the standard mailbox from the SII (words 0x18-0x1C) and configures SM0/SM1 (the slave should
    // be in INIT: SMs can be set only while disabled; the state machine checks them on INIT -> PREOP).
    // bootstrap: the bootstrap mailbox (words 0x14-0x17) for the BOOT state instead.
    Error configure_from_sii(bool bootstrap = false);
    // Writes SM0/SM1 (start, length, control, activate = 1) in one 16-byte write.
    Error configure(const MailboxConfig& config);
    // Takes SM0/SM1 as the slave has them now (a slave already in PREOP or above), without writing.
    Error adopt_current();
    const MailboxConfig& config() const { return config_; }
    Address slave() const { return slave_; }

    // Largest payload of one message in each direction.
    std::size_t max_out_payload() const { return config_.out_size > 6 ? config_.out_size - 6u : 0u; }
    std::size_t max_in_payload() const { return config_.in_size > 6 ? config_.in_size - 6u : 0u; }

    // Writes one message into SM0 (waits while the slave has not read the previous one).
    Error send(MailboxType type, std::span<const uint8_t> payload);
    // Waits for one message from SM1. A mailbox error reply (type 0) is returned as a message too.
    Error receive(MailboxMessage& message);
    Error receive(MailboxMessage& message, std::chrono::milliseconds timeout);
    // Reads SM1 empty before an exchange: what waits there is a late answer of an exchange given up on, or
    // a message the slave sent by itself (an emergency). `keep` is offered each message and returns true for
    // one its owner takes; the others are dropped and counted (the return value). Bounded: a slave that keeps
    // SM1 full is the next exchange's problem.
    std::size_t drain(const std::function<bool(const MailboxMessage&)>& keep = {});

    std::chrono::milliseconds timeout() const { return timeout_; }
    void set_timeout(std::chrono::milliseconds t) { timeout_ = t; }
    uint64_t repeats() const { return repeats_; }  // repeat requests issued after lost read replies
    // Counter (header byte 5 bits 4-6) of the last message receive() returned.
    uint8_t last_rx_counter() const { return last_rx_counter_; }

  private:
    Error read_sm1(bool& got);
    Error repeat_request();
    uint8_t next_counter();

    Master& m_;
    Address slave_;
    std::chrono::milliseconds timeout_;
    MailboxConfig config_;
    std::vector<uint8_t> tx_;
    std::vector<uint8_t> rx_;
    uint8_t counter_ = 0;
    bool send_zero_ = false;       // next request goes out with counter 0 (after adopt_current)
    uint8_t last_rx_counter_ = 0;  // counter of the last message received (repeat duplicates)
    uint64_t repeats_ = 0;
};

}  // namespace master
