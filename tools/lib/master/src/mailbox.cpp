// Master side of the mailbox (mailbox SMs and repeat: ESC datasheet section I §8.2, §8.6; header and counter:
// ETG.1000.4 mailbox, ESC datasheet section I Table 24).
#include "master/mailbox.hpp"

#include <algorithm>
#include <thread>

#include "util/le.hpp"

namespace master {

using Clock = std::chrono::steady_clock;

namespace {
using util::get16;
using util::put16;
constexpr auto kPoll = std::chrono::microseconds(200);
}  // namespace

Mailbox::Mailbox(Master& master, Address slave, std::chrono::milliseconds timeout)
    : m_(master), slave_(slave), timeout_(timeout) {}

Error Mailbox::configure_from_sii(bool bootstrap) {
    uint8_t w[10];  // words 0x18-0x1C (0x14-0x17 bootstrap): SM0 start/size, SM1 start/size, protocols
    if (Error e = m_.sii_read(slave_, sii::StdMailboxOut, w); e != Error::Ok) return e;
    if (bootstrap) {
        if (Error e = m_.sii_read(slave_, sii::BootMailboxOut, std::span<uint8_t>(w, 8)); e != Error::Ok)
            return e;
    }
    MailboxConfig c;
    c.out_start = get16(w);
    c.out_size = get16(w + 2);
    c.in_start = get16(w + 4);
    c.in_size = get16(w + 6);
    c.protocols = get16(w + 8);
    if (std::all_of(w, w + 8, [](uint8_t b) { return b == 0; })) return Error::NoMailbox;
    if (!c.valid()) return Error::MailboxNotConfigured;
    return configure(c);
}

Error Mailbox::configure(const MailboxConfig& c) {
    if (!c.valid()) return Error::InvalidArgument;
    uint8_t sm[16] = {};
    put16(sm + 0, c.out_start);
    put16(sm + 2, c.out_size);
    sm[4] = kSm0ControlDefault;
    sm[6] = 0x01;  // activate
    put16(sm + 8, c.in_start);
    put16(sm + 10, c.in_size);
    sm[12] = kSm1ControlDefault;
    sm[14] = 0x01;
    // Disable both first: start, length and control are taken only while an SM is disabled (ESC datasheet
    // section I §8).
    const uint8_t off[16] = {};
    if (Error e = m_.write(slave_, reg::Sm0, off); e != Error::Ok) return e;
    if (Error e = m_.write(slave_, reg::Sm0, sm); e != Error::Ok) return e;
    config_ = c;
    tx_.assign(c.out_size, 0);
    rx_.assign(c.in_size, 0);
    counter_ = 0;
    send_zero_ = false;
    return Error::Ok;
}

Error Mailbox::adopt_current() {
    uint8_t sm[16];
    if (Error e = m_.read(slave_, reg::Sm0, sm); e != Error::Ok) return e;
    MailboxConfig c;
    c.out_start = get16(sm);
    c.out_size = get16(sm + 2);
    c.in_start = get16(sm + 8);
    c.in_size = get16(sm + 10);
    if (!c.valid() || !(sm[6] & 1) || !(sm[14] & 1) || (sm[4] & 0x0F) != 0x06 || (sm[12] & 0x0F) != 0x02)
        return Error::MailboxNotConfigured;
    if (auto p = m_.sii_read_word(slave_, sii::MailboxProtocols)) c.protocols = *p;
    config_ = c;
    tx_.assign(c.out_size, 0);
    rx_.assign(c.in_size, 0);
    // The slave remembers the counter of the last request it took, which another master process may
    // have sent; a first request with that counter would be dropped as a repeat. Counter 0 ("not
    // used", ETG.1000.4 mailbox header) is never a repeat, and 1, 2, ... follow it.
    counter_ = 0;
    send_zero_ = true;
    drain();  // an answer an earlier process abandoned is not ours
    return Error::Ok;
}

uint8_t Mailbox::next_counter() {
    counter_ = static_cast<uint8_t>(counter_ % 7 + 1);  // 1..7, never 0 (ETG.1000.4 mailbox header)
    return counter_;
}

Error Mailbox::send(MailboxType type, std::span<const uint8_t> payload) {
    if (!config_.valid()) return Error::MailboxNotConfigured;
    if (payload.empty() || payload.size() > max_out_payload()) return Error::InvalidArgument;
    // The whole SM0 length is written so that its last byte closes the buffer (ESC datasheet section I §8.2).
    std::fill(tx_.begin(), tx_.end(), 0);
    put16(tx_.data(), static_cast<uint16_t>(payload.size()));
    put16(tx_.data() + 2, 0);
    tx_[4] = 0;
    const uint8_t counter = send_zero_ ? 0 : next_counter();
    send_zero_ = false;
    tx_[5] = static_cast<uint8_t>(static_cast<uint8_t>(type) | (counter << 4));
    std::copy(payload.begin(), payload.end(), tx_.begin() + 6);
    const auto deadline = Clock::now() + timeout_;
    for (;;) {
        Datagram d = Master::addressed(slave_, true, config_.out_start, tx_);
        // Retries are safe here: a repeated write carries the same counter and the slave drops it (ETG.1000.4
        // mailbox header).
        if (Error e = m_.exchange(d); e != Error::Ok) return e;
        if (d.wkc == 1) return Error::Ok;
        if (Clock::now() >= deadline) return Error::MailboxTimeout;  // SM0 stays full
        std::this_thread::sleep_for(kPoll);
    }
}

Error Mailbox::read_sm1(bool& got) {
    got = false;
    Datagram d = Master::addressed(slave_, false, config_.in_start, rx_);
    // One attempt only: if the reply is lost, the ESC has already released the message, and a second
    // read would find SM1 empty; the repeat request gets it back.
    if (Error e = m_.exchange(std::span<Datagram>(&d, 1), 0); e != Error::Ok) return e;
    got = d.wkc == 1;
    return Error::Ok;
}

Error Mailbox::repeat_request() {
    const auto deadline = Clock::now() + timeout_;
    uint8_t act = 0;
    if (Error e = m_.read(slave_, static_cast<uint16_t>(reg::Sm0 + 8 + 6), std::span<uint8_t>(&act, 1));
        e != Error::Ok)
        return e;
    const uint8_t toggled = static_cast<uint8_t>(act ^ 0x02);
    if (Error e =
            m_.write(slave_, static_cast<uint16_t>(reg::Sm0 + 8 + 6), std::span<const uint8_t>(&toggled, 1));
        e != Error::Ok)
        return e;
    ++repeats_;
    for (;;) {
        uint8_t pdi = 0;
        if (Error e = m_.read(slave_, static_cast<uint16_t>(reg::Sm0 + 8 + 7), std::span<uint8_t>(&pdi, 1));
            e != Error::Ok)
            return e;
        if ((pdi & 0x02) == (toggled & 0x02)) return Error::Ok;  // acknowledged: the message is back
        if (Clock::now() >= deadline) return Error::MailboxTimeout;
        std::this_thread::sleep_for(kPoll);
    }
}

Error Mailbox::receive(MailboxMessage& message) {
    return receive(message, timeout_);
}

Error Mailbox::receive(MailboxMessage& message, std::chrono::milliseconds timeout) {
    if (!config_.valid()) return Error::MailboxNotConfigured;
    const auto deadline = Clock::now() + timeout;
    bool repeated = false;
    for (;;) {
        bool got = false;
        Error e = read_sm1(got);
        if (e == Error::Timeout) {
            // Lost reply: ask the slave to put its last message back, then read again.
            if ((e = repeat_request()) != Error::Ok) return e;
            repeated = true;
            continue;
        }
        if (e != Error::Ok) return e;
        if (got) {
            const uint16_t len = get16(rx_.data());
            if (len > rx_.size() - 6) return Error::MailboxProtocol;
            const auto counter = static_cast<uint8_t>((rx_[5] >> 4) & 0x07);
            if (repeated && counter != 0 && counter == last_rx_counter_) {
                // The lost read had found SM1 empty: what came back is the message we already had.
                repeated = false;
                continue;
            }
            last_rx_counter_ = counter;
            message.type = static_cast<MailboxType>(rx_[5] & 0x0F);
            message.counter = static_cast<uint8_t>((rx_[5] >> 4) & 0x07);
            message.address = get16(rx_.data() + 2);
            message.channel = rx_[4] & 0x3F;
            message.priority = static_cast<uint8_t>(rx_[4] >> 6);
            message.payload = std::span<const uint8_t>(rx_.data() + 6, len);
            return Error::Ok;
        }
        if (Clock::now() >= deadline) return Error::MailboxTimeout;
        std::this_thread::sleep_for(kPoll);
    }
}

std::size_t Mailbox::drain(const std::function<bool(const MailboxMessage&)>& keep) {
    constexpr int kMaxWaiting = 8;
    std::size_t dropped = 0;
    MailboxMessage msg;
    for (int i = 0; i < kMaxWaiting; ++i) {
        if (receive(msg, std::chrono::milliseconds(0)) != Error::Ok) break;
        if (!keep || !keep(msg)) ++dropped;
    }
    return dropped;
}

}  // namespace master
