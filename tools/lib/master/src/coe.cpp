// CoE SDO client (ETG.1000.6 CoE: SDO transfers, abort codes, emergencies).
#include "master/coe.hpp"

#include <algorithm>
#include <cstring>

#include "coe/wire/sdo.hpp"
#include "util/le.hpp"

namespace master {

using Clock = std::chrono::steady_clock;

namespace {
using util::get16;
using util::get32;
using util::put16;
using util::put32;
// The CoE vocabulary (coe/wire/sdo.hpp).
constexpr uint8_t kServiceEmergency = static_cast<uint8_t>(coe::Service::Emergency);
constexpr uint8_t kServiceSdoRequest = static_cast<uint8_t>(coe::Service::SdoRequest);
constexpr uint8_t kServiceSdoResponse = static_cast<uint8_t>(coe::Service::SdoResponse);
constexpr uint8_t kServiceSdoInfo = static_cast<uint8_t>(coe::Service::SdoInfo);
constexpr uint8_t kInfoError = coe::info::kError;
constexpr uint8_t kInfoIncomplete = coe::info::kIncomplete;
constexpr uint32_t kAbortToggle = coe::abort::ToggleBit;
constexpr uint32_t kAbortCommand = coe::abort::UnknownCommand;
constexpr uint32_t kAbortOutOfMemory = coe::abort::OutOfMemory;
constexpr uint32_t kAbortGeneral = coe::abort::General;

// CoE header + SDO command + index + subindex.
void sdo_head(uint8_t* p, uint8_t cmd, uint16_t index, uint8_t sub) {
    put16(p, static_cast<uint16_t>(kServiceSdoRequest << 12));
    p[2] = cmd;
    put16(p + 3, index);
    p[5] = sub;
}
}  // namespace

std::string_view sdo_abort_text(uint32_t code) {
    const std::string_view text = coe::abort::text(code);
    return text.empty() ? "unknown abort code" : text;
}

SdoClient::SdoClient(Mailbox& mailbox)
    : mbx_(mailbox), req_(std::max<std::size_t>(mailbox.max_out_payload(), 10)) {}

Error SdoClient::prepare() {
    // The mailbox may have been (re)configured since construction: follow its size (allocates only then).
    if (mbx_.max_out_payload() < 10 || mbx_.max_in_payload() < 10) return Error::MailboxNotConfigured;
    if (req_.size() != mbx_.max_out_payload()) req_.assign(mbx_.max_out_payload(), 0);
    take_stale();
    return Error::Ok;
}

void SdoClient::take_stale() {
    // What the slave put in its out-mailbox since the last transfer: emergencies (kept as ever) and the late
    // answers of transfers given up on (counted).
    stale_answers_ += mbx_.drain([this](const MailboxMessage& msg) { return take_emergency(msg); });
}

bool SdoClient::take_emergency(const MailboxMessage& msg) {
    const auto p = msg.payload;
    if (msg.type != MailboxType::CoE || p.size() < 2 || (p[1] >> 4) != kServiceEmergency) return false;
    if (p.size() >= 10) {
        last_emergency_.code = get16(p.data() + 2);
        last_emergency_.error_register = p[4];
        std::copy_n(p.begin() + 5, 5, last_emergency_.data.begin());
    }
    ++emergencies_;
    return true;
}

Error SdoClient::send(std::size_t length) {
    return mbx_.send(MailboxType::CoE, std::span<const uint8_t>(req_.data(), length));
}

void SdoClient::abort(uint16_t index, uint8_t sub, uint32_t code) {
    std::fill(req_.begin(), req_.begin() + 10, 0);
    sdo_head(req_.data(), 0x80, index, sub);
    put32(req_.data() + 6, code);
    (void)send(10);  // best effort: the transfer is over for us either way
    last_abort_ = code;
}

Error SdoClient::response(MailboxMessage& msg, uint8_t wanted) {
    const auto deadline = Clock::now() + mbx_.timeout();
    for (;;) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
        if (left.count() <= 0) return Error::MailboxTimeout;
        if (Error e = mbx_.receive(msg, left); e != Error::Ok) return e;
        const auto p = msg.payload;
        if (msg.type == MailboxType::Error) {
            last_mailbox_error_ = p.size() >= 4 ? get16(p.data() + 2) : 0;
            return Error::MailboxError;
        }
        if (msg.type != MailboxType::CoE || p.size() < 2 || take_emergency(msg)) continue;  // not for us
        const uint8_t service = static_cast<uint8_t>(p[1] >> 4);
        if (wanted == kServiceSdoInfo) {
            if (service != kServiceSdoInfo) continue;
            if (p.size() < 6) return Error::MailboxProtocol;
            return Error::Ok;
        }
        // An abort may come as an SDO request (service 2, as SOES sends it) or response: SOEM takes it
        // by its command byte alone, and so does this client.
        const bool abort_request = service == kServiceSdoRequest && p.size() >= 10 && p[2] == 0x80;
        if (service != kServiceSdoResponse && !abort_request) continue;
        if (p.size() < 10) return Error::MailboxProtocol;
        return Error::Ok;
    }
}

Result<std::size_t> SdoClient::upload(uint16_t index, uint8_t sub, std::span<uint8_t> out,
                                      bool complete_access) {
    if (Error e = prepare(); e != Error::Ok) return e;
    std::fill(req_.begin(), req_.begin() + 10, 0);
    sdo_head(req_.data(), static_cast<uint8_t>(0x40 | (complete_access ? 0x10 : 0)), index, sub);
    if (Error e = send(10); e != Error::Ok) return e;
    MailboxMessage msg;
    if (Error e = response(msg); e != Error::Ok) return e;
    auto p = msg.payload;
    uint8_t cmd = p[2];
    if (cmd == 0x80) {
        last_abort_ = get32(p.data() + 6);
        return Error::SdoAbort;
    }
    if ((cmd >> 5) != 2 || get16(p.data() + 3) != index) {
        abort(index, sub, kAbortCommand);
        return Error::MailboxProtocol;
    }
    last_size_indicated_ = (cmd & 0x01) != 0;
    if (cmd & 0x02) {  // expedited: data in the 4-byte field
        const std::size_t n = (cmd & 0x01) ? 4u - ((cmd >> 2) & 0x03) : 4u;
        if (n > out.size()) return Error::BufferTooSmall;
        std::copy_n(p.begin() + 6, n, out.begin());
        return n;
    }
    const bool size_known = cmd & 0x01;
    const std::size_t size = size_known ? get32(p.data() + 6) : out.size();
    if (size_known && size > out.size()) {
        abort(index, sub, kAbortOutOfMemory);
        return Error::BufferTooSmall;
    }
    std::size_t done = std::min(p.size() - 10, size);
    std::copy_n(p.begin() + 10, done, out.begin());
    uint8_t toggle = 0;
    while (done < size) {
        std::fill(req_.begin(), req_.begin() + 10, 0);
        sdo_head(req_.data(), static_cast<uint8_t>(0x60 | (toggle << 4)), index, sub);
        if (Error e = send(10); e != Error::Ok) return e;
        if (Error e = response(msg); e != Error::Ok) return e;
        p = msg.payload;
        cmd = p[2];
        if (cmd == 0x80) {
            last_abort_ = get32(p.data() + 6);
            return Error::SdoAbort;
        }
        if ((cmd >> 5) != 0) {
            abort(index, sub, kAbortCommand);
            return Error::MailboxProtocol;
        }
        if (((cmd >> 4) & 1) != toggle) {
            abort(index, sub, kAbortToggle);
            return Error::MailboxProtocol;
        }
        // A segment carries 7 bytes minus the unused count in a 10-byte message, else length - 3.
        const std::size_t n = p.size() == 10 ? 7u - ((cmd >> 1) & 0x07) : p.size() - 3;
        if (n > size - done) {
            if (size_known) {
                abort(index, sub, kAbortGeneral);
                return Error::MailboxProtocol;
            }
            abort(index, sub, kAbortOutOfMemory);
            return Error::BufferTooSmall;
        }
        std::copy_n(p.begin() + 3, n, out.begin() + static_cast<std::ptrdiff_t>(done));
        done += n;
        toggle ^= 1;
        if (cmd & 0x01) break;  // last segment
    }
    if (size_known && done != size) return Error::MailboxProtocol;
    return done;
}

Error SdoClient::download(uint16_t index, uint8_t sub, std::span<const uint8_t> data, bool complete_access) {
    if (Error e = prepare(); e != Error::Ok) return e;
    const std::size_t max_payload = req_.size();
    if (data.empty()) return Error::InvalidArgument;
    MailboxMessage msg;
    std::size_t done = 0;
    std::fill(req_.begin(), req_.end(), 0);
    if (data.size() <= 4 && !complete_access) {
        sdo_head(req_.data(), static_cast<uint8_t>(0x23 | ((4 - data.size()) << 2)), index, sub);
        std::copy(data.begin(), data.end(), req_.begin() + 6);
        if (Error e = send(10); e != Error::Ok) return e;
        done = data.size();
    } else {
        sdo_head(req_.data(), static_cast<uint8_t>(0x21 | (complete_access ? 0x10 : 0)), index, sub);
        put32(req_.data() + 6, static_cast<uint32_t>(data.size()));
        done = std::min(data.size(), max_payload - 10);
        std::copy_n(data.begin(), done, req_.begin() + 10);
        if (Error e = send(10 + done); e != Error::Ok) return e;
    }
    if (Error e = response(msg); e != Error::Ok) return e;
    auto p = msg.payload;
    if (p[2] == 0x80) {
        last_abort_ = get32(p.data() + 6);
        return Error::SdoAbort;
    }
    if ((p[2] >> 5) != 3 || get16(p.data() + 3) != index) {
        abort(index, sub, kAbortCommand);
        return Error::MailboxProtocol;
    }
    uint8_t toggle = 0;
    while (done < data.size()) {
        const std::size_t n = std::min(data.size() - done, max_payload - 3);
        const bool last = done + n == data.size();
        uint8_t cmd = static_cast<uint8_t>((toggle << 4) | (last ? 1 : 0));
        std::fill(req_.begin(), req_.end(), 0);
        put16(req_.data(), static_cast<uint16_t>(kServiceSdoRequest << 12));
        std::copy_n(data.begin() + static_cast<std::ptrdiff_t>(done), n, req_.begin() + 3);
        std::size_t length = 3 + n;
        if (n < 7) {
            cmd = static_cast<uint8_t>(cmd | ((7 - n) << 1));
            length = 10;
        }
        req_[2] = cmd;
        if (Error e = send(length); e != Error::Ok) return e;
        if (Error e = response(msg); e != Error::Ok) return e;
        p = msg.payload;
        if (p[2] == 0x80) {
            last_abort_ = get32(p.data() + 6);
            return Error::SdoAbort;
        }
        if ((p[2] >> 5) != 1) {
            abort(index, sub, kAbortCommand);
            return Error::MailboxProtocol;
        }
        if (((p[2] >> 4) & 1) != toggle) {
            abort(index, sub, kAbortToggle);
            return Error::MailboxProtocol;
        }
        done += n;
        toggle ^= 1;
    }
    return Error::Ok;
}

Error SdoClient::info(uint8_t opcode, std::span<const uint8_t> body, std::vector<uint8_t>& answer) {
    if (Error e = prepare(); e != Error::Ok) return e;
    if (6 + body.size() > req_.size()) return Error::InvalidArgument;
    std::fill(req_.begin(), req_.begin() + 6, 0);
    put16(req_.data(), static_cast<uint16_t>(kServiceSdoInfo << 12));
    req_[2] = opcode;
    std::copy(body.begin(), body.end(), req_.begin() + 6);
    if (Error e = send(6 + body.size()); e != Error::Ok) return e;
    answer.clear();
    const uint8_t want = static_cast<uint8_t>(opcode + 1);
    for (;;) {
        MailboxMessage msg;
        if (Error e = response(msg, kServiceSdoInfo); e != Error::Ok) return e;
        const auto p = msg.payload;
        const uint8_t op = p[2] & 0x7F;
        if (op == kInfoError) {
            last_abort_ = p.size() >= 10 ? get32(p.data() + 6) : kAbortGeneral;
            return Error::SdoAbort;
        }
        if (op != want) return Error::MailboxProtocol;
        answer.insert(answer.end(), p.begin() + 6, p.end());
        // Fragments follow while the incomplete bit is set (fragments-left counts down to 0).
        if (!(p[2] & kInfoIncomplete) || get16(p.data() + 4) == 0) return Error::Ok;
    }
}

Result<std::vector<uint16_t>> SdoClient::od_list(uint16_t list_type) {
    uint8_t body[2];
    put16(body, list_type);
    std::vector<uint8_t> a;
    if (Error e = info(coe::info::kOdListReq, body, a); e != Error::Ok) return e;
    if (a.size() < 2 || get16(a.data()) != list_type) return Error::MailboxProtocol;
    std::vector<uint16_t> out;
    for (std::size_t i = 2; i + 1 < a.size(); i += 2)
        out.push_back(get16(&a[i]));
    return out;
}

Result<ObjectDescription> SdoClient::object_description(uint16_t index) {
    uint8_t body[2];
    put16(body, index);
    std::vector<uint8_t> a;
    if (Error e = info(coe::info::kObjDescReq, body, a); e != Error::Ok) return e;
    if (a.size() < 6 || get16(a.data()) != index) return Error::MailboxProtocol;
    ObjectDescription d;
    d.index = index;
    d.data_type = get16(&a[2]);
    d.max_subindex = a[4];
    d.object_code = a[5];
    d.name.assign(a.begin() + 6, a.end());
    return d;
}

Result<EntryDescription> SdoClient::entry_description(uint16_t index, uint8_t sub, uint8_t value_info) {
    uint8_t body[4];
    put16(body, index);
    body[2] = sub;
    body[3] = value_info;
    std::vector<uint8_t> a;
    if (Error e = info(coe::info::kEntryDescReq, body, a); e != Error::Ok) return e;
    if (a.size() < 10 || get16(a.data()) != index || a[2] != sub) return Error::MailboxProtocol;
    EntryDescription d;
    d.index = index;
    d.subindex = sub;
    d.value_info = a[3];
    d.data_type = get16(&a[4]);
    d.bit_length = get16(&a[6]);
    d.access = get16(&a[8]);
    // Unit (4 bytes), then default, minimum, maximum (each of the entry's byte size), then the name.
    std::size_t extra = 0;
    const std::size_t value_bytes = (d.bit_length + 7u) / 8u;
    if (d.value_info & 0x08) extra += 4;
    for (uint8_t bit : {uint8_t{0x10}, uint8_t{0x20}, uint8_t{0x40}})
        if (d.value_info & bit) extra += value_bytes;
    if (10 + extra > a.size()) return Error::MailboxProtocol;
    d.values.assign(a.begin() + 10, a.begin() + static_cast<std::ptrdiff_t>(10 + extra));
    d.name.assign(a.begin() + static_cast<std::ptrdiff_t>(10 + extra), a.end());
    return d;
}

Error SdoClients::open(Master& master, std::span<const Address> slaves,
                       const std::function<Error(Mailbox&, Address)>& open_each) {
    for (std::size_t k = 0; k < slaves.size(); ++k) {
        mailboxes_.push_back(std::make_unique<Mailbox>(master, slaves[k]));
        failed_ = k;
        if (Error e = open_each(*mailboxes_.back(), slaves[k]); e != Error::Ok) return e;
        clients_.push_back(std::make_unique<SdoClient>(*mailboxes_.back()));
        pointers_.push_back(clients_.back().get());
    }
    return Error::Ok;
}

}  // namespace master
