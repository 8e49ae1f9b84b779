#pragma once
// The contract between the mailbox (ecat/) and the protocols behind it (coe/, foe/).
// A handler sees only mailbox payloads (what follows the 6-byte mailbox header) and answers through a
// MailboxSender; it never touches the ESC.
#include <cstddef>
#include <cstdint>
#include <span>

#include "ecat/wire/mailbox.hpp"
#include "od/types.hpp"

namespace ecat {

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
