// SDO information service (CoE service 8, ETG.1000.6 SDO Information).
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <string_view>

#include "coe/abort.hpp"
#include "coe/sdo_info.hpp"
#include "coe/sdo_server.hpp"
#include "wire.hpp"

namespace coe {

namespace {

// SDO information opcodes and value info bits: the CoE vocabulary (coe/wire/sdo.hpp).
constexpr uint8_t kOpOdListReq = info::kOdListReq;
constexpr uint8_t kOpOdListResp = info::kOdListResp;
constexpr uint8_t kOpObjDescReq = info::kObjDescReq;
constexpr uint8_t kOpObjDescResp = info::kObjDescResp;
constexpr uint8_t kOpEntryDescReq = info::kEntryDescReq;
constexpr uint8_t kOpEntryDescResp = info::kEntryDescResp;
constexpr uint8_t kOpError = info::kError;
using info::kIncomplete;
using info::kValueInfoDefault;
using info::kValueInfoMax;
using info::kValueInfoMin;
using info::kValueInfoUnit;
constexpr std::size_t kInfoHead = info::kHead;

std::size_t value_size(const od::Entry& e) {
    return e.byte_size();
}

void put_le(uint8_t* p, std::size_t n, uint64_t v) {
    for (std::size_t i = 0; i < n && i < 8; ++i)
        p[i] = static_cast<uint8_t>(v >> (8 * i));
}

// A declared number (or, if none, the type's own limit) in the entry's wire format.
void put_number(const od::Entry& e, const od::Number& num, bool maximum, uint8_t* p, std::size_t n) {
    std::memset(p, 0, n);
    if (od::is_string(e.type)) return;
    if (e.type == od::DataType::Real32 || e.type == od::DataType::Real64) {
        double v;
        if (std::holds_alternative<double>(num))
            v = std::get<double>(num);
        else if (std::holds_alternative<int64_t>(num))
            v = static_cast<double>(std::get<int64_t>(num));
        else if (std::holds_alternative<uint64_t>(num))
            v = static_cast<double>(std::get<uint64_t>(num));
        else
            v = e.type == od::DataType::Real32 ? (maximum ? FLT_MAX : -FLT_MAX)
                                               : (maximum ? DBL_MAX : -DBL_MAX);
        if (e.type == od::DataType::Real32 && n >= 4) {
            float f = static_cast<float>(v);
            std::memcpy(p, &f, 4);
        } else if (n >= 8) {
            std::memcpy(p, &v, 8);
        }
        return;
    }
    uint64_t raw;
    if (std::holds_alternative<int64_t>(num)) {
        raw = static_cast<uint64_t>(std::get<int64_t>(num));
    } else if (std::holds_alternative<uint64_t>(num)) {
        raw = std::get<uint64_t>(num);
    } else if (std::holds_alternative<double>(num)) {
        raw = static_cast<uint64_t>(static_cast<int64_t>(std::llround(std::get<double>(num))));
    } else {
        const unsigned bits = std::min<unsigned>(e.bit_length, 64u);
        if (od::is_signed(e.type)) {
            raw = maximum ? (bits >= 64 ? uint64_t{INT64_MAX} : (uint64_t{1} << (bits - 1)) - 1)
                          : (bits >= 64 ? uint64_t{1} << 63 : ~((uint64_t{1} << (bits - 1)) - 1));
        } else {
            raw = maximum ? (bits >= 64 ? ~uint64_t{0} : (uint64_t{1} << bits) - 1) : 0;
        }
    }
    put_le(p, n, raw);
}

}  // namespace

bool in_od_list(const od::Object& obj, uint16_t list_type) {
    uint16_t flag = 0;
    switch (list_type) {
        case 1:
            return true;
        case 2:
            flag = od::access::RxPdo;
            break;
        case 3:
            flag = od::access::TxPdo;
            break;
        case 4:
            flag = od::access::Backup;
            break;
        case 5:
            flag = od::access::Settings;
            break;
        default:
            return false;
    }
    return std::any_of(obj.entries.begin(), obj.entries.end(),
                       [&](const od::Entry& e) { return e.access & flag; });
}

// CiA 303-2 / ETG.1004 unit encoding: byte 3 prefix (power of ten, signed), byte 2 SI numerator unit,
// byte 1 denominator unit, byte 0 reserved. Units without an SI code (increments, rpm, mNm) give 0.
uint32_t unit_code(std::string_view unit) {
    struct Base {
        std::string_view name;
        uint8_t code;
    };
    static constexpr Base kBase[] = {
        {"m", 0x01},   {"kg", 0x02}, {"s", 0x03},  {"A", 0x04}, {"K", 0x05}, {"rad", 0x10}, {"Hz", 0x20},
        {"N", 0x21},   {"Pa", 0x22}, {"J", 0x23},  {"W", 0x24}, {"C", 0x25}, {"V", 0x26},   {"F", 0x27},
        {"Ohm", 0x28}, {"S", 0x29},  {"Wb", 0x2A}, {"T", 0x2B}, {"H", 0x2C}, {"°C", 0x2D},
    };
    struct Prefix {
        std::string_view name;
        int8_t exp;
    };
    static constexpr Prefix kPrefix[] = {{"", 0},   {"k", 3},  {"M", 6}, {"m", -3},
                                         {"u", -6}, {"µ", -6}, {"n", -9}};
    for (const auto& b : kBase) {
        for (const auto& pre : kPrefix) {
            if (unit.size() == pre.name.size() + b.name.size() &&
                unit.substr(0, pre.name.size()) == pre.name && unit.substr(pre.name.size()) == b.name) {
                return (static_cast<uint32_t>(static_cast<uint8_t>(pre.exp)) << 24) |
                       (static_cast<uint32_t>(b.code) << 16);
            }
        }
    }
    return 0;
}

void CoeServer::handle_info(std::span<const uint8_t> body, ecat::MailboxSender& out) {
    const uint8_t opcode = body[0] & 0x7F;
    auto req = body.subspan(4);
    switch (opcode) {
        case kOpOdListReq:
            if (req.size() < 2) return send_mailbox_error(ecat::MailboxError::SizeTooShort, out);
            return info_od_list(wire::get16(req, 0), out);
        case kOpObjDescReq:
            if (req.size() < 2) return send_mailbox_error(ecat::MailboxError::SizeTooShort, out);
            return info_object(wire::get16(req, 0), out);
        case kOpEntryDescReq:
            if (req.size() < 4) return send_mailbox_error(ecat::MailboxError::SizeTooShort, out);
            return info_entry(wire::get16(req, 0), req[2], req[3], out);
        default:
            return info_error(abort::UnknownCommand, out);
    }
}

void CoeServer::info_error(uint32_t code, ecat::MailboxSender& out) {
    uint8_t* p = tx(kInfoHead + 4);
    wire::put_coe_header(p, wire::Service::SdoInfo);
    p[2] = kOpError;
    wire::put32(p + kInfoHead, code);
    send(std::span<const uint8_t>(p, kInfoHead + (config_.faults.info_error_short ? 2 : 4)), out);
}

void CoeServer::info_od_list(uint16_t list_type, ecat::MailboxSender& out) {
    if (list_type > 5) return info_error(abort::ValueRange, out);
    const auto objects = dict_.objects();
    if (info_buf_.size() < 2 + 2 * std::max<std::size_t>(objects.size(), 5))
        info_buf_.resize(2 + 2 * std::max<std::size_t>(objects.size(), 5));
    uint8_t* p = info_buf_.data();
    wire::put16(p, list_type);
    std::size_t len = 2;
    if (list_type == 0) {
        for (uint16_t t = 1; t <= 5; ++t) {
            uint16_t n = 0;
            for (const auto& obj : objects)
                if (in_od_list(obj, t)) ++n;
            wire::put16(p + len, n);
            len += 2;
        }
    } else {
        for (const auto& obj : objects) {
            if (!in_od_list(obj, list_type)) continue;
            wire::put16(p + len, obj.index);
            len += 2;
        }
    }
    start_info_reply(kOpOdListResp, len, 2, out);
}

void CoeServer::info_object(uint16_t index, ecat::MailboxSender& out) {
    const od::Object* obj = dict_.find(index);
    if (obj == nullptr) return info_error(abort::NoObject, out);
    const std::size_t len = 6 + obj->name.size();
    if (info_buf_.size() < len) info_buf_.resize(len);
    uint8_t* p = info_buf_.data();
    wire::put16(p, index);
    wire::put16(p + 2, static_cast<uint16_t>(obj->type));
    p[4] = obj->max_subindex();
    p[5] = static_cast<uint8_t>(obj->code);
    std::memcpy(p + 6, obj->name.data(), obj->name.size());
    start_info_reply(kOpObjDescResp, len, 1, out);
}

void CoeServer::info_entry(uint16_t index, uint8_t sub, uint8_t value_info, ecat::MailboxSender& out) {
    const od::Object* obj = dict_.find(index);
    if (obj == nullptr) return info_error(abort::NoObject, out);
    const od::Entry* e = obj->entry(sub);
    if (e == nullptr) return info_error(abort::NoSubindex, out);
    const std::string& name = e->name.empty() ? obj->name : e->name;
    const std::size_t vsize = value_size(*e);
    const std::size_t len = 10 + 4 + 3 * vsize + name.size();
    if (info_buf_.size() < len) info_buf_.resize(len);
    uint8_t* p = info_buf_.data();
    wire::put16(p, index);
    p[2] = sub;
    p[3] = value_info;
    wire::put16(p + 4, sub > 0 && config_.faults.info_entry_wrong_type ? uint16_t{0x0005}
                                                                       : static_cast<uint16_t>(e->type));
    wire::put16(p + 6, e->bit_length);
    wire::put16(p + 8, e->access);
    std::size_t at = 10;
    if (value_info & kValueInfoUnit) {
        wire::put32(p + at, unit_code(e->unit));
        at += 4;
    }
    if (value_info & kValueInfoDefault) {
        std::memset(p + at, 0, vsize);
        auto def = dict_.default_raw(index, sub);
        std::memcpy(p + at, def.data(), std::min(def.size(), vsize));
        at += vsize;
    }
    if (value_info & kValueInfoMin) {
        put_number(*e, e->minimum, false, p + at, vsize);
        at += vsize;
    }
    if (value_info & kValueInfoMax) {
        put_number(*e, e->maximum, true, p + at, vsize);
        at += vsize;
    }
    std::memcpy(p + at, name.data(), name.size());
    at += name.size();
    start_info_reply(kOpEntryDescResp, at, 1, out);
}

void CoeServer::start_info_reply(uint8_t opcode, std::size_t length, std::size_t item,
                                 ecat::MailboxSender& out) {
    const std::size_t max = std::max(out.max_payload(), kInfoHead + item);
    std::size_t chunk = (max - kInfoHead) / item * item;
    info_ = InfoReply{};
    info_.active = true;
    info_.opcode = opcode;
    info_.length = length;
    info_.chunk = chunk;
    info_.fragments_left = static_cast<uint16_t>(length == 0 ? 0 : (length + chunk - 1) / chunk - 1);
    pump_info(out);
}

void CoeServer::pump_info(ecat::MailboxSender& out) {
    while (info_.active && held_len_ == 0) {
        const std::size_t n = std::min(info_.chunk, info_.length - info_.sent);
        uint8_t* p = tx(kInfoHead + n);
        wire::put_coe_header(p, wire::Service::SdoInfo);
        p[2] = static_cast<uint8_t>(info_.opcode | (info_.fragments_left > 0 ? kIncomplete : 0));
        wire::put16(p + 4, info_.fragments_left);
        std::memcpy(p + kInfoHead, info_buf_.data() + info_.sent, n);
        if (!out.send(ecat::MailboxType::CoE, std::span<const uint8_t>(p, kInfoHead + n))) return;
        info_.sent += n;
        if (info_.fragments_left == 0) {
            info_.active = false;
        } else {
            --info_.fragments_left;
        }
    }
}

}  // namespace coe
