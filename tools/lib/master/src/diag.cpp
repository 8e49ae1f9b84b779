#include "master/diag.hpp"

#include <cstdio>
#include <ctime>
#include <iomanip>
#include <sstream>

#include "util/le.hpp"
#include "util/strfmt.hpp"

namespace master {

namespace {
using util::get16;
using util::get32;
using util::get64;

constexpr std::size_t kHead = 16;

uint64_t le_n(std::span<const uint8_t> d) {
    uint64_t v = 0;
    for (std::size_t i = d.size(); i-- > 0;)
        v = (v << 8) | d[i];
    return v;
}

bool is_signed(uint16_t t) {
    return t == 0x0002 || t == 0x0003 || t == 0x0004 || t == 0x0010 || (t >= 0x0012 && t <= 0x0015);
}

}  // namespace

std::size_t diag_value_size(uint16_t t) {
    switch (t) {
        case 0x0001:  // BOOLEAN
        case 0x0002:  // INTEGER8
        case 0x0005:  // UNSIGNED8
            return 1;
        case 0x0003:  // INTEGER16
        case 0x0006:  // UNSIGNED16
            return 2;
        case 0x0010:  // INTEGER24
        case 0x0016:  // UNSIGNED24
            return 3;
        case 0x0004:  // INTEGER32
        case 0x0007:  // UNSIGNED32
        case 0x0008:  // REAL32
            return 4;
        case 0x0012:  // INTEGER40
        case 0x0018:  // UNSIGNED40
            return 5;
        case 0x000C:  // TIME_OF_DAY
        case 0x000D:  // TIME_DIFFERENCE
        case 0x0013:  // INTEGER48
        case 0x0019:  // UNSIGNED48
            return 6;
        case 0x0014:  // INTEGER56
        case 0x001A:  // UNSIGNED56
            return 7;
        case 0x0011:  // REAL64
        case 0x0015:  // INTEGER64
        case 0x001B:  // UNSIGNED64
            return 8;
        default:
            return 0;
    }
}

std::optional<DiagEntry> decode_diag_message(std::span<const uint8_t> bytes, uint8_t subindex) {
    if (bytes.size() < kHead) return std::nullopt;
    DiagEntry e;
    e.subindex = subindex;
    e.code = get32(bytes.data());
    const uint16_t flags = get16(bytes.data() + 4);
    e.type = static_cast<uint8_t>(flags & 0x0F);
    e.local_time = (flags & 0x10) != 0;
    e.text_id = get16(bytes.data() + 6);
    e.timestamp_ns = get64(bytes.data() + 8);
    // An erased slot (all zero) is no message.
    bool all_zero = true;
    for (uint8_t b : bytes.first(kHead))
        all_zero = all_zero && b == 0;
    if (all_zero) return std::nullopt;
    const unsigned count = flags >> 8;
    std::size_t at = kHead;
    for (unsigned i = 0; i < count; ++i) {
        if (at + 2 > bytes.size()) {
            e.truncated = true;
            break;
        }
        DiagParameter p;
        p.flags = get16(bytes.data() + at);
        const std::size_t len = p.kind() == 0 ? diag_value_size(p.flags & 0x0FFF) : (p.flags & 0x0FFFu);
        if ((p.kind() == 0 && len == 0) || p.kind() > 3 || at + 2 + len > bytes.size()) {
            e.truncated = true;  // unknown data type or kind: the rest cannot be delimited
            break;
        }
        p.data.assign(bytes.begin() + static_cast<std::ptrdiff_t>(at + 2),
                      bytes.begin() + static_cast<std::ptrdiff_t>(at + 2 + len));
        e.params.push_back(std::move(p));
        at += 2 + len;
    }
    return e;
}

std::vector<uint8_t> diag_message_order(const DiagHeader& h, bool newest_first, bool only_new) {
    std::vector<uint8_t> out;
    const unsigned max = h.max_messages;
    if (max == 0 || h.newest < kDiagFirstMessage || h.newest >= kDiagFirstMessage + max) return out;
    const bool acked_valid = h.acknowledged >= kDiagFirstMessage && h.acknowledged < kDiagFirstMessage + max;
    // Walk backwards from the newest; stop at the acknowledged one when only new ones are asked for.
    unsigned pos = h.newest - kDiagFirstMessage;
    for (unsigned i = 0; i < max; ++i) {
        const auto sub = static_cast<uint8_t>(kDiagFirstMessage + pos);
        if (only_new && acked_valid && sub == h.acknowledged) break;
        out.push_back(sub);
        pos = (pos + max - 1) % max;
    }
    if (!newest_first) {
        for (std::size_t i = 0, j = out.size(); i + 1 < j; ++i, --j)
            std::swap(out[i], out[j - 1]);
    }
    return out;
}

std::string_view diag_type_name(uint8_t type) {
    switch (type) {
        case 0:
            return "info";
        case 1:
            return "warning";
        case 2:
            return "error";
        default:
            return "unknown";
    }
}

std::string format_diag_param(const DiagParameter& p) {
    std::string s;
    switch (p.kind()) {
        case 0: {
            const uint16_t t = p.flags & 0x0FFF;
            const uint64_t v = le_n(p.data);
            if (is_signed(t)) {
                const unsigned bits = static_cast<unsigned>(p.data.size() * 8);
                int64_t sv = static_cast<int64_t>(v);
                if (bits < 64 && (v >> (bits - 1)) & 1) sv = static_cast<int64_t>(v | (~uint64_t{0} << bits));
                return util::strprintf("%lld", static_cast<long long>(sv));
            }
            return util::strprintf("0x%0*llx (%llu)", static_cast<int>(p.data.size() * 2),
                                   static_cast<unsigned long long>(v), static_cast<unsigned long long>(v));
        }
        case 1:
            s = "bytes";
            for (uint8_t x : p.data)
                s += util::strprintf(" %02x", x);
            return s;
        case 2:
            s = "\"";
            for (uint8_t x : p.data) {
                if (x == 0) break;
                s += (x >= 0x20 && x < 0x7F) ? static_cast<char>(x) : '?';
            }
            return s + "\"";
        case 3:
            s = "\"";
            for (std::size_t i = 0; i + 1 < p.data.size(); i += 2) {
                const uint16_t c = get16(p.data.data() + i);
                if (c == 0) break;
                s += (c >= 0x20 && c < 0x7F) ? static_cast<char>(c) : '?';
            }
            return s + "\"";
        default:
            return "?";
    }
}

std::string_view emergency_class_name(uint16_t code) {
    if (code == 0x0000) return "";
    if ((code & 0xFF00) == 0x8100) return "communication error";
    if ((code & 0xFF00) == 0x8200) return "protocol error";
    switch (code >> 12) {
        case 0x1:
            return "generic error";
        case 0x2:
            return "current error";
        case 0x3:
            return "voltage error";
        case 0x4:
            return "temperature error";
        case 0x5:
            return "device hardware error";
        case 0x6:
            return "device software error";
        case 0x7:
            return "additional modules error";
        case 0x8:
            return "monitoring error";
        case 0x9:
            return "external error";
        case 0xF:
            return (code & 0xFF00) == 0xFF00 ? "device specific error" : "additional functions error";
        default:
            return "error code";
    }
}

std::string diag_text(const DiagEntry& e, ErrorNameLookup lookup, const TextIdLookup& texts) {
    // A text the device gives by id says more than the error it concerns (e.g. "Fault reset refused: cause
    // still present" about a following error): the text first, the error's name after it.
    if (e.text_id != 0 && texts != nullptr) {
        const std::string_view t = texts(e.text_id);
        if (!t.empty()) {
            std::string s(t);
            if (e.from_emergency() && e.emergency_code() != 0 && lookup != nullptr) {
                const std::string_view n = lookup(e.emergency_code());
                if (!n.empty() && n != t) s += " (" + std::string(n) + ")";
            }
            return s;
        }
    }
    if (e.from_emergency()) {
        const uint16_t c = e.emergency_code();
        if (c == 0x0000) return "no error (error reset)";
        if (lookup != nullptr) {
            const std::string_view n = lookup(c);
            if (!n.empty()) return std::string(n);
        }
        return std::string(emergency_class_name(c));
    }
    if (e.text_id != 0) {
        return util::strprintf("text id 0x%04x", e.text_id);
    }
    for (const auto& p : e.params) {
        if (p.kind() == 2 || p.kind() == 3) {
            const std::string quoted = format_diag_param(p);
            return quoted.substr(1, quoted.size() - 2);
        }
    }
    if ((e.code & 0xFFFF) >= 0xE000 && (e.code & 0xFFFF) < 0xE800) return "manufacturer-specific message";
    return "";
}

std::string format_diag_time(uint64_t ns, bool local) {
    const uint64_t total_ms = ns / 1000000u;
    const auto ms = static_cast<unsigned>(total_ms % 1000u);
    const uint64_t total_s = total_ms / 1000u;
    std::ostringstream o;
    o << std::setfill('0');
    // DC system time counts from 2000-01-01 00:00 UTC (ETG.1000.4); a clock set to the wall time (a year or
    // more past its epoch) reads as a date, anything else as the time since the clock started.
    constexpr uint64_t kYear = 365ull * 24 * 3600;
    if (!local && total_s >= kYear) {
        const std::time_t t = static_cast<std::time_t>(total_s + 946684800ull);
        std::tm tm{};
        if (gmtime_r(&t, &tm) != nullptr) {
            o << std::setw(4) << tm.tm_year + 1900 << '-' << std::setw(2) << tm.tm_mon + 1 << '-'
              << std::setw(2) << tm.tm_mday << ' ' << std::setw(2) << tm.tm_hour << ':' << std::setw(2)
              << tm.tm_min << ':' << std::setw(2) << tm.tm_sec << '.' << std::setw(3) << ms << " UTC";
            return o.str();
        }
    }
    const uint64_t days = total_s / 86400u;
    if (days) o << days << "d ";
    o << std::setw(2) << (total_s / 3600u) % 24u << ':' << std::setw(2) << (total_s / 60u) % 60u << ':'
      << std::setw(2) << total_s % 60u << '.' << std::setw(3) << ms;
    return o.str();
}

std::string format_diag_flags(uint16_t flags) {
    std::string s;
    auto add = [&](const char* t) {
        if (!s.empty()) s += ", ";
        s += t;
    };
    if (flags & kDiagFlagEmergency) add("send as emergency");
    if (flags & kDiagFlagNoInfo) add("info not stored");
    if (flags & kDiagFlagNoWarning) add("warnings not stored");
    if (flags & kDiagFlagNoError) add("errors not stored");
    add(flags & kDiagFlagAcknowledgeMode ? "acknowledge mode" : "overwrite mode");
    if (flags & kDiagFlagOverflow) add("overflow");
    if (flags & 0xFFC0) add("reserved bits set");
    return s;
}

std::string format_diag_line(const DiagEntry& e, ErrorNameLookup lookup, const TextIdLookup& texts) {
    std::string s = util::strprintf(
        ":%02u  %s%s  %-7s  0x%08x  ", e.subindex, format_diag_time(e.timestamp_ns, e.local_time).c_str(),
        e.local_time ? " (local)" : "", std::string(diag_type_name(e.type)).c_str(), e.code);
    const std::string text = diag_text(e, lookup, texts);
    s += text;
    std::vector<std::string> shown;
    for (const auto& p : e.params) {
        if (p.kind() == 2 || p.kind() == 3) {
            const std::string quoted = format_diag_param(p);
            const std::string inner = quoted.size() >= 2 ? quoted.substr(1, quoted.size() - 2) : quoted;
            if (!inner.empty() && text.compare(0, inner.size(), inner) == 0) continue;  // said already
        }
        shown.push_back(format_diag_param(p));
    }
    if (!shown.empty() || e.truncated) {
        s += "  [";
        for (std::size_t i = 0; i < shown.size(); ++i) {
            if (i) s += ", ";
            s += shown[i];
        }
        if (e.truncated) s += shown.empty() ? "cut short" : ", cut short";
        s += "]";
    }
    return s;
}

}  // namespace master
