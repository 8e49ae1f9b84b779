#pragma once
// What can go wrong on the master side, and a small value-or-error carrier (C++20 has no std::expected).
#include <cstdint>
#include <string_view>
#include <utility>

namespace master {

enum class Error : uint8_t {
    Ok,
    InvalidArgument,       // a caller error: datagram too long, empty frame, bad address, ...
    SendFailed,            // the link refused the frame (interface down, no privileges, ...)
    Timeout,               // no matching reply within the timeout, after all retries ("no slave answered")
    WorkingCounter,        // a reply came back but its working counter is not the expected one
    SiiBusy,               // the SII interface stayed busy past the timeout
    SiiNack,               // the SII interface kept reporting "missing acknowledge / invalid command"
    SiiWriteDisabled,      // the SII write was refused with "write without write enable"
    SiiFormat,             // the category chain runs past the EEPROM size or never ends
    AlTimeout,             // the slave did not reach the requested AL state in time
    AlRefused,             // the slave set the Error Indication bit (AL status code tells why)
    MailboxNotConfigured,  // the mailbox SyncManagers are not set up (or not as a mailbox)
    NoMailbox,             // the slave has none: its SII declares no standard mailbox (words 0x18-0x1B zero)
    MailboxTimeout,        // no mailbox answer within the timeout
    MailboxError,          // the slave answered with a mailbox error message (type 0)
    MailboxProtocol,       // the answer does not fit the request (wrong type, service, length)
    SdoAbort,              // the SDO server aborted the transfer (abort code tells why)
    BufferTooSmall,        // the caller's buffer cannot hold the answer
    FoeError,              // the FoE server answered with an ERR packet (code and text kept by the client)
    TooFewFmmus,           // the slave has fewer FMMUs (ESC 0x0004) than process-data SMs with data
};

std::string_view to_string(Error e);

template <typename T>
class Result {
  public:
    Result(T value) : value_(std::move(value)) {}  // NOLINT: implicit on purpose, as std::expected
    Result(Error error) : error_(error) {}         // NOLINT
    bool ok() const { return error_ == Error::Ok; }
    explicit operator bool() const { return ok(); }
    Error error() const { return error_; }
    const T& value() const& { return value_; }
    T& value() & { return value_; }
    T&& value() && { return std::move(value_); }
    const T& operator*() const& { return value_; }
    T& operator*() & { return value_; }
    const T* operator->() const { return &value_; }

  private:
    T value_{};
    Error error_ = Error::Ok;
};

}  // namespace master
