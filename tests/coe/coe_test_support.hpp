#pragma once
// Shared pieces of the CoE tests: a recording mailbox sender, a small dictionary, request builders.
#include <cstdint>
#include <deque>
#include <initializer_list>
#include <string>
#include <vector>

#include "coe/diagnosis.hpp"
#include "coe/sdo_server.hpp"
#include "ecat/mailbox_handler.hpp"
#include "od/dictionary.hpp"
#include "util/le.hpp"

namespace coe_test {

using Bytes = std::vector<uint8_t>;

struct Sent {
    ecat::MailboxType type;
    Bytes payload;
};

class RecordingSender final : public ecat::MailboxSender {
  public:
    explicit RecordingSender(std::size_t max_payload = 122, std::size_t queue = 64)
        : max_payload_(max_payload), queue_(queue) {}
    bool send(ecat::MailboxType type, std::span<const uint8_t> payload) override {
        if (messages.size() >= queue_ || payload.size() > max_payload_) return false;
        messages.push_back({type, Bytes(payload.begin(), payload.end())});
        return true;
    }
    std::size_t max_payload() const override { return max_payload_; }
    Sent take() {
        Sent s = messages.front();
        messages.pop_front();
        return s;
    }
    void set_queue(std::size_t q) { queue_ = q; }
    std::deque<Sent> messages;

  private:
    std::size_t max_payload_;
    std::size_t queue_;
};

inline void put_le(Bytes& b, uint64_t v, std::size_t n) {
    const Bytes le = util::le_bytes(v, n);
    b.insert(b.end(), le.begin(), le.end());
}
inline uint32_t le32(const Bytes& b, std::size_t at) {
    return util::get32(b, at);
}
inline uint16_t le16(const Bytes& b, std::size_t at) {
    return util::get16(b, at);
}

// An SDO request (CoE payload): CoE header 0x2000, command, index, subindex, 4 data bytes, extra bytes.
inline Bytes sdo(uint8_t cmd, uint16_t index, uint8_t sub, uint32_t data = 0,
                 std::initializer_list<uint8_t> extra = {}) {
    Bytes b{0x00, 0x20, cmd};
    put_le(b, index, 2);
    b.push_back(sub);
    put_le(b, data, 4);
    for (uint8_t x : extra)
        b.push_back(x);
    return b;
}
// A segment request: CoE header, command, data (padded to 7 bytes by the caller if wanted).
inline Bytes segment(uint8_t cmd, const Bytes& data) {
    Bytes b{0x00, 0x20, cmd};
    b.reserve(3 + data.size());
    for (uint8_t x : data)
        b.push_back(x);  // (vector::insert here trips GCC 12's -Warray-bounds at -O2)
    return b;
}
// An SDO info request: CoE header 0x8000, opcode, reserved, fragments left 0, body.
inline Bytes info(uint8_t opcode, std::initializer_list<uint8_t> body) {
    Bytes b{0x00, 0x80, opcode, 0x00, 0x00, 0x00};
    for (uint8_t x : body)
        b.push_back(x);  // (insert of an empty list trips GCC 12's -Warray-bounds at -O2)
    return b;
}
// An expected abort (as SOES sends it: service 2, command 0x80).
inline Bytes abort_reply(uint16_t index, uint8_t sub, uint32_t code) {
    Bytes b{0x00, 0x20, 0x80};
    put_le(b, index, 2);
    b.push_back(sub);
    put_le(b, code, 4);
    return b;
}

inline od::Entry entry(uint8_t sub, const std::string& name, od::DataType t, uint16_t access,
                       od::Number def = {}, od::Number min = {}, od::Number max = {}) {
    od::Entry e;
    e.subindex = sub;
    e.name = name;
    e.type = t;
    e.access = access;
    e.default_value = def;
    e.minimum = min;
    e.maximum = max;
    return e;
}
inline od::Object var(uint16_t index, const std::string& name, od::Entry e) {
    od::Object o;
    o.index = index;
    o.code = od::ObjectCode::Var;
    o.name = name;
    o.type = e.type;
    e.subindex = 0;
    if (e.name.empty()) e.name = name;
    o.entries.push_back(e);
    return o;
}
inline od::Object composite(uint16_t index, od::ObjectCode code, const std::string& name, od::DataType type,
                            std::vector<od::Entry> entries) {
    od::Object o;
    o.index = index;
    o.code = code;
    o.name = name;
    o.type = type;
    o.entries = std::move(entries);
    return o;
}
inline od::Entry string_entry(const std::string& name, od::DataType t, uint16_t access, std::size_t capacity,
                              const std::string& def) {
    od::Entry e = entry(0, name, t, access);
    e.bit_length = static_cast<uint16_t>(capacity * 8);
    e.default_string = def;
    return e;
}

// A small device: identity, error register, diagnosis history, two PDOs with assignment, a few drive
// objects, a write-only, a long string, and a record of bits.
inline od::Dictionary make_test_dictionary() {
    using namespace od::access;
    using DT = od::DataType;
    od::Dictionary d;
    d.add(var(0x1000, "Device Type", entry(0, "", DT::Unsigned32, RO, uint64_t{0x00020192})));
    d.add(var(0x1001, "Error Register", entry(0, "", DT::Unsigned8, RO | TxPdo, uint64_t{0})));
    d.add(var(0x1008, "Device Name", string_entry("Device Name", DT::VisibleString, RO, 32, "MAXPOS")));
    d.add(composite(0x1018, od::ObjectCode::Record, "Identity", DT::Identity,
                    {entry(0, "Number of entries", DT::Unsigned8, RO, uint64_t{4}),
                     entry(1, "Vendor ID", DT::Unsigned32, RO, uint64_t{0xFB}),
                     entry(2, "Product Code", DT::Unsigned32, RO, uint64_t{0x30010000}),
                     entry(3, "Revision", DT::Unsigned32, RO, uint64_t{0x01200000}),
                     entry(4, "Serial Number", DT::Unsigned32, RO, uint64_t{0x12345678})}));
    d.add(coe::DiagnosisHistory::make_object(4, 40));
    auto mapping = [](uint16_t index, const std::string& name, std::vector<uint32_t> defaults) {
        std::vector<od::Entry> es{entry(0, "Number of entries", DT::Unsigned8, RW_PreOp | Backup,
                                        uint64_t{defaults.size()}, uint64_t{0}, uint64_t{4})};
        for (uint8_t i = 1; i <= 4; ++i)
            es.push_back(entry(i, "Mapped object " + std::to_string(i), DT::Unsigned32, RW_PreOp | Backup,
                               uint64_t{i <= defaults.size() ? defaults[i - 1] : 0u}));
        return composite(index, od::ObjectCode::Record, name, DT::PdoMapping, es);
    };
    d.add(mapping(0x1600, "RxPDO 1", {0x60400010, 0x607A0020}));
    d.add(mapping(0x1601, "RxPDO 2", {0x60400010}));
    d.add(mapping(0x1A00, "TxPDO 1", {0x60410010, 0x60640020}));
    d.add(mapping(0x1A01, "TxPDO 2", {0x60410010}));
    auto assign = [](uint16_t index, const std::string& name, uint16_t first, uint16_t second) {
        return composite(index, od::ObjectCode::Array, name, DT::Unsigned16,
                         {entry(0, "Number of assigned PDOs", DT::Unsigned8, RW_PreOp, uint64_t{1},
                                uint64_t{0}, uint64_t{2}),
                          entry(1, "PDO 1", DT::Unsigned16, RW_PreOp, uint64_t{first}),
                          entry(2, "PDO 2", DT::Unsigned16, RW_PreOp, uint64_t{second})});
    };
    d.add(assign(0x1C12, "RxPDO assign", 0x1600, 0));
    d.add(assign(0x1C13, "TxPDO assign", 0x1A00, 0));
    d.add(var(0x2000, "Big Data", string_entry("Big Data", DT::OctetString, RW, 300, "")));
    d.add(var(0x2001, "Password", entry(0, "", DT::Unsigned32, WO)));
    od::Entry limited = entry(0, "", DT::Integer16, RW | Settings, int64_t{5}, int64_t{-100}, int64_t{100});
    limited.unit = "ms";
    d.add(var(0x2002, "Limited", limited));
    d.add(var(0x2003, "Op only", entry(0, "", DT::Unsigned8, RO | WriteOp)));
    d.add(composite(
        0x3000, od::ObjectCode::Record, "Bits", DT::Unsigned8,
        {entry(0, "Number of entries", DT::Unsigned8, RO, uint64_t{3}),
         entry(1, "Bit A", DT::Boolean, RW, uint64_t{1}), entry(2, "Bit B", DT::Boolean, RW, uint64_t{0}),
         entry(3, "Word", DT::Unsigned16, RW, uint64_t{0xBEEF})}));
    d.add(var(0x6040, "Controlword", entry(0, "", DT::Unsigned16, RW | RxPdo)));
    d.add(var(0x6041, "Statusword", entry(0, "", DT::Unsigned16, RO | TxPdo, uint64_t{0x0250})));
    d.add(var(0x6060, "Modes of operation", entry(0, "", DT::Integer8, RW | RxPdo, int64_t{8})));
    d.add(var(0x6064, "Position actual value", entry(0, "", DT::Integer32, RO | TxPdo, int64_t{1226})));
    d.add(var(0x607A, "Target position", entry(0, "", DT::Integer32, RW | RxPdo)));
    return d;
}

}  // namespace coe_test
