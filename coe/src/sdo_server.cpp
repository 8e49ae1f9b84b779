#include "coe/sdo_server.hpp"

#include <algorithm>
#include <cstring>

#include "coe/abort.hpp"
#include "complete_access.hpp"
#include "wire.hpp"

namespace coe {

namespace {

// SDO command specifiers, command byte bits and sizes: the CoE vocabulary (coe/wire/sdo.hpp).
using sdo::kCcsAbort;
using sdo::kCcsDownloadInitiate;
using sdo::kCcsDownloadSegment;
using sdo::kCcsUploadInitiate;
using sdo::kCcsUploadSegment;
using sdo::kCmdCompleteAccess;
using sdo::kCmdExpedited;
using sdo::kCmdLastSegment;
using sdo::kCmdSizeIndicated;
using sdo::kSdoFrame;
using sdo::kSegmentHead;

constexpr std::size_t kMinMessage = 64;  // initial size of the message buffers

bool writable_at_all(const od::Entry& e) {
    return (e.access & od::access::WriteMask) != 0;
}

}  // namespace

CoeServer::CoeServer(od::Dictionary& dict, StateFn state, CoeConfig config)
    : dict_(dict), state_(std::move(state)), config_(config), emergency_(&dict, config.emergency_queue) {
    std::size_t largest_value = 8;
    std::size_t largest_image = 0;
    std::size_t largest_rollback = 0;
    for (const auto& obj : dict_.objects()) {
        std::size_t rb = 0;
        for (const auto& e : obj.entries) {
            largest_value = std::max(largest_value, e.byte_size());
            rb += 3 + e.byte_size();
        }
        largest_image = std::max(largest_image, ca::max_image_size(obj));
        largest_rollback = std::max(largest_rollback, rb);
    }
    data_.resize(std::max(largest_value, largest_image));
    scratch_.resize(largest_value);
    rollback_.reserve(largest_rollback);
    tx_.resize(kMinMessage);
    held_.resize(kMinMessage);
    // SDO info: the whole OD list, or one entry description with unit, default, minimum, maximum and name.
    std::size_t longest_name = 0;
    for (const auto& obj : dict_.objects()) {
        longest_name = std::max(longest_name, obj.name.size());
        for (const auto& e : obj.entries)
            longest_name = std::max(longest_name, e.name.size());
    }
    info_buf_.resize(std::max(2 + 2 * dict_.objects().size(), 16 + 3 * largest_value + longest_name));
}

bool CoeServer::available(od::AlState s) const {
    return s == od::AlState::PreOp || s == od::AlState::SafeOp || s == od::AlState::Op;
}

// ---- Output path ----------------------------------------------------------------------------------------

uint8_t* CoeServer::tx(std::size_t size) {
    if (tx_.size() < size) tx_.resize(size);  // grows once to the mailbox size, then never again
    std::memset(tx_.data(), 0, size);
    return tx_.data();
}

bool CoeServer::send(std::span<const uint8_t> payload, ecat::MailboxSender& out) {
    if (held_len_ == 0 && out.send(ecat::MailboxType::CoE, payload)) return true;
    // Keep the newest reply until the sender has room (poll); an older held reply is stale by now.
    if (held_.size() < payload.size()) held_.resize(payload.size());
    std::memcpy(held_.data(), payload.data(), payload.size());
    held_len_ = payload.size();
    held_type_ = ecat::MailboxType::CoE;
    return false;
}

void CoeServer::send_mailbox_error(ecat::MailboxError e, ecat::MailboxSender& out) {
    uint8_t body[4];
    wire::put16(body, 0x0001);  // mailbox command error
    wire::put16(body + 2, static_cast<uint16_t>(e));
    if (out.send(ecat::MailboxType::Error, body)) return;
    std::memcpy(held_.data(), body, sizeof body);
    held_len_ = sizeof body;
    held_type_ = ecat::MailboxType::Error;
}

void CoeServer::send_abort(uint16_t index, uint8_t sub, uint32_t code, ecat::MailboxSender& out) {
    uint8_t* p = tx(kSdoFrame);
    // SOES sends the abort as an SDO request (service 2); masters accept it by its command byte.
    wire::put_coe_header(p, wire::Service::SdoRequest);
    p[2] = abort_command_;
    abort_command_ = 0x80;
    wire::put16(p + 3, index);
    p[5] = sub;
    wire::put32(p + 6, code);
    send(std::span<const uint8_t>(p, kSdoFrame), out);
}

void CoeServer::confirm_download(uint16_t index, uint8_t sub, ecat::MailboxSender& out) {
    uint8_t* p = tx(kSdoFrame);
    wire::put_coe_header(p, wire::Service::SdoResponse);
    p[2] = 0x60;
    wire::put16(p + 3, index);
    p[5] = sub;
    send(std::span<const uint8_t>(p, kSdoFrame), out);
}

// The AL state a download is checked against: with the pdo_map_in_safe_op fault, the PDO mapping and
// assignment objects are writable in Safe-Op as in Pre-Op.
od::AlState CoeServer::write_state(uint16_t index) const {
    if (is_pdo_object(index) && config_.faults.pdo_map_in_safe_op && state() == od::AlState::SafeOp)
        return od::AlState::PreOp;
    return state();
}

// A PDO mapping or assignment object as the object model declares it (od::Object::direction), wherever its
// index lies.
bool CoeServer::is_pdo_object(uint16_t index) const {
    const od::Object* o = dict_.find(index);
    return o != nullptr && o->direction != od::PdoDirection::None;
}

// The PDO mapping and assignment change only in Pre-Op (ETG.1000.6 PDO mapping and assignment: a change in
// Safe-Op or Op is refused with 0x08000022), whatever the access flags say: an ESI may declare 0x1C12 or
// 0x1600 "rw" without a write restriction (Beckhoff terminals, Inovance drives), and the devices built from
// it still refuse the change while their process data runs.
bool CoeServer::pdo_locked(uint16_t index) const {
    return is_pdo_object(index) && write_state(index) != od::AlState::PreOp;
}

void CoeServer::cancel_transfer() {
    xfer_ = Transfer{};
}

// ---- Dispatch -------------------------------------------------------------------------------------------

void CoeServer::handle(std::span<const uint8_t> payload, ecat::MailboxSender& out) {
    if (payload.size() < 2) {
        send_mailbox_error(ecat::MailboxError::SizeTooShort, out);
        return;
    }
    held_len_ = 0;  // the master has moved on: an answer it never fetched is stale
    auto service = static_cast<wire::Service>(wire::get16(payload, 0) >> 12);
    switch (service) {
        case wire::Service::SdoRequest:
            if (payload.size() < kSegmentHead) {
                send_mailbox_error(ecat::MailboxError::SizeTooShort, out);
                return;
            }
            info_ = InfoReply{};  // a new request cancels an SDO info answer still in fragments
            handle_sdo(payload.subspan(2), payload.size(), out);
            return;
        case wire::Service::SdoInfo:
            if (payload.size() < 6) {
                send_mailbox_error(ecat::MailboxError::SizeTooShort, out);
                return;
            }
            info_ = InfoReply{};
            if (xfer_.kind != Transfer::None) cancel_transfer();
            handle_info(payload.subspan(2), out);
            return;
        default:
            send_mailbox_error(ecat::MailboxError::ServiceNotSupported, out);
            return;
    }
}

void CoeServer::handle_sdo(std::span<const uint8_t> sdo, std::size_t frame_size, ecat::MailboxSender& out) {
    const uint8_t cmd = sdo[0];
    const uint8_t ccs = cmd >> 5;
    const bool segment = ccs == kCcsDownloadSegment || ccs == kCcsUploadSegment;
    if (!segment && frame_size < kSdoFrame) {
        send_mailbox_error(ecat::MailboxError::SizeTooShort, out);
        return;
    }
    switch (ccs) {
        case kCcsDownloadInitiate:
            cancel_transfer();
            download_initiate(sdo, out);
            return;
        case kCcsDownloadSegment:
            download_segment(sdo, out);
            return;
        case kCcsUploadInitiate:
            cancel_transfer();
            if ((cmd & kCmdCompleteAccess) && !config_.complete_access)
                return send_abort(wire::get16(sdo, 1), sdo[3], abort::CompleteAccessUnsupported, out);
            upload_initiate(wire::get16(sdo, 1), sdo[3], (cmd & kCmdCompleteAccess) != 0, out);
            return;
        case kCcsUploadSegment:
            upload_segment(cmd, out);
            return;
        case kCcsAbort:
            cancel_transfer();  // the master gave up: no answer
            return;
        default:
            // Block transfers (5, 6) and 7 are not CoE services.
            cancel_transfer();
            send_abort(wire::get16(sdo, 1), sdo[3], abort::UnknownCommand, out);
            return;
    }
}

// ---- Upload ---------------------------------------------------------------------------------------------

void CoeServer::upload_initiate(uint16_t index, uint8_t sub, bool ca, ecat::MailboxSender& out) {
    const od::Object* obj = dict_.find(index);
    if (obj == nullptr)
        return send_abort(index, sub,
                          config_.faults.abort_missing_object ? abort::NoSubindex : abort::NoObject, out);
    std::size_t len = 0;
    od::Status st;
    if (ca && obj->code != od::ObjectCode::Var) {
        if (sub > 1) return send_abort(index, sub, abort::UnsupportedAccess, out);
        std::size_t need = ca::image_size(*obj, sub, obj->max_subindex());
        if (data_.size() < need) data_.resize(need);
        st = ca::upload(dict_, *obj, sub, state(), data_, len, scratch_);
        if (st == od::Status::Ok && sub == 0 && len >= 2 && config_.faults.ca_no_padding) {
            std::memmove(data_.data() + 1, data_.data() + 2, len - 2);  // subindex 0 without its pad byte
            --len;
        }
    } else {
        const od::Entry* e = dict_.find(index, sub);
        if (e == nullptr) return send_abort(index, sub, abort::NoSubindex, out);
        if (data_.size() < e->byte_size()) data_.resize(e->byte_size());
        st = dict_.read(index, sub, state(), data_, len);
    }
    if (st != od::Status::Ok) return send_abort(index, sub, abort_code(st), out);

    const uint8_t ca_bit = ca ? kCmdCompleteAccess : 0;
    if (len >= 1 && len <= 4) {
        uint8_t* p = tx(kSdoFrame);
        wire::put_coe_header(p, wire::Service::SdoResponse);
        const std::size_t unused = config_.faults.expedited_size_wrong ? 0 : 4 - len;
        p[2] = static_cast<uint8_t>(0x40 | ca_bit | (unused << 2) | kCmdExpedited | kCmdSizeIndicated);
        wire::put16(p + 3, index);
        p[5] = sub;
        std::memcpy(p + 6, data_.data(), len);
        send(std::span<const uint8_t>(p, kSdoFrame), out);
        return;
    }
    const std::size_t max = std::max(out.max_payload(), kSdoFrame);
    const std::size_t first = std::min(len, max - kSdoFrame);
    uint8_t* p = tx(kSdoFrame + first);
    wire::put_coe_header(p, wire::Service::SdoResponse);
    p[2] = static_cast<uint8_t>(0x40 | ca_bit | kCmdSizeIndicated);
    wire::put16(p + 3, index);
    p[5] = sub;
    wire::put32(p + 6, static_cast<uint32_t>(len));
    std::memcpy(p + kSdoFrame, data_.data(), first);
    if (first < len) {
        xfer_.kind = Transfer::Upload;
        xfer_.index = index;
        xfer_.sub = sub;
        xfer_.complete_access = ca;
        xfer_.size = len;
        xfer_.done = first;
        xfer_.toggle = 0;
        xfer_.stamp_pending = true;
    }
    send(std::span<const uint8_t>(p, kSdoFrame + first), out);
}

void CoeServer::upload_segment(uint8_t cmd, ecat::MailboxSender& out) {
    if (xfer_.kind != Transfer::Upload) {
        uint16_t index = xfer_.index;
        uint8_t sub = xfer_.sub;
        cancel_transfer();
        return send_abort(index, sub, abort::UnknownCommand, out);
    }
    const uint8_t toggle = (cmd & kCmdCompleteAccess) ? 1 : 0;
    if (toggle != xfer_.toggle) {
        uint16_t index = xfer_.index;
        uint8_t sub = xfer_.sub;
        cancel_transfer();
        return send_abort(index, sub, abort::ToggleBit, out);
    }
    send_upload_segment(out);
}

void CoeServer::send_upload_segment(ecat::MailboxSender& out) {
    const std::size_t max = std::max(out.max_payload(), kSdoFrame);
    const std::size_t remaining = xfer_.size - xfer_.done;
    const std::size_t n = std::min(remaining, max - kSegmentHead);
    const bool last = n == remaining;
    const std::size_t frame = std::max(kSegmentHead + n, kSdoFrame);
    uint8_t* p = tx(frame);
    wire::put_coe_header(p, wire::Service::SdoResponse);
    uint8_t c = static_cast<uint8_t>(xfer_.toggle && !config_.faults.upload_toggle_stuck ? 0x10 : 0x00);
    if (n < 7) c = static_cast<uint8_t>(c | ((7 - n) << 1));
    if (last) c |= kCmdLastSegment;
    p[2] = c;
    std::memcpy(p + kSegmentHead, data_.data() + xfer_.done, n);
    xfer_.done += n;
    xfer_.toggle ^= 1;
    xfer_.stamp_pending = true;
    if (last) cancel_transfer();
    send(std::span<const uint8_t>(p, frame), out);
}

// ---- Download -------------------------------------------------------------------------------------------

void CoeServer::download_initiate(std::span<const uint8_t> sdo, ecat::MailboxSender& out) {
    const uint8_t cmd = sdo[0];
    const uint16_t index = wire::get16(sdo, 1);
    const uint8_t sub = sdo[3];
    bool ca = (cmd & kCmdCompleteAccess) != 0;
    if (config_.faults.download_abort_command) abort_command_ = cmd;
    if (ca && !config_.complete_access) return send_abort(index, sub, abort::CompleteAccessUnsupported, out);
    const od::Object* obj = dict_.find(index);
    if (obj == nullptr)
        return send_abort(index, sub,
                          config_.faults.abort_missing_object ? abort::NoSubindex : abort::NoObject, out);
    const bool whole = ca && obj->code != od::ObjectCode::Var;
    std::size_t capacity = 0;
    if (whole) {
        if (sub > 1) return send_abort(index, sub, abort::UnsupportedAccess, out);
        capacity = ca::image_size(*obj, sub, obj->max_subindex());
    } else {
        const od::Entry* e = dict_.find(index, sub);
        if (e == nullptr) return send_abort(index, sub, abort::NoSubindex, out);
        if (!writable_at_all(*e)) {
            if (config_.faults.read_only_write_confirmed) {
                abort_command_ = 0x80;
                return confirm_download(index, sub, out);
            }
            return send_abort(index, sub, abort::ReadOnly, out);
        }
        if (!e->writable(write_state(index)) || pdo_locked(index))
            return send_abort(index, sub, abort::WrongState, out);
        capacity = e->byte_size();
    }
    if (data_.size() < capacity) data_.resize(capacity);

    xfer_ = Transfer{};
    xfer_.index = index;
    xfer_.sub = sub;
    xfer_.complete_access = whole;

    if (cmd & kCmdExpedited) {
        std::size_t n = 4;
        if (cmd & kCmdSizeIndicated)
            n = 4 - ((cmd >> 2) & 3);
        else if (!whole)
            n = std::min<std::size_t>(capacity, 4);  // size not indicated: the entry's own size
        if (n > capacity) {
            cancel_transfer();
            return send_abort(index, sub, abort::LengthTooHigh, out);
        }
        std::memcpy(data_.data(), sdo.data() + 4, n);
        xfer_.done = n;
    } else {
        if (sdo.size() < 8) {
            cancel_transfer();
            return send_abort(index, sub, abort::LengthTooLow, out);
        }
        // The Complete Size field is part of every normal initiate, whatever the size indicator says. With
        // s = 0 a master may still fill it (KickCAT sends 5..n bytes as 0x20/0x30 + Complete Size + data):
        // a non-zero Complete Size is honoured as if s were set (SOES reads it regardless of s). Only s = 0
        // with Complete Size 0 leaves the size open, bounded by the entry (see docs/decisions/coe.md).
        const uint32_t complete_size = wire::get32(sdo, 4);
        xfer_.size_known = (cmd & kCmdSizeIndicated) != 0 || complete_size != 0;
        xfer_.size = xfer_.size_known ? complete_size : capacity;
        if (xfer_.size > capacity) {
            cancel_transfer();
            return send_abort(index, sub, abort::LengthTooHigh, out);
        }
        const std::size_t n = std::min(sdo.size() - 8, xfer_.size);
        std::memcpy(data_.data(), sdo.data() + 8, n);
        xfer_.done = n;
        if (!xfer_.size_known || n < xfer_.size) {
            // The rest follows in download segments.
            xfer_.kind = Transfer::Download;
            xfer_.toggle = 0;
            xfer_.stamp_pending = true;
        }
    }

    if (xfer_.kind != Transfer::Download) {
        uint32_t code = commit_download();
        cancel_transfer();
        if (code != 0) return send_abort(index, sub, code, out);
    }
    abort_command_ = 0x80;
    uint8_t* p = tx(kSdoFrame);
    wire::put_coe_header(p, wire::Service::SdoResponse);
    p[2] = static_cast<uint8_t>(0x60 | (ca ? kCmdCompleteAccess : 0));
    wire::put16(p + 3, index);
    p[5] = sub;
    send(std::span<const uint8_t>(p, kSdoFrame), out);
}

void CoeServer::download_segment(std::span<const uint8_t> sdo, ecat::MailboxSender& out) {
    const uint8_t cmd = sdo[0];
    if (config_.faults.download_abort_command) abort_command_ = cmd;
    if (xfer_.kind != Transfer::Download) {
        uint16_t index = xfer_.index;
        uint8_t sub = xfer_.sub;
        cancel_transfer();
        return send_abort(index, sub, abort::UnknownCommand, out);
    }
    const uint16_t index = xfer_.index;
    const uint8_t sub = xfer_.sub;
    const uint8_t toggle = (cmd & 0x10) ? 1 : 0;
    if (toggle != xfer_.toggle && !config_.faults.download_toggle_unchecked) {
        cancel_transfer();
        return send_abort(index, sub, abort::ToggleBit, out);
    }
    std::size_t n = sdo.size() - 1;
    if (n == 7) n -= (cmd >> 1) & 7;  // a short segment is padded to 7 bytes and says how many are unused
    if (xfer_.done + n > xfer_.size) {
        cancel_transfer();
        return send_abort(index, sub, abort::LengthTooHigh, out);
    }
    std::memcpy(data_.data() + xfer_.done, sdo.data() + 1, n);
    xfer_.done += n;
    xfer_.toggle ^= 1;
    xfer_.stamp_pending = true;
    if (cmd & kCmdLastSegment) {
        uint32_t code = 0;
        if (xfer_.size_known && xfer_.done < xfer_.size)
            code = abort::LengthTooLow;
        else
            code = commit_download();
        cancel_transfer();
        if (code != 0) return send_abort(index, sub, code, out);
    }
    abort_command_ = 0x80;
    uint8_t* p = tx(kSdoFrame);
    wire::put_coe_header(p, wire::Service::SdoResponse);
    p[2] = static_cast<uint8_t>(0x20 | (toggle ? 0x10 : 0));
    send(std::span<const uint8_t>(p, kSdoFrame), out);
}

uint32_t CoeServer::commit_download() {
    if (pdo_locked(xfer_.index)) return abort::WrongState;
    std::span<const uint8_t> value(data_.data(), xfer_.done);
    od::Status st;
    if (xfer_.complete_access) {
        const od::Object* obj = dict_.find(xfer_.index);
        if (obj == nullptr) return abort::NoObject;
        st = ca::download(dict_, *obj, xfer_.sub, write_state(xfer_.index), value, rollback_, scratch_);
    } else {
        st = dict_.write(xfer_.index, xfer_.sub, write_state(xfer_.index), value);
    }
    if (config_.faults.value_range_unchecked &&
        (st == od::Status::ValueTooHigh || st == od::Status::ValueTooLow))
        return 0;  // confirmed, although the value was not taken
    return abort_code(st);
}

// ---- Time and state -------------------------------------------------------------------------------------

void CoeServer::poll(uint64_t now_ns, ecat::MailboxSender& out) {
    now_ns_ = now_ns;
    if (xfer_.kind != Transfer::None) {
        if (xfer_.stamp_pending) {
            xfer_.stamp_ns = now_ns;
            xfer_.stamp_pending = false;
        } else if (now_ns - xfer_.stamp_ns > config_.transfer_timeout_ns) {
            uint16_t index = xfer_.index;
            uint8_t sub = xfer_.sub;
            cancel_transfer();
            send_abort(index, sub, abort::Timeout, out);
        }
    }
    if (held_len_ > 0) {
        if (!out.send(held_type_, std::span<const uint8_t>(held_.data(), held_len_))) return;
        held_len_ = 0;
    }
    if (info_.active) {
        pump_info(out);
        if (info_.active) return;
    }
    // Emergencies go out when no answer is waiting, so they never split a fragmented SDO info reply.
    if (!available(state())) return;
    while (!emergency_.empty()) {
        const auto& m = emergency_.front();
        if (!out.send(ecat::MailboxType::CoE, m)) return;
        emergency_.pop();
    }
}

void CoeServer::on_state_change(od::AlState /*from*/, od::AlState to) {
    if (!available(to)) {
        // The mailbox stops: nothing in flight survives (emergencies stay queued for the next Pre-Op).
        cancel_transfer();
        info_ = InfoReply{};
        held_len_ = 0;
    }
}

}  // namespace coe
