#pragma once
// CoE SDO client (ETG.1000.6 CoE): upload and download, expedited, normal and segmented,
// with or without complete access, over a configured Mailbox. Emergencies that arrive while waiting are
// kept (the last one) and counted. Buffers are allocated at construction.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "master/mailbox.hpp"

namespace master {

struct EmergencyMessage {
    uint16_t code = 0;
    uint8_t error_register = 0;
    std::array<uint8_t, 5> data{};
};

// SDO information service (ETG.1000.6).
struct ObjectDescription {
    uint16_t index = 0;
    uint16_t data_type = 0;
    uint8_t max_subindex = 0;
    uint8_t object_code = 0;  // 7 VAR, 8 ARRAY, 9 RECORD
    std::string name;
};

struct EntryDescription {
    uint16_t index = 0;
    uint8_t subindex = 0;
    uint8_t value_info = 0;
    uint16_t data_type = 0;
    uint16_t bit_length = 0;
    uint16_t access = 0;  // bits 0-5 read/write in PreOp/SafeOp/Op, 6 RxPDO, 7 TxPDO, 8 backup, 9 setting
    std::vector<uint8_t> values;  // unit, default, minimum, maximum as value_info asked for them
    std::string name;
};

class SdoClient {
  public:
    explicit SdoClient(Mailbox& mailbox);

    // Reads index:sub into out; returns the number of bytes the slave sent. complete_access: the whole
    // object from sub (0 or 1), subindex 0 then occupying 16 bits (ETG.1000.6 complete access).
    Result<std::size_t> upload(uint16_t index, uint8_t sub, std::span<uint8_t> out,
                               bool complete_access = false);
    Error download(uint16_t index, uint8_t sub, std::span<const uint8_t> data, bool complete_access = false);

    // SDO information: the object indices of a list (1 = all objects, 2 RxPDO-mappable, 3 TxPDO-mappable,
    // 4 backup, 5 settings), an object's description, an entry's description. An SDO info error response
    // is Error::SdoAbort with last_abort().
    Result<std::vector<uint16_t>> od_list(uint16_t list_type = 1);
    Result<ObjectDescription> object_description(uint16_t index);
    Result<EntryDescription> entry_description(uint16_t index, uint8_t sub, uint8_t value_info = 0);

    // Abort code of the last Error::SdoAbort (from the slave, or sent by us when we gave up).
    uint32_t last_abort() const { return last_abort_; }
    // Whether the last successful upload said its size: false for an expedited response with the size
    // indicator clear (CiA 301 / ETG.1000.6: "data set size not indicated"), whose 4 bytes upload() returns;
    // a caller that knows the entry's size takes that many of them.
    bool last_size_indicated() const { return last_size_indicated_; }
    // Detail code of the last Error::MailboxError (ETG.1000.6 mailbox error reply).
    uint16_t last_mailbox_error() const { return last_mailbox_error_; }
    uint64_t emergencies() const { return emergencies_; }
    const EmergencyMessage& last_emergency() const { return last_emergency_; }
    // Messages found waiting in the slave's out-mailbox when a transfer started, other than emergencies: the
    // late answers of transfers given up on (a timeout on a lossy or loaded link). Each transfer starts with
    // the out-mailbox read empty, as SOEM's SDO functions do, so a late answer is never taken for the next
    // transfer's (which would put every later transfer one answer behind).
    uint64_t stale_answers() const { return stale_answers_; }

  private:
    Error prepare();
    void take_stale();
    bool take_emergency(const MailboxMessage& message);
    Error send(std::size_t length);
    Error response(MailboxMessage& message, uint8_t service = 3);
    // Sends one SDO info request and collects every fragment of the answer (after the 6-byte head).
    Error info(uint8_t opcode, std::span<const uint8_t> body, std::vector<uint8_t>& answer);
    void abort(uint16_t index, uint8_t sub, uint32_t code);

    Mailbox& mbx_;
    std::vector<uint8_t> req_;
    uint32_t last_abort_ = 0;
    bool last_size_indicated_ = true;
    uint16_t last_mailbox_error_ = 0;
    uint64_t emergencies_ = 0;
    uint64_t stale_answers_ = 0;
    EmergencyMessage last_emergency_;
};

// Text of an SDO abort code (ETG.1000.6), "unknown abort code" if not in the table.
std::string_view sdo_abort_text(uint32_t code);

// A mailbox and an SDO client for each of several slaves (a line in one process-data session). open_each
// gets each mailbox going (SM0/SM1 from the SII, the slave to PREOP, ...); the first failure stops it and
// failed() names the slave (index into `slaves`).
class SdoClients {
  public:
    Error open(Master& master, std::span<const Address> slaves,
               const std::function<Error(Mailbox&, Address)>& open_each);
    std::span<SdoClient* const> clients() const { return pointers_; }
    std::size_t failed() const { return failed_; }

  private:
    std::vector<std::unique_ptr<Mailbox>> mailboxes_;
    std::vector<std::unique_ptr<SdoClient>> clients_;
    std::vector<SdoClient*> pointers_;
    std::size_t failed_ = 0;
};

}  // namespace master
