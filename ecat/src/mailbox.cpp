#include "ecat/mailbox.hpp"

#include <algorithm>
#include <cstring>

#include "ecat/registers.hpp"

#include "util/le.hpp"

namespace ecat {
namespace {
using util::get16;
using util::put16;

constexpr uint8_t kSm0 = 0;
constexpr uint8_t kSm1 = 1;

// Smallest protocol header after the mailbox header; a shorter request is "size too short" (ETG.1000.6,
// mailbox error reply).
std::size_t min_protocol_length(uint8_t type) {
    switch (static_cast<MailboxType>(type)) {
        case MailboxType::CoE:
            return 2;  // CoE header
        case MailboxType::FoE:
            return 6;  // opcode, reserved, 4-byte password / packet number / code
        case MailboxType::EoE:
            return 4;  // EoE header
        case MailboxType::SoE:
            return 4;  // SoE header
        case MailboxType::AoE:
            return 32;  // AMS header
        case MailboxType::VoE:
            return 6;  // vendor id + vendor type
        default:
            return 1;
    }
}

}  // namespace

Mailbox::Mailbox(esc::Pdi& pdi, std::size_t max_size)
    : pdi_(pdi),
      max_size_(std::max<std::size_t>(max_size, kMailboxHeaderSize + 4)),
      storage_(kQueueCapacity * max_size_),
      current_(max_size_),
      previous_(max_size_),
      rx_(max_size_) {}

void Mailbox::add_handler(MailboxHandler& handler) {
    for (std::size_t i = 0; i < handler_count_; ++i) {
        if (handlers_[i]->type() == handler.type()) {
            handlers_[i] = &handler;
            return;
        }
    }
    if (handler_count_ < handlers_.size()) handlers_[handler_count_++] = &handler;
}

uint16_t Mailbox::sm1_base() const {
    return reg::sm_base(kSm1);
}

void Mailbox::start(const od::MailboxLayout& layout, od::AlState state) {
    layout_ = layout;
    layout_.out_size = static_cast<uint16_t>(std::min<std::size_t>(layout_.out_size, max_size_));
    layout_.in_size = static_cast<uint16_t>(std::min<std::size_t>(layout_.in_size, max_size_));
    state_ = state;
    head_ = 0;
    count_ = 0;
    current_len_ = 0;
    previous_len_ = 0;
    last_rx_counter_ = 0;
    tx_counter_ = 0;
    reply_address_ = 0;
    // Re-enable both mailbox SMs from the PDI side; take the master's current repeat-request bit as the
    // starting point of the handshake.
    repeat_ack_ = (pdi_.read_reg<uint8_t>(sm1_base() + reg::kSmActivate) & reg::kSmRepeatRequest) != 0;
    pdi_.write_reg<uint8_t>(reg::sm_base(kSm0) + reg::kSmPdiControl, 0);
    pdi_.write_reg<uint8_t>(sm1_base() + reg::kSmPdiControl, repeat_ack_ ? reg::kSmPdiRepeatAck : 0);
    running_ = true;
}

void Mailbox::stop() {
    running_ = false;
    count_ = 0;
    head_ = 0;
    current_len_ = 0;
    previous_len_ = 0;
    pdi_.write_reg<uint8_t>(reg::sm_base(kSm0) + reg::kSmPdiControl, reg::kSmPdiDeactivate);
    pdi_.write_reg<uint8_t>(sm1_base() + reg::kSmPdiControl, reg::kSmPdiDeactivate);
}

void Mailbox::set_state(od::AlState from, od::AlState to) {
    state_ = to;
    for (std::size_t i = 0; i < handler_count_; ++i)
        handlers_[i]->on_state_change(from, to);
}

std::size_t Mailbox::max_payload() const {
    const std::size_t in = running_ ? layout_.in_size : std::min<std::size_t>(max_size_, 128);
    return in > kMailboxHeaderSize ? in - kMailboxHeaderSize : 0;
}

bool Mailbox::send(MailboxType type, std::span<const uint8_t> payload) {
    if (!running_ || payload.size() > max_payload()) return false;
    if (count_ == kQueueCapacity) {
        ++stats_.queue_full;
        return false;
    }
    const std::size_t index = (head_ + count_) % kQueueCapacity;
    uint8_t* m = slot(index);
    put16(m, static_cast<uint16_t>(payload.size()));
    put16(m + 2, reply_address_);
    m[4] = 0;                                  // channel 0, priority 0
    m[5] = static_cast<uint8_t>(type) & 0x0F;  // counter assigned when first written into SM1
    if (!payload.empty()) std::memcpy(m + kMailboxHeaderSize, payload.data(), payload.size());
    lengths_[index] = static_cast<uint16_t>(kMailboxHeaderSize + payload.size());
    ++count_;
    return true;
}

bool Mailbox::send_error(MailboxError detail) {
    uint8_t body[4];
    put16(body, 0x0001);  // mailbox command error
    put16(body + 2, static_cast<uint16_t>(detail));
    const bool ok = send(MailboxType::Error, body);
    if (ok) ++stats_.errors_sent;
    return ok;
}

uint8_t Mailbox::next_counter() {
    tx_counter_ = static_cast<uint8_t>(tx_counter_ % 7 + 1);  // 1..7, never 0
    return tx_counter_;
}

void Mailbox::poll(uint64_t now_ns) {
    if (!running_) return;
    serve_repeat_request();
    receive();
    for (std::size_t i = 0; i < handler_count_; ++i)
        handlers_[i]->poll(now_ns, *this);
    transmit();
}

void Mailbox::receive() {
    const uint8_t status = pdi_.read_reg<uint8_t>(reg::sm_base(kSm0) + reg::kSmStatus);
    if (!(status & reg::kSmStatusMailboxFull)) return;
    // Read SM0 to its last byte: that releases the buffer for the master's next write.
    std::span<uint8_t> message(rx_.data(), layout_.out_size);
    pdi_.read(layout_.out_start, message);
    ++stats_.received;
    dispatch(message);
}

void Mailbox::dispatch(std::span<const uint8_t> message) {
    if (message.size() < kMailboxHeaderSize) return;
    const uint16_t length = get16(message.data());
    const uint16_t address = get16(message.data() + 2);
    const uint8_t channel = message[4] & 0x3F;
    const uint8_t type = message[5] & 0x0F;
    const uint8_t counter = (message[5] >> 4) & 0x07;

    reply_address_ = address;
    struct ResetAddress {
        uint16_t& a;
        ~ResetAddress() { a = 0; }
    } reset{reply_address_};

    // Header checks (ETG.1000.4 mailbox header, ETG.1000.6 mailbox error reply; decisions in
    // docs/decisions/ecat.md).
    if (type == static_cast<uint8_t>(MailboxType::Error)) {
        send_error(MailboxError::InvalidHeader);
        return;
    }
    if (length > message.size() - kMailboxHeaderSize) {
        send_error(MailboxError::InvalidSize);
        return;
    }
    if (length < min_protocol_length(type)) {
        send_error(MailboxError::SizeTooShort);
        return;
    }
    if (channel != 0) {
        send_error(MailboxError::InvalidChannel);
        return;
    }
    // A request repeated with the same non-zero counter (its reply was lost, or the master's write was
    // repeated) is not executed twice.
    if (counter != 0 && counter == last_rx_counter_ && !faults_.counter_ignored) {
        ++stats_.duplicates;
        return;
    }
    last_rx_counter_ = counter;

    MailboxHandler* handler = nullptr;
    for (std::size_t i = 0; i < handler_count_; ++i) {
        if (static_cast<uint8_t>(handlers_[i]->type()) == type) handler = handlers_[i];
    }
    // Bootstrap serves FoE only (ETG.1000.6, Bootstrap state); otherwise the handler says where it is
    // available.
    const bool allowed = handler != nullptr && handler->available(state_) &&
                         (state_ != od::AlState::Boot || handler->type() == MailboxType::FoE);
    if (!allowed) {
        if (!faults_.unsupported_protocol_silent) send_error(MailboxError::UnsupportedProtocol);
        return;
    }
    ++stats_.dispatched;
    handler->handle(message.subspan(kMailboxHeaderSize, length), *this);
}

void Mailbox::write_sm1(std::span<const uint8_t> message) {
    // Write the whole SM1 length so the last byte completes the buffer; the tail is zero.
    std::span<uint8_t> out(current_.data(), layout_.in_size);
    if (message.data() != current_.data()) std::memcpy(current_.data(), message.data(), message.size());
    std::fill(out.begin() + static_cast<std::ptrdiff_t>(message.size()), out.end(), uint8_t{0});
    current_len_ = message.size();
    pdi_.write(layout_.in_start, out);
}

void Mailbox::transmit() {
    if (count_ == 0) return;
    const uint8_t status = pdi_.read_reg<uint8_t>(sm1_base() + reg::kSmStatus);
    if (status & reg::kSmStatusMailboxFull) return;  // the master has not read the last one yet
    uint8_t* m = slot(head_);
    const std::size_t len = lengths_[head_];
    head_ = (head_ + 1) % kQueueCapacity;
    --count_;
    if (((m[5] >> 4) & 0x07) == 0) {
        m[5] = static_cast<uint8_t>((m[5] & 0x0F) | (next_counter() << 4));
        ++stats_.sent;
    }
    // What SM1 held so far has been read by the master: it becomes the repeat backup.
    std::swap(previous_, current_);
    previous_len_ = current_len_;
    write_sm1({m, len});
}

void Mailbox::serve_repeat_request() {
    const uint8_t activate = pdi_.read_reg<uint8_t>(sm1_base() + reg::kSmActivate);
    const bool request = (activate & reg::kSmRepeatRequest) != 0;
    if (request == repeat_ack_ || faults_.repeat_ignored) return;
    ++stats_.repeats;
    const uint8_t status = pdi_.read_reg<uint8_t>(sm1_base() + reg::kSmStatus);
    const uint8_t ack_bits = repeat_ack_ ? reg::kSmPdiRepeatAck : 0;
    if (status & reg::kSmStatusMailboxFull) {
        // SM1 holds a newer message the master has not read: flush it (PDI deactivation), put it back at
        // the front of the queue, and rewrite the one whose read was lost.
        pdi_.write_reg<uint8_t>(sm1_base() + reg::kSmPdiControl,
                                static_cast<uint8_t>(ack_bits | reg::kSmPdiDeactivate));
        pdi_.write_reg<uint8_t>(sm1_base() + reg::kSmPdiControl, ack_bits);
        if (current_len_ > 0) {
            if (count_ == kQueueCapacity) {
                ++stats_.queue_full;  // the newest queued message is dropped to keep the order
                --count_;
            }
            head_ = (head_ + kQueueCapacity - 1) % kQueueCapacity;
            std::memcpy(slot(head_), current_.data(), current_len_);
            lengths_[head_] = static_cast<uint16_t>(current_len_);
            ++count_;
        }
        std::swap(previous_, current_);
        current_len_ = previous_len_;
        previous_len_ = 0;
    }
    if (current_len_ > 0) write_sm1({current_.data(), current_len_});
    repeat_ack_ = request;
    pdi_.write_reg<uint8_t>(sm1_base() + reg::kSmPdiControl, request ? reg::kSmPdiRepeatAck : 0);
}

}  // namespace ecat
