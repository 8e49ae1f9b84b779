#include "master/master.hpp"

#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <thread>

#include "util/le.hpp"

namespace master {

using Clock = std::chrono::steady_clock;

std::string_view to_string(Error e) {
    switch (e) {
        case Error::Ok:
            return "ok";
        case Error::InvalidArgument:
            return "invalid argument";
        case Error::SendFailed:
            return "the link could not send the frame";
        case Error::Timeout:
            return "no slave answered (timeout)";
        case Error::WorkingCounter:
            return "unexpected working counter";
        case Error::SiiBusy:
            return "SII EEPROM interface stayed busy";
        case Error::SiiNack:
            return "SII EEPROM command not acknowledged";
        case Error::SiiWriteDisabled:
            return "SII EEPROM write refused (write enable)";
        case Error::SiiFormat:
            return "SII EEPROM category chain is broken";
        case Error::AlTimeout:
            return "AL state not reached in time";
        case Error::AlRefused:
            return "AL state change refused by the slave";
        case Error::MailboxNotConfigured:
            return "mailbox not configured";
        case Error::NoMailbox:
            return "the slave has no mailbox (its SII declares none)";
        case Error::MailboxTimeout:
            return "no mailbox answer (timeout)";
        case Error::MailboxError:
            return "mailbox error reply";
        case Error::MailboxProtocol:
            return "unexpected mailbox answer";
        case Error::SdoAbort:
            return "SDO transfer aborted";
        case Error::BufferTooSmall:
            return "buffer too small";
        case Error::FoeError:
            return "FoE error reply";
        case Error::TooFewFmmus:
            return "the slave has fewer FMMUs (ESC 0x0004) than process-data SyncManagers with data";
    }
    return "unknown error";
}

std::string_view to_string(AlState s) {
    return al_state_name(static_cast<uint8_t>(s));
}

std::string_view al_state_name(uint8_t state) {
    return esc::al_state_name(state);
}

std::string_view al_status_code_name(uint16_t code) {
    const std::string_view text = esc::al::status_text(code);
    if (!text.empty()) return text;
    return code >= 0x8000 ? "Vendor specific" : "unknown";
}

Master::Master(esc::Link& link, MasterOptions options) : link_(link), options_(options) {}

// ---- Frames --------------------------------------------------------------------------------------

Error Master::exchange(std::span<Datagram> datagrams, unsigned retries) {
    if (datagrams.empty() || datagrams.size() > 255) return Error::InvalidArgument;
    for (unsigned attempt = 0; attempt <= retries; ++attempt) {
        // A fresh index range per attempt: a late reply to an earlier attempt is then told apart
        // from the reply to this one (and dropped as stale).
        const uint8_t first = next_index_;
        next_index_ = static_cast<uint8_t>(next_index_ + datagrams.size());
        const std::size_t n = encode_frame(datagrams, first, options_.source_mac, tx_);
        if (n == 0) return Error::InvalidArgument;
        const auto sent_at = Clock::now();
        if (!link_.send(std::span<const uint8_t>(tx_.data(), n))) return Error::SendFailed;
        ++stats_.frames_sent;
        const Error e = wait_frame(first, datagrams, sent_at + options_.timeout);
        if (e == Error::Ok) {
            const auto rtt = std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - sent_at);
            stats_.last_round_trip = rtt;
            stats_.max_round_trip = std::max(stats_.max_round_trip, rtt);
            return Error::Ok;
        }
        if (e != Error::Timeout) return e;
        ++stats_.timeouts;
    }
    return Error::Timeout;
}

Error Master::exchange_frames(std::span<const std::span<Datagram>> frames) {
    constexpr std::size_t kMaxFrames = 64;
    if (frames.empty() || frames.size() > kMaxFrames) return Error::InvalidArgument;
    std::array<uint8_t, kMaxFrames> first{};
    const auto sent_at = Clock::now();
    for (std::size_t k = 0; k < frames.size(); ++k) {
        const std::span<Datagram> d = frames[k];
        if (d.empty() || d.size() > 255) return Error::InvalidArgument;
        first[k] = next_index_;
        next_index_ = static_cast<uint8_t>(next_index_ + d.size());
        const std::size_t n = encode_frame(d, first[k], options_.source_mac, tx_);
        if (n == 0) return Error::InvalidArgument;
        if (!link_.send(std::span<const uint8_t>(tx_.data(), n))) return Error::SendFailed;
        ++stats_.frames_sent;
    }
    Error result = Error::Ok;
    for (std::size_t k = 0; k < frames.size(); ++k) {
        const Error e = wait_frame(first[k], frames[k], sent_at + options_.timeout);
        if (e == Error::Timeout) {
            ++stats_.timeouts;
            result = Error::Timeout;
            continue;
        }
        if (e != Error::Ok) return e;
    }
    if (result == Error::Ok) {
        const auto rtt = std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - sent_at);
        stats_.last_round_trip = rtt;
        stats_.max_round_trip = std::max(stats_.max_round_trip, rtt);
    }
    return result;
}

Error Master::wait_frame(uint8_t first_index, std::span<Datagram> datagrams, Clock::time_point deadline) {
    for (;;) {
        const std::size_t n = link_.receive(rx_);
        if (n > 0) {
            const std::span<const uint8_t> frame(rx_.data(), n);
            FrameReader reader(frame);
            // Our own frame seen again unprocessed (a loop with no slave in it) is not a reply.
            bool match =
                reader.valid() && (options_.accept_own_source ||
                                   !std::equal(options_.source_mac.begin(), options_.source_mac.end(),
                                               reader.source_mac().begin()));
            // Validate the whole chain before copying anything back.
            std::size_t i = 0;
            while (match) {
                auto v = reader.next();
                if (!v) break;
                if (i >= datagrams.size() || v->index != static_cast<uint8_t>(first_index + i) ||
                    v->command != datagrams[i].command || v->data.size() != datagrams[i].data.size()) {
                    match = false;
                    break;
                }
                ++i;
            }
            if (match && reader.valid() && i == datagrams.size()) {
                FrameReader again(frame);
                for (Datagram& d : datagrams) {
                    auto v = again.next();
                    if (!d.data.empty()) std::memcpy(d.data.data(), v->data.data(), d.data.size());
                    d.wkc = v->wkc;
                    d.irq = v->irq;
                    d.index = v->index;
                }
                ++stats_.frames_received;
                return Error::Ok;
            }
            ++stats_.frames_ignored;
            continue;
        }
        const auto now = Clock::now();
        if (now >= deadline) return Error::Timeout;
        const int fd = link_.fd();
        if (options_.busy_poll) {
            // No PAUSE here: in a virtual machine a tight PAUSE loop makes the host give the vCPU away
            // (pause-loop exiting), the opposite of what busy polling is for.
        } else if (fd >= 0) {
            const auto left = std::chrono::duration_cast<std::chrono::nanoseconds>(deadline - now);
            timespec ts{static_cast<time_t>(left.count() / 1'000'000'000),
                        static_cast<long>(left.count() % 1'000'000'000)};
            pollfd pfd{fd, POLLIN, 0};
            const int r = ::ppoll(&pfd, 1, &ts, nullptr);
            if (r < 0 && errno != EINTR) return Error::SendFailed;
        } else {
            std::this_thread::yield();
        }
    }
}

// ---- Registers -----------------------------------------------------------------------------------

Datagram Master::addressed(Address a, bool write, uint16_t address, std::span<uint8_t> data) {
    Datagram d;
    if (a.mode == Address::Mode::Position) {
        d.command = write ? Command::APWR : Command::APRD;
        d.adp = static_cast<uint16_t>(0u - a.value);  // slave n is addressed with -n
    } else {
        d.command = write ? Command::FPWR : Command::FPRD;
        d.adp = a.value;
    }
    d.ado = address;
    d.data = data;
    return d;
}

Error Master::read(Address a, uint16_t address, std::span<uint8_t> out) {
    if (out.empty() || out.size() > kMaxDatagramData) return Error::InvalidArgument;
    std::fill(out.begin(), out.end(), 0);
    Datagram d = addressed(a, false, address, out);
    if (Error e = exchange(d); e != Error::Ok) return e;
    return d.wkc == 1 ? Error::Ok : Error::WorkingCounter;
}

Error Master::write(Address a, uint16_t address, std::span<const uint8_t> in) {
    if (in.empty() || in.size() > kMaxDatagramData) return Error::InvalidArgument;
    std::array<uint8_t, kMaxDatagramData> buf;
    std::copy(in.begin(), in.end(), buf.begin());
    Datagram d = addressed(a, true, address, std::span<uint8_t>(buf.data(), in.size()));
    if (Error e = exchange(d); e != Error::Ok) return e;
    return d.wkc == 1 ? Error::Ok : Error::WorkingCounter;
}

Result<uint16_t> Master::broadcast_read(uint16_t address, std::span<uint8_t> out) {
    if (out.empty() || out.size() > kMaxDatagramData) return Error::InvalidArgument;
    std::fill(out.begin(), out.end(), 0);  // BRD ORs every slave's value into what the frame carries
    Datagram d{Command::BRD, 0, address, out};
    if (Error e = exchange(d); e != Error::Ok) return e;
    return d.wkc;
}

Result<uint16_t> Master::broadcast_write(uint16_t address, std::span<const uint8_t> in) {
    if (in.empty() || in.size() > kMaxDatagramData) return Error::InvalidArgument;
    std::array<uint8_t, kMaxDatagramData> buf;
    std::copy(in.begin(), in.end(), buf.begin());
    Datagram d{Command::BWR, 0, address, std::span<uint8_t>(buf.data(), in.size())};
    if (Error e = exchange(d); e != Error::Ok) return e;
    return d.wkc;
}

// ---- Bus -----------------------------------------------------------------------------------------

Result<uint16_t> Master::count_slaves() {
    uint8_t type[2];
    return broadcast_read(reg::Type, type);
}

Error Master::assign_station_addresses(uint16_t count, uint16_t first) {
    for (uint16_t i = 0; i < count; ++i) {
        if (Error e = write_reg<uint16_t>(Address::position(i), reg::StationAddress,
                                          static_cast<uint16_t>(first + i));
            e != Error::Ok)
            return e;
    }
    return Error::Ok;
}

// ---- AL state machine ----------------------------------------------------------------------------

Result<AlStatus> Master::al_status(Address a) {
    uint8_t b[6];  // 0x0130 status, 0x0132 reserved, 0x0134 status code
    if (Error e = read(a, reg::AlStatus, b); e != Error::Ok) return e;
    AlStatus s;
    s.state = b[0] & 0x0F;
    s.error = (b[0] & kAlErrorAck) != 0;
    s.id_loaded = (b[0] & kAlIdentify) != 0;
    s.code = util::get16(b + 4);
    return s;
}

namespace {

// AL control behaves like a mailbox on firmware-driven slaves (ESC datasheet section II, AL control 0x0120):
// a write before the firmware read the previous one may be refused (WKC 0). Keep trying until the deadline.
Error write_al_control(Master& m, Address a, uint16_t value, Clock::time_point deadline) {
    for (;;) {
        const Error e = m.write_reg<uint16_t>(a, reg::AlControl, value);
        if (e != Error::WorkingCounter || Clock::now() >= deadline) return e;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
}

}  // namespace

Error Master::request_state(Address a, AlState state, AlStatus* final) {
    const auto deadline = Clock::now() + options_.al_timeout;
    auto st = al_status(a);
    if (!st) return st.error();
    if (st->error) {
        // A pending error indication: acknowledge it first, so that the error bit seen afterwards
        // belongs to this request and not to an older one.
        if (Error e = write_al_control(*this, a, static_cast<uint16_t>(st->state | kAlErrorAck), deadline);
            e != Error::Ok)
            return e;
        for (;;) {
            st = al_status(a);
            if (!st) return st.error();
            if (!st->error) break;
            if (Clock::now() >= deadline) {
                if (final) *final = *st;
                return Error::AlTimeout;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
    }
    if (st->state == static_cast<uint8_t>(state)) {
        // Already there: write nothing. AL control is a one-message mailbox in the ESC (device emulation
        // off): a write the firmware has not read yet blocks the next one, so a needless request here could
        // swallow the caller's next, real request (seen as a BOOT request lost after INIT -> INIT).
        if (final) *final = *st;
        return Error::Ok;
    }
    if (Error e = write_al_control(*this, a, static_cast<uint8_t>(state), deadline); e != Error::Ok) return e;
    for (;;) {
        st = al_status(a);
        if (!st) return st.error();
        if (final) *final = *st;
        if (st->error) {
            // Refused: acknowledge, leaving the slave in the state it reports.
            const AlStatus refused = *st;
            write_al_control(*this, a, static_cast<uint16_t>(refused.state | kAlErrorAck), deadline);
            if (final) *final = refused;
            return Error::AlRefused;
        }
        if (st->state == static_cast<uint8_t>(state)) return Error::Ok;
        if (Clock::now() >= deadline) return Error::AlTimeout;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
}

Result<uint16_t> Master::identify(Address a) {
    const auto deadline = Clock::now() + options_.al_timeout;
    auto st = al_status(a);
    if (!st) return st.error();
    if (st->error) return Error::AlRefused;
    if (Error e = write_al_control(*this, a, static_cast<uint16_t>(st->state | kAlIdentify), deadline);
        e != Error::Ok)
        return e;
    for (;;) {
        auto now = al_status(a);
        if (!now) return now.error();
        if (now->error) return Error::AlRefused;
        if (now->id_loaded) {
            const uint16_t value = now->code;
            (void)write_al_control(*this, a, st->state, deadline);  // request off again
            return value;
        }
        if (Clock::now() >= deadline) return Error::AlTimeout;
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
}

Error Master::request_state_all(AlState state, std::span<const uint16_t> stations) {
    const uint8_t v[2] = {static_cast<uint8_t>(state), 0};
    auto w = broadcast_write(reg::AlControl, v);
    if (!w) return w.error();
    if (*w == 0) return Error::WorkingCounter;
    Error result = Error::Ok;
    for (uint16_t s : stations) {
        // Each slave is then driven (and its error acknowledged) individually.
        const Error e = request_state(Address::station(s), state);
        if (e != Error::Ok && result == Error::Ok) result = e;
    }
    return result;
}

}  // namespace master
