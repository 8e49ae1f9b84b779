#pragma once
// A small EtherCAT master: frames of several datagrams over an esc::Link, replies matched by datagram
// index with a timeout and retries, working-counter checks; slave counting, station addresses, register
// access, SII EEPROM, AL state requests and the mailbox (see mailbox.hpp for CoE on top of it).
//
// Not thread-safe: one Master per link, used from one thread.
#include <array>
#include <chrono>
#include <cstdint>
#include <span>
#include <vector>

#include "esc/link.hpp"
#include "esc/wire/al.hpp"
#include "esc/wire/registers.hpp"
#include "esc/wire/sii.hpp"
#include "master/error.hpp"
#include "master/frame.hpp"

namespace master {

// Where a register access goes: the n-th slave on the wire (auto-increment) or a configured station address.
struct Address {
    enum class Mode : uint8_t { Position, Station };
    Mode mode = Mode::Position;
    uint16_t value = 0;
    static Address position(uint16_t p) { return {Mode::Position, p}; }
    static Address station(uint16_t s) { return {Mode::Station, s}; }
};

// ESC registers the master uses, under its names (values: esc/wire/registers.hpp).
namespace reg {
constexpr uint16_t Type = esc::reg::kType;
constexpr uint16_t StationAddress = esc::reg::kStationAddress;
constexpr uint16_t StationAlias = esc::reg::kStationAlias;
constexpr uint16_t DlStatus = esc::reg::kDlStatus;
constexpr uint16_t AlControl = esc::reg::kAlControl;
constexpr uint16_t AlStatus = esc::reg::kAlStatus;
constexpr uint16_t AlStatusCode = esc::reg::kAlStatusCode;
constexpr uint16_t SiiConfig = esc::reg::kSiiConfig;
constexpr uint16_t SiiControl = esc::reg::kSiiControl;
constexpr uint16_t SiiAddress = esc::reg::kSiiAddress;
constexpr uint16_t SiiData = esc::reg::kSiiData;
constexpr uint16_t Fmmu0 = esc::reg::kFmmu;
constexpr uint16_t Sm0 = esc::reg::kSm;
constexpr uint16_t DcSystemTime = esc::reg::kDcSystemTime;
}  // namespace reg

// SII word addresses of the fixed header (ETG.2010; esc/wire/sii.hpp) and the 0x0502 control/status bits
// (esc/wire/registers.hpp), under the master's names.
namespace sii {
constexpr uint16_t VendorId = esc::sii::word::VendorId;
constexpr uint16_t ProductCode = esc::sii::word::ProductCode;
constexpr uint16_t Revision = esc::sii::word::Revision;
constexpr uint16_t SerialNumber = esc::sii::word::SerialNumber;
constexpr uint16_t BootMailboxOut = esc::sii::word::BootMailboxOut;
constexpr uint16_t StdMailboxOut = esc::sii::word::StdMailboxOut;
constexpr uint16_t StdMailboxIn = esc::sii::word::StdMailboxIn;
constexpr uint16_t MailboxProtocols = esc::sii::word::MailboxProtocols;
constexpr uint16_t EepromSize = esc::sii::word::EepromSize;
constexpr uint16_t FirstCategory = esc::sii::word::FirstCategory;
constexpr uint16_t CategoryEnd = esc::sii::category::End;
using namespace esc::reg::sii;
}  // namespace sii

using AlState = esc::AlState;
constexpr uint16_t kAlErrorAck =
    esc::reg::kAlErrorFlag;  // AL control bit 4 / AL status bit 4 (error indication)
constexpr uint16_t kAlIdentify = esc::reg::kAlIdFlag;  // AL control bit 5 / AL status bit 5

struct AlStatus {
    uint8_t state = 0;   // bits 3:0 of 0x0130
    bool error = false;  // bit 4: error indication
    bool id_loaded = false;
    uint16_t code = 0;  // 0x0134
};

std::string_view to_string(AlState s);
// "INIT", "PREOP", ... or "0x0?" for a state code that is not one of the five.
std::string_view al_state_name(uint8_t state);
// Name of an AL status code (ETG.1000.6 AL status codes), "unknown" if not in the table.
std::string_view al_status_code_name(uint16_t code);

struct MasterOptions {
    std::chrono::microseconds timeout{100'000};                 // per frame, per attempt
    unsigned retries = 2;                                       // extra attempts after a timeout
    MacAddress source_mac{0x01, 0x01, 0x01, 0x01, 0x01, 0x01};  // bit 1 of byte 0 clear: replies set it
    std::chrono::milliseconds sii_timeout{100};                 // busy polling of one SII command
    std::chrono::milliseconds al_timeout{5000};                 // reaching a requested AL state
    bool busy_poll = false;  // wait for replies by polling the link in a loop instead of sleeping in ppoll()
    // Take frames that come back with our own source MAC as replies (a slave that does not set the locally
    // administered bit, as a conformance tool must still talk to); an unprocessed frame then looks like a
    // reply with its working counters unchanged.
    bool accept_own_source = false;
};

struct MasterStats {
    uint64_t frames_sent = 0;
    uint64_t frames_received = 0;  // matched replies
    uint64_t frames_ignored = 0;   // received but not ours (stale index, not EtherCAT, our own frame)
    uint64_t timeouts = 0;         // attempts that got no reply
    std::chrono::nanoseconds last_round_trip{0};
    std::chrono::nanoseconds max_round_trip{0};
};

class Master {
  public:
    explicit Master(esc::Link& link, MasterOptions options = {});

    const MasterOptions& options() const { return options_; }
    void set_timeout(std::chrono::microseconds t) { options_.timeout = t; }
    const MasterStats& stats() const { return stats_; }

    // ---- Frames ----------------------------------------------------------------------------------
    // Sends all datagrams in one frame and waits for the reply with the same datagram indices; on a
    // timeout sends again (options().retries times). Fills each datagram's data (read commands), wkc
    // and irq from the reply. Working counters are not checked here. Allocates nothing.
    Error exchange(std::span<Datagram> datagrams) { return exchange(datagrams, options_.retries); }
    // Same with an explicit number of retries (0: one attempt; for requests that must not be repeated
    // blindly, such as the read of a mailbox whose reply may have been lost).
    Error exchange(std::span<Datagram> datagrams, unsigned retries);
    Error exchange(Datagram& datagram) { return exchange(std::span<Datagram>(&datagram, 1)); }
    // Several frames at once (a process-data image larger than one frame): all sent back to back, then
    // their replies collected in the same order, without retries. Every frame whose reply came is filled;
    // Error::Timeout if any reply is missing. Allocates nothing.
    Error exchange_frames(std::span<const std::span<Datagram>> frames);

    // ---- Registers -------------------------------------------------------------------------------
    // APRD/FPRD and APWR/FPWR; the working counter must be 1.
    Error read(Address a, uint16_t address, std::span<uint8_t> out);
    Error write(Address a, uint16_t address, std::span<const uint8_t> in);
    // The datagram read()/write() would send (APxx for a position, FPxx for a station address).
    static Datagram addressed(Address a, bool write, uint16_t address, std::span<uint8_t> data);
    template <typename T>
    Result<T> read_reg(Address a, uint16_t address) {
        uint8_t b[sizeof(T)] = {};
        if (Error e = read(a, address, b); e != Error::Ok) return e;
        T v{};
        for (std::size_t i = 0; i < sizeof(T); ++i)
            v = static_cast<T>(v | (static_cast<T>(b[i]) << (8 * i)));
        return v;
    }
    template <typename T>
    Error write_reg(Address a, uint16_t address, T value) {
        uint8_t b[sizeof(T)];
        for (std::size_t i = 0; i < sizeof(T); ++i)
            b[i] = static_cast<uint8_t>(static_cast<uint64_t>(value) >> (8 * i));
        return write(a, address, b);
    }
    // BRD/BWR: every slave answers; returns the working counter (= number of slaves that took it).
    Result<uint16_t> broadcast_read(uint16_t address, std::span<uint8_t> out);
    Result<uint16_t> broadcast_write(uint16_t address, std::span<const uint8_t> in);

    // ---- Bus -------------------------------------------------------------------------------------
    // BRD of 0x0000: the working counter is the number of slaves. Error::Timeout if nothing answered.
    Result<uint16_t> count_slaves();
    // APWR of 0x0010 to slaves 0..count-1: first, first+1, ... (each must answer with WKC 1).
    Error assign_station_addresses(uint16_t count, uint16_t first = 0x1001);

    // ---- SII EEPROM ------------------------------------------------------------------------------
    // Reads out.size() bytes starting at word address `word` (any length; done in 4- or 8-byte steps as
    // the slave's read size says). Takes the EEPROM from the PDI if it holds it, clears stale errors,
    // waits out busy and retries commands that fail with "missing acknowledge".
    Error sii_read(Address a, uint32_t word, std::span<uint8_t> out);
    Result<uint16_t> sii_read_word(Address a, uint32_t word);
    Result<uint32_t> sii_read_u32(Address a, uint32_t word);
    // Whether the SII declares a standard mailbox: false when words 0x18-0x1B (SM0/SM1 offset and size) are
    // all zero, as for a coupler or a digital IO terminal (ETG.2010 SII words); such a slave goes from INIT
    // to PREOP without mailbox SyncManagers and has its process-data layout in the SII alone.
    Result<bool> sii_has_mailbox(Address a);
    // The whole image: the fixed header and the category chain up to and including the 0xFFFF end
    // word; with whole_eeprom, every byte of the size given in word 0x3E instead.
    Result<std::vector<uint8_t>> sii_read_image(Address a, bool whole_eeprom = false);
    Error sii_write_word(Address a, uint32_t word, uint16_t value);

    // ---- AL state machine ------------------------------------------------------------------------
    Result<AlStatus> al_status(Address a);
    // Writes the requested state to AL control (with the error-acknowledge bit if an error is pending)
    // and polls AL status until the state is reached. If the slave refuses (error indication), the error
    // is acknowledged (AL control = actual state | 0x10) and Error::AlRefused is returned; `final`
    // then holds the refused status with its AL status code.
    Error request_state(Address a, AlState state, AlStatus* final = nullptr);
    // Device identification (ETG.1000.6 AL control): AL control bit 5 set with the current state; once AL
    // status bit 5 says the value is loaded, 0x0134 holds it (the station alias or ID selector). The request
    // bit is cleared again afterwards. Error::AlRefused if an error indication is pending.
    Result<uint16_t> identify(Address a);
    // Same on every slave at once (BWR 0x0120), then each of the given station addresses is polled.
    Error request_state_all(AlState state, std::span<const uint16_t> stations);

  private:
    Error sii_take(Address a);
    Error sii_wait(Address a, uint16_t& status, std::span<uint8_t> data_out = {});
    Error sii_command(Address a, uint16_t command, uint32_t word, std::span<uint8_t> data_out,
                      const uint16_t* write_value);
    Error wait_frame(uint8_t first_index, std::span<Datagram> datagrams,
                     std::chrono::steady_clock::time_point deadline);

    esc::Link& link_;
    MasterOptions options_;
    MasterStats stats_;
    uint8_t next_index_ = 0;
    uint16_t last_sii_status_ = 0;  // 0x0502 after the last completed SII command
    std::array<uint8_t, kMaxFrameSize> tx_{};
    std::array<uint8_t, kMaxFrameSize + 64> rx_{};
};

}  // namespace master
