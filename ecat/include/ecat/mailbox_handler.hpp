#pragma once
// The contract between the mailbox (ecat/) and the protocols behind it (coe/, foe/).
// A handler sees only mailbox payloads (what follows the 6-byte mailbox header) and answers through a
// MailboxSender; it never touches the ESC.
#include <cstddef>
#include <cstdint>
#include <span>

#include "od/types.hpp"

namespace ecat {

// Mailbox types (header byte 5, bits 3:0).
enum class MailboxType : uint8_t {
    Error = 0x0,
    AoE = 0x1,
    EoE = 0x2,
    CoE = 0x3,
    FoE = 0x4,
    SoE = 0x5,
    VoE = 0xF
};

// Mailbox error codes (mailbox type 0 reply, ETG.1000.4).
enum class MailboxError : uint16_t {
    Syntax = 0x0001,
    UnsupportedProtocol = 0x0002,
    InvalidChannel = 0x0003,
    ServiceNotSupported = 0x0004,
    InvalidHeader = 0x0005,
    SizeTooShort = 0x0006,
    NoMoreMemory = 0x0007,
    InvalidSize = 0x0008,
    ServiceInWork = 0x0009,
};

constexpr std::size_t kMailboxHeaderSize = 6;

// The outgoing side of the mailbox, as a protocol handler sees it.
class MailboxSender {
  public:
    virtual ~MailboxSender() = default;
    // Queues one message (payload = bytes after the mailbox header). False if the queue is full or the
    // payload does not fit the SM1 mailbox.
    virtual bool send(MailboxType type, std::span<const uint8_t> payload) = 0;
    // Largest payload one message can carry (SM1 length - 6).
    virtual std::size_t max_payload() const = 0;
};

class MailboxHandler {
  public:
    virtual ~MailboxHandler() = default;
    virtual MailboxType type() const = 0;
    // Whether the protocol is served in this AL state (FoE in Bootstrap, CoE not in Bootstrap, ...).
    virtual bool available(od::AlState state) const = 0;
    // One request: payload = bytes after the mailbox header (already length-checked against the header).
    virtual void handle(std::span<const uint8_t> payload, MailboxSender& out) = 0;
    // Periodic work: transfer timeouts, deferred replies (e.g. FoE busy while storing).
    virtual void poll(uint64_t /*now_ns*/, MailboxSender& /*out*/) {}
    // The AL state changed; a handler drops transfers that cannot survive it.
    virtual void on_state_change(od::AlState /*from*/, od::AlState /*to*/) {}
};

}  // namespace ecat
