// FoE client (ETG.1000.6 FoE: packets and transfer flow).
#include <algorithm>

#include "master/foe.hpp"

#include "foe/wire/foe.hpp"
#include "util/le.hpp"

namespace master {

namespace {
using util::get32;
// The FoE vocabulary (foe/wire/foe.hpp).
constexpr uint8_t kRead = static_cast<uint8_t>(foe::Opcode::Read),
                  kWrite = static_cast<uint8_t>(foe::Opcode::Write),
                  kData = static_cast<uint8_t>(foe::Opcode::Data),
                  kAck = static_cast<uint8_t>(foe::Opcode::Ack),
                  kErr = static_cast<uint8_t>(foe::Opcode::Error),
                  kBusy = static_cast<uint8_t>(foe::Opcode::Busy);
constexpr uint32_t kErrIllegal = static_cast<uint32_t>(foe::ErrorCode::Illegal);
constexpr uint32_t kErrPacketNumber = static_cast<uint32_t>(foe::ErrorCode::PacketNumberWrong);
constexpr uint32_t kErrDiskFull = static_cast<uint32_t>(foe::ErrorCode::DiskFull);
}  // namespace

FoeClient::FoeClient(Mailbox& mailbox) : mbx_(mailbox) {}

Error FoeClient::send(uint8_t opcode, uint32_t value, std::span<const uint8_t> data) {
    if (mbx_.max_out_payload() < 6 + data.size() || mbx_.max_out_payload() < 7) return Error::InvalidArgument;
    buf_.assign(6 + data.size(), 0);  // (allocation-free once the capacity is there)
    buf_[0] = opcode;
    buf_[1] = 0;
    for (int i = 0; i < 4; ++i)
        buf_[2 + i] = static_cast<uint8_t>(value >> (8 * i));
    std::copy(data.begin(), data.end(), buf_.begin() + 6);
    return mbx_.send(MailboxType::FoE, buf_);
}

Error FoeClient::receive(uint8_t& opcode, uint32_t& value, std::span<const uint8_t>& data) {
    for (;;) {
        MailboxMessage msg;
        if (Error e = mbx_.receive(msg); e != Error::Ok) return e;
        if (msg.type == MailboxType::Error) return Error::MailboxError;
        if (msg.type != MailboxType::FoE) continue;  // e.g. a CoE emergency: not part of this transfer
        if (msg.payload.size() < 6) return Error::MailboxProtocol;
        opcode = msg.payload[0];
        value = get32(msg.payload.data() + 2);
        data = msg.payload.subspan(6);
        if (opcode == kErr) {
            last_error_ = value;
            last_error_text_.assign(data.begin(), data.end());
            return Error::FoeError;
        }
        return Error::Ok;
    }
}

Result<std::vector<uint8_t>> FoeClient::read(std::string_view name, uint32_t password, std::size_t max_size) {
    if (!mbx_.config().valid()) return Error::MailboxNotConfigured;
    mbx_.drain();  // a late answer of an abandoned transfer is not this one's
    const std::size_t full = mbx_.max_in_payload() - 6;  // a full DATA packet from the slave
    if (Error e = send(kRead, password,
                       std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(name.data()), name.size()));
        e != Error::Ok)
        return e;
    std::vector<uint8_t> file;
    for (uint32_t expected = 1;; ++expected) {
        uint8_t op = 0;
        uint32_t packet = 0;
        std::span<const uint8_t> data;
        if (Error e = receive(op, packet, data); e != Error::Ok) return e;
        if (op == kBusy) {
            ++busy_;
            --expected;
            continue;
        }
        if (op != kData) {
            (void)send(kErr, kErrIllegal, {});
            return Error::MailboxProtocol;
        }
        if (packet != expected) {
            (void)send(kErr, kErrPacketNumber, {});
            return Error::MailboxProtocol;
        }
        if (file.size() + data.size() > max_size) {
            (void)send(kErr, kErrDiskFull, {});
            return Error::BufferTooSmall;
        }
        file.insert(file.end(), data.begin(), data.end());
        if (Error e = send(kAck, packet, {}); e != Error::Ok) return e;
        if (progress_) progress_(FoeProgress{file.size(), 0, false});
        if (data.size() < full) return file;
    }
}

Error FoeClient::write(std::string_view name, std::span<const uint8_t> data, uint32_t password) {
    if (!mbx_.config().valid()) return Error::MailboxNotConfigured;
    mbx_.drain();  // a late answer of an abandoned transfer is not this one's
    const std::size_t full = mbx_.max_out_payload() - 6;
    if (Error e = send(kWrite, password,
                       std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(name.data()), name.size()));
        e != Error::Ok)
        return e;
    uint8_t op = 0;
    uint32_t value = 0;
    std::span<const uint8_t> rest;
    if (Error e = receive(op, value, rest); e != Error::Ok) return e;
    if (op != kAck || value != 0) return Error::MailboxProtocol;
    std::size_t done = 0;
    for (uint32_t packet = 1;; ++packet) {
        const std::size_t n = std::min(full, data.size() - done);
        const auto chunk = data.subspan(done, n);
        if (Error e = send(kData, packet, chunk); e != Error::Ok) return e;
        // After the last packet the slave stores the image before it answers (or answers BUSY while it does).
        if (n < full && progress_) progress_(FoeProgress{done + n, data.size(), true});
        for (;;) {
            if (Error e = receive(op, value, rest); e != Error::Ok) return e;
            if (op == kBusy) {
                // Still working (e.g. storing the image): send the same packet again (SOEM).
                ++busy_;
                if (progress_) progress_(FoeProgress{done + n, data.size(), true});
                if (Error e = send(kData, packet, chunk); e != Error::Ok) return e;
                continue;
            }
            if (op != kAck || value != packet) return Error::MailboxProtocol;
            break;
        }
        done += n;
        if (progress_) progress_(FoeProgress{done, data.size(), false});
        if (n < full) return Error::Ok;  // a short (or empty) packet was the last one
    }
}

}  // namespace master
