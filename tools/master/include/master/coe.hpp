#pragma once
// CoE SDO client (ethercat-protocol.md §9.2): upload and download, expedited, normal and segmented,
// with or without complete access, over a configured Mailbox. Emergencies that arrive while waiting are
// kept (the last one) and counted. Buffers are allocated at construction.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "master/mailbox.hpp"

namespace master {

struct EmergencyMessage {
    uint16_t code = 0;
    uint8_t error_register = 0;
    std::array<uint8_t, 5> data{};
};

class SdoClient {
  public:
    explicit SdoClient(Mailbox& mailbox);

    // Reads index:sub into out; returns the number of bytes the slave sent. complete_access: the whole
    // object from sub (0 or 1), subindex 0 then occupying 16 bits (§9.2).
    Result<std::size_t> upload(uint16_t index, uint8_t sub, std::span<uint8_t> out,
                               bool complete_access = false);
    Error download(uint16_t index, uint8_t sub, std::span<const uint8_t> data, bool complete_access = false);

    // Abort code of the last Error::SdoAbort (from the slave, or sent by us when we gave up).
    uint32_t last_abort() const { return last_abort_; }
    // Detail code of the last Error::MailboxError (ethercat-protocol.md §8.3).
    uint16_t last_mailbox_error() const { return last_mailbox_error_; }
    uint64_t emergencies() const { return emergencies_; }
    const EmergencyMessage& last_emergency() const { return last_emergency_; }

  private:
    Error prepare();
    Error send(std::size_t length);
    Error response(MailboxMessage& message);
    void abort(uint16_t index, uint8_t sub, uint32_t code);

    Mailbox& mbx_;
    std::vector<uint8_t> req_;
    uint32_t last_abort_ = 0;
    uint16_t last_mailbox_error_ = 0;
    uint64_t emergencies_ = 0;
    EmergencyMessage last_emergency_;
};

// Text of an SDO abort code (§9.3), "unknown abort code" if not in the table.
std::string_view sdo_abort_text(uint32_t code);

}  // namespace master
