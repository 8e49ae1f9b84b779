#pragma once
// Diagnosis history, object 0x10F3 (ETG.1020 Diagnosis History; MAXPOS firmware specification §7.2.5). The
// drive glue adds messages; they live in the dictionary entries 0x10F3:06.. (a ring), so the master reads
// them by SDO like any object.
//
//   :01 maximum messages   :02 newest message (subindex, 0 = none)   :03 newest acknowledged (write: 0 clears
//   all, 6..5+max acknowledges up to that message, 1..5 -> 0x06090032, above -> 0x06090031)
//   :04 new messages available (1 until the master reads the newest message)
//   :05 flags: b0 send as emergency, b1/b2/b3 do not store info/warning/error, b4 0 overwrite / 1 acknowledge
//       mode, b5 overflow (read-only)
//
// Message layout (ETG.1020): UINT32 diag code, UINT16 flags (b3:0 type 0 info/1 warning/2 error, b4 local
// time stamp, b15:8 number of parameters), UINT16 text id, UINT64 time stamp (DC system time, ns), then per
// parameter UINT16 parameter flags (b15:12 kind: 0 = value of the CoE data type in b11:0, 1 = byte array,
// 2 = ASCII string, 3 = Unicode string, b11:0 = length) followed by its data.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "coe/emergency.hpp"
#include "od/dictionary.hpp"

namespace coe {

enum class DiagType : uint8_t { Info = 0, Warning = 1, Error = 2 };

struct DiagParam {
    uint16_t flags = 0;
    std::span<const uint8_t> data;  // not owned: valid for the add() call

    static DiagParam value(od::DataType type, std::span<const uint8_t> bytes) {
        return {static_cast<uint16_t>(static_cast<uint16_t>(type) & 0x0FFF), bytes};
    }
    static DiagParam byte_array(std::span<const uint8_t> bytes) {
        return {static_cast<uint16_t>(0x1000 | (bytes.size() & 0x0FFF)), bytes};
    }
    static DiagParam ascii(std::string_view text) {
        return {static_cast<uint16_t>(0x2000 | (text.size() & 0x0FFF)),
                std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(text.data()), text.size())};
    }
};

struct DiagMessage {
    uint32_t code = 0;  // ETG.1020 diag code; emergency-derived codes: DiagnosisHistory::from_emergency()
    DiagType type = DiagType::Info;
    uint16_t text_id = 0;
    uint64_t timestamp_ns = 0;  // DC system time
    bool local_time = false;    // the time stamp is the local clock, not DC system time
    std::span<const DiagParam> params;
};

class DiagnosisHistory {
  public:
    static constexpr uint16_t kIndex = 0x10F3;
    static constexpr uint8_t kFirstMessage = 6;
    static constexpr uint16_t kFlagEmergency = 0x0001;
    static constexpr uint16_t kFlagNoInfo = 0x0002;
    static constexpr uint16_t kFlagNoWarning = 0x0004;
    static constexpr uint16_t kFlagNoError = 0x0008;
    static constexpr uint16_t kFlagAcknowledgeMode = 0x0010;
    static constexpr uint16_t kFlagOverflow = 0x0020;
    static constexpr std::size_t kMaxMessages = 250;

    enum class Result : uint8_t { Stored, Suppressed, Discarded };

    // Declares 0x10F3 for dictionaries that lack it (tests; od's drive dictionary declares its own).
    static od::Object make_object(uint8_t max_messages = 10, uint16_t message_bytes = 64);
    // Diag code of a message derived from a CiA 301 / CiA 402 emergency error code (ETG.1020: 0xE800 in the
    // low word, the error code in the high word).
    static constexpr uint32_t from_emergency(uint16_t error_code) {
        return (static_cast<uint32_t>(error_code) << 16) | 0xE800u;
    }
    // Encodes one message. A byte array or string that does not fit `out` is cut to the room left; a value
    // that does not fit is left out with everything after it (the count says how many are in).
    static std::size_t encode(const DiagMessage& m, std::span<uint8_t> out);

    // Installs the write/read semantics on 0x10F3. emergency may be null (flag b0 then cannot be set).
    // Throws std::logic_error if the dictionary has no usable 0x10F3. Must not outlive dict, must not move.
    // Why the dictionary's 0x10F3 cannot hold a history (ETG.1020: :01..:05 and at least one message
    // subindex from :06 on, contiguous, of at least 16 bytes, at most 250 of them); empty if it can, or if
    // there is no 0x10F3. A device described by a vendor's ESI that declares 0x10F3 without room for
    // messages serves the object as stored values instead (docs/decisions/device.md).
    static std::string unusable(const od::Dictionary& dict);
    DiagnosisHistory(od::Dictionary& dict, Emergency* emergency = nullptr);
    ~DiagnosisHistory();  // takes its hooks off the dictionary, which may outlive it
    DiagnosisHistory(const DiagnosisHistory&) = delete;
    DiagnosisHistory& operator=(const DiagnosisHistory&) = delete;

    // Stores a message (unless its type is suppressed or acknowledge mode is full). With flag b0 set it also
    // goes out as an emergency, unless may_send_emergency is false (the caller sent one already).
    Result add(const DiagMessage& m, bool may_send_emergency = true);
    // Removes every message (what a master write of 0 to :03 does).
    void clear();

    uint8_t max_messages() const { return static_cast<uint8_t>(slots_); }
    std::size_t stored() const { return count_; }
    std::size_t unacknowledged() const;
    uint8_t newest() const;
    uint16_t flags() const;

  private:
    od::Status validate(const od::Entry& e, std::span<const uint8_t> value) const;
    void on_written(const od::Entry& e);
    void on_read(const od::Entry& e);
    void store(uint8_t sub, std::span<const uint8_t> bytes);
    void set_u8(uint8_t sub, uint8_t v);
    void set_flags(uint16_t v);

    od::Dictionary& dict_;
    Emergency* emergency_;
    std::size_t slots_ = 0;
    std::size_t capacity_ = 0;                  // bytes per message entry
    std::vector<uint8_t> buf_;                  // encoding buffer, sized once
    std::array<uint32_t, kMaxMessages> seq_{};  // sequence number per slot (0 = empty)
    std::size_t next_ = 0;                      // slot written next
    std::size_t count_ = 0;
    uint32_t next_seq_ = 1;
    uint32_t acked_seq_ = 0;  // messages with seq <= this are acknowledged
    bool overflow_ = false;
    bool updating_ = false;  // our own dictionary writes must not re-enter the listener
};

}  // namespace coe
