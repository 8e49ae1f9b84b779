// The soft drive's control socket (see device/control.hpp).
#include "device/control.hpp"

#include <fcntl.h>
#include <grp.h>
#include <pwd.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "device/device.hpp"
#include "esc/wire/al.hpp"
#include "util/lex.hpp"
#include "util/strfmt.hpp"

namespace device {

namespace {

bool level(std::string_view s, bool& out) {
    if (s == "on" || s == "1" || s == "high" || s == "true") return out = true, true;
    if (s == "off" || s == "0" || s == "low" || s == "false") return out = false, true;
    return false;
}

// A position in increments: any finite number (the environment compares it with the actual position).
bool number(const util::Word& w, double& out) {
    return util::parse_number(w.text, out) == util::NumberError::None;
}

// Is a socket bound at path (someone would receive what is sent there)? A datagram connect() succeeds on a
// bound datagram socket and fails with ECONNREFUSED on a stale file; anything else counts as live.
bool live_socket(const sockaddr_un& addr) {
    const int probe = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (probe < 0) return true;
    const int rc = ::connect(probe, reinterpret_cast<const sockaddr*>(&addr), sizeof addr);
    const int err = errno;
    ::close(probe);
    return rc == 0 || err != ECONNREFUSED;
}

bool in_group(uid_t uid, gid_t gid, gid_t group) {
    if (gid == group) return true;
    std::vector<char> buf(16384);
    passwd pw{};
    passwd* found = nullptr;
    if (::getpwuid_r(uid, &pw, buf.data(), buf.size(), &found) != 0 || found == nullptr) return false;
    int n = 64;
    std::vector<gid_t> groups(static_cast<std::size_t>(n));
    if (::getgrouplist(pw.pw_name, pw.pw_gid, groups.data(), &n) < 0) {
        groups.resize(static_cast<std::size_t>(n));
        if (::getgrouplist(pw.pw_name, pw.pw_gid, groups.data(), &n) < 0) return false;
    }
    groups.resize(static_cast<std::size_t>(n));
    return std::find(groups.begin(), groups.end(), group) != groups.end();
}

std::string lower(std::string_view s) {
    std::string r(s);
    for (char& c : r)
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return r;
}

// Text in an answer, which is one line per command: an entry name comes from the ESI (a vendor's file may put
// a line feed, a tab or a quote in it: "ud&#10;ok injected" answered a second, forged "ok" line) and a name
// typed may hold "\n" escapes. Written with the lexer's escapes (\" \\ \t \n), other control bytes as \xNN,
// so a quoted name in an answer can be typed back.
std::string escaped(std::string_view s) {
    std::string r;
    r.reserve(s.size());
    for (const char c : s) {
        const auto u = static_cast<unsigned char>(c);
        if (c == '"' || c == '\\')
            r += '\\', r += c;
        else if (c == '\t')
            r += "\\t";
        else if (c == '\n')
            r += "\\n";
        else if (u < 0x20 || u == 0x7F)
            r += util::strprintf("\\x%02X", static_cast<unsigned>(u));
        else
            r += c;
    }
    return r;
}

std::string where(uint16_t index, uint8_t sub) {
    char b[16];
    std::snprintf(b, sizeof b, "0x%04X:%02X", static_cast<unsigned>(index), static_cast<unsigned>(sub));
    return b;
}

// An entry named on the command line: index:subindex (numbers, 0x for hex: "0x6000:1"), or a name: the
// entry's name, or "<object name>/<entry name>" (any case). Names are looked up first among the entries
// mapped for process data, then in the whole dictionary; a name that fits several entries is an error that
// lists them.
struct Found {
    const od::Entry* entry = nullptr;
    std::string error;
};

Found find_entry(const Device& device, od::Dictionary& dict, std::string_view text) {
    Found f;
    if (const std::size_t colon = text.find(':'); colon != std::string_view::npos) {
        uint16_t index = 0;
        uint8_t sub = 0;
        if (util::parse_number(text.substr(0, colon), index) == util::NumberError::None &&
            util::parse_number(text.substr(colon + 1), sub) == util::NumberError::None) {
            f.entry = dict.find(index, sub);
            if (f.entry == nullptr) f.error = "no entry " + where(index, sub);
            return f;
        }
    }
    const std::string want = lower(text);
    auto matches = [&](const od::Entry& e) {
        if (lower(e.name) == want) return true;
        const od::Object* o = dict.find(e.index);
        return o != nullptr && lower(o->name + "/" + e.name) == want;
    };
    std::vector<const od::Entry*> hits;
    if (const IoModel* io = device.io_model()) {
        for (const auto list : {io->inputs(), io->outputs()})
            for (const IoEntry& m : list)
                if (matches(*m.entry) && std::find(hits.begin(), hits.end(), m.entry) == hits.end())
                    hits.push_back(m.entry);
    }
    if (hits.empty())
        for (const od::Object& o : dict.objects())
            for (const od::Entry& e : o.entries)
                if (matches(e)) hits.push_back(&e);
    if (hits.size() == 1) {
        f.entry = hits.front();
    } else if (hits.empty()) {
        // printf, not "literal" + std::string&& or a literal assigned: GCC 12 at -O3 misjudges those as
        // overlapping copies (-Werror=restrict, GCC bug 105651).
        f.error = util::strprintf("no entry named '%s'", escaped(text).c_str());
    } else {
        std::string list;
        for (std::size_t i = 0; i < hits.size() && i < 8; ++i) {
            if (i) list += ' ';
            list += where(hits[i]->index, hits[i]->subindex);
        }
        f.error = util::strprintf("'%s' names %zu entries (%s%s): give index:subindex", escaped(text).c_str(),
                                  hits.size(), list.c_str(), hits.size() > 8 ? " ..." : "");
    }
    return f;
}

// "0x7000:01 "Output"=1" for each entry of a list.
void list_entries(std::ostringstream& s, const Device& device, std::span<const IoEntry> list) {
    for (const IoEntry& m : list)
        s << ' ' << where(m.entry->index, m.entry->subindex) << " \"" << escaped(m.entry->name)
          << "\"=" << device.value_text(m.entry->index, m.entry->subindex);
}

}  // namespace

ControlSocket::ControlSocket(std::filesystem::path path, gid_t group)
    : path_(std::move(path)), group_(group), buffer_(kMaxDatagram) {
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    const std::string p = path_.string();
    if (p.empty() || p.size() >= sizeof addr.sun_path)
        throw std::runtime_error("control socket path '" + p + "' is empty or too long");
    std::memcpy(addr.sun_path, p.c_str(), p.size() + 1);
    auto fail = [this, &p](const std::string& why) {
        for (int* fd : {&fd_, &event_, &sock_})
            if (*fd >= 0) ::close(*fd), *fd = -1;
        throw std::runtime_error("control socket '" + p + "': " + why);
    };
    // What is at the path already: only a stale socket of this user is replaced.
    struct stat st {};
    if (::lstat(p.c_str(), &st) == 0) {
        if (!S_ISSOCK(st.st_mode)) fail("the path exists and is not a socket; it is left alone");
        if (live_socket(addr))
            fail("a socket in use (another program's, or another control socket) is there; it is left alone");
        if (st.st_uid != ::geteuid())
            fail("a stale socket of another user (uid " + std::to_string(st.st_uid) +
                 ") is there; it is left alone");
        if (::unlink(p.c_str()) != 0)
            fail(std::string("cannot remove the stale socket: ") + std::strerror(errno));
    } else if (errno != ENOENT) {
        fail(std::strerror(errno));
    }
    sock_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (sock_ < 0) fail(std::strerror(errno));
    const int one = 1;
    if (::setsockopt(sock_, SOL_SOCKET, SO_PASSCRED, &one, sizeof one) != 0) fail(std::strerror(errno));
    // Mode 0600 from the bind on (the umask decides a socket file's mode): no moment in which others may
    // send; then the group's, if one is given.
    const mode_t old_mask = ::umask(0177);
    const int bound = ::bind(sock_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr);
    const int bind_errno = errno;
    ::umask(old_mask);
    if (bound != 0) fail(std::strerror(bind_errno));
    if (::lstat(p.c_str(), &st) != 0) fail(std::strerror(errno));
    dev_ = st.st_dev;
    ino_ = st.st_ino;
    if (group_ != kNoGroup &&
        // Never following a symbolic link someone may have put in the socket's place meanwhile.
        (::lchown(p.c_str(), static_cast<uid_t>(-1), group_) != 0 ||
         ::fchmodat(AT_FDCWD, p.c_str(), 0660, AT_SYMLINK_NOFOLLOW) != 0)) {
        const int err = errno;
        ::unlink(p.c_str());
        fail(std::string("cannot give the socket to group ") + std::to_string(group_) + ": " +
             std::strerror(err));
    }
    event_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    fd_ = ::epoll_create1(EPOLL_CLOEXEC);
    if (event_ < 0 || fd_ < 0) {
        ::unlink(p.c_str());
        fail(std::strerror(errno));
    }
    for (const int fd : {sock_, event_}) {
        epoll_event ev{};
        ev.events = EPOLLIN;
        ev.data.fd = fd;
        if (::epoll_ctl(fd_, EPOLL_CTL_ADD, fd, &ev) != 0) {
            ::unlink(p.c_str());
            fail(std::strerror(errno));
        }
    }
}

ControlSocket::~ControlSocket() {
    if (sock_ < 0) return;
    // Only the socket this object created: a path taken over since (another program's socket, a file)
    // stays.
    struct stat st {};
    if (::lstat(path_.c_str(), &st) == 0 && S_ISSOCK(st.st_mode) && st.st_dev == dev_ && st.st_ino == ino_)
        ::unlink(path_.c_str());
    for (const int fd : {fd_, event_, sock_})
        if (fd >= 0) ::close(fd);
}

std::string ControlSocket::refuse(uid_t uid, gid_t gid) const {
    if (uid == 0 || uid == ::geteuid()) return {};
    if (group_ != kNoGroup && in_group(uid, gid, group_)) return {};
    return "permission denied: uid " + std::to_string(uid) +
           " may not use this control socket (its owner, root" +
           (group_ != kNoGroup ? " or the control group" : "") + " only)";
}

void ControlSocket::answer(const Pending& p) const {
    if (p.reply.empty() || p.from_len <= sizeof(sa_family_t)) return;
    (void)::sendto(sock_, p.reply.data(), p.reply.size(), MSG_DONTWAIT | MSG_NOSIGNAL,
                   reinterpret_cast<const sockaddr*>(&p.from), p.from_len);
}

bool ControlSocket::receive() {
    Pending p;
    iovec iov{buffer_.data(), buffer_.size()};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(ucred))];
    msghdr m{};
    m.msg_name = &p.from;
    m.msg_namelen = sizeof p.from;
    m.msg_iov = &iov;
    m.msg_iovlen = 1;
    m.msg_control = control;
    m.msg_controllen = sizeof control;
    const ssize_t n = ::recvmsg(sock_, &m, MSG_DONTWAIT | MSG_CMSG_CLOEXEC);
    if (n < 0) return false;  // EAGAIN: drained (other errors: nothing more to read either)
    p.from_len = m.msg_namelen;
    const ucred* cred = nullptr;
    for (cmsghdr* c = CMSG_FIRSTHDR(&m); c != nullptr; c = CMSG_NXTHDR(&m, c))
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_CREDENTIALS &&
            c->cmsg_len >= CMSG_LEN(sizeof(ucred)))
            cred = reinterpret_cast<const ucred*>(CMSG_DATA(c));
    std::string refused =
        cred == nullptr ? "permission denied: no sender credentials" : refuse(cred->uid, cred->gid);
    if (refused.empty() && (m.msg_flags & MSG_TRUNC) != 0)
        refused = "datagram longer than " + std::to_string(kMaxDatagram) +
                  " bytes: refused whole, nothing of it executed (send fewer lines per datagram)";
    if (!refused.empty()) {
        p.reply = "error: " + refused + '\n';
        answer(p);
        return true;
    }
    p.text.assign(buffer_.data(), static_cast<std::size_t>(n));
    pending_ = std::move(p);
    return true;
}

void ControlSocket::set_busy(bool busy) {
    if (busy == event_set_) return;
    uint64_t v = 1;
    if (busy)
        (void)!::write(event_, &v, sizeof v);
    else
        (void)!::read(event_, &v, sizeof v);
    event_set_ = busy;
}

void ControlSocket::service(Device& device, uint64_t /*now_ns*/) {
    service([&device](std::string_view line) { return apply(device, line); });
}

void ControlSocket::service(const std::function<std::string(std::string_view)>& apply_line,
                            uint64_t budget_ns) {
    // Frames come first: the runtime handled them before this call, and handles them again before the
    // next, which comes at once while work is left (fd() stays readable). Each datagram received or line
    // applied is work; the budget is checked after each.
    const auto start = std::chrono::steady_clock::now();
    const auto budget = std::chrono::nanoseconds(budget_ns);
    bool worked = false;
    while (!worked || std::chrono::steady_clock::now() - start < budget) {
        if (!pending_) {
            if (!receive()) break;
            worked = !pending_.has_value();  // a refusal answered is work; lines received are not yet
            continue;
        }
        Pending& p = *pending_;
        const std::string_view rest = std::string_view(p.text).substr(p.at);
        const std::size_t nl = rest.find('\n');
        const std::string answer_line = apply_line(rest.substr(0, nl));
        if (!answer_line.empty()) p.reply += answer_line + '\n';
        p.at = nl == std::string_view::npos ? p.text.size() : p.at + nl + 1;
        worked = true;
        if (p.at == p.text.size()) {
            answer(p);
            pending_.reset();
        }
    }
    set_busy(pending_.has_value());
}

std::string ControlSocket::apply(Device& device, std::string_view line) {
    std::vector<util::Word> w;
    try {
        w = util::split(line);
    } catch (const util::LexError& e) {
        return std::string("error: ") + e.what();
    }
    if (w.empty()) return {};
    const std::string& cmd = w[0].text;
    EnvironmentOptions env = device.environment();
    const bool none = w.size() == 2 && w[1].text == "none";
    double a = 0, b = 0;
    bool on = false;
    const bool drive_command = cmd == "input" || cmd == "sto" || cmd == "limit-neg" || cmd == "limit-pos" ||
                               cmd == "home" || cmd == "stops";
    if (drive_command && !device.has_drive())
        return "error: '" + escaped(cmd) + "' acts on a drive; this device has none (get, set, status)";
    if (cmd == "input") {
        int pin = 0;
        if (w.size() != 3 || util::parse_number(w[1].text, pin, 1, 6) != util::NumberError::None ||
            !level(w[2].text, on) || !device.set_input(pin, on))
            return "error: usage: input <1..6> on|off";
        return "ok input " + std::to_string(pin) + (on ? " on" : " off");
    }
    if (cmd == "sto") {
        if (w.size() != 2 || !level(w[1].text, on)) return "error: usage: sto on|off";
        device.set_input(5, on);
        device.set_input(6, on);
        return std::string("ok sto ") + (on ? "on" : "off");
    }
    if (cmd == "limit-neg" || cmd == "limit-pos") {
        double& field = cmd == "limit-neg" ? env.negative_limit : env.positive_limit;
        if (none)
            field = EnvironmentOptions::kNone;
        else if (w.size() == 2 && number(w[1], a))
            field = a;
        else
            return "error: usage: " + std::string(cmd) + " <increments>|none";
        device.set_environment(env);
        return "ok " + std::string(cmd);
    }
    if (cmd == "home" || cmd == "stops") {
        double& lo = cmd == "home" ? env.home_from : env.stop_lo;
        double& hi = cmd == "home" ? env.home_to : env.stop_hi;
        if (none) {
            lo = hi = EnvironmentOptions::kNone;
        } else if (w.size() == 3 && number(w[1], a) && number(w[2], b) && a <= b) {
            lo = a, hi = b;
        } else {
            return "error: usage: " + std::string(cmd) + " <from> <to>|none (from <= to)";
        }
        device.set_environment(env);
        return "ok " + std::string(cmd);
    }
    if (cmd == "status" && w.size() == 1) {
        od::Dictionary& d = device.dictionary();
        std::ostringstream s;
        s << "ok state " << esc::al_state_name(device.stack().state());
        if (const IoModel* io = device.io_model()) {
            // A device without application: its process data by entry, with values.
            s << " outputs";
            list_entries(s, device, io->outputs());
            s << " inputs";
            list_entries(s, device, io->inputs());
            return s.str();
        }
        if (d.find(0x6041, 0) != nullptr)
            s << " statusword 0x" << std::hex << d.get<uint16_t>(0x6041, 0) << std::dec;
        if (d.find(0x6064, 0) != nullptr) s << " position " << d.get<int32_t>(0x6064, 0);
        if (d.find(0x603F, 0) != nullptr) s << " error 0x" << std::hex << d.get<uint16_t>(0x603F, 0);
        return s.str();
    }
    if (cmd == "get") {
        if (w.size() != 2) return "error: usage: get <entry name>|<index>:<subindex>";
        const Found f = find_entry(device, device.dictionary(), w[1].text);
        if (f.entry == nullptr) return "error: " + f.error;
        return "ok " + where(f.entry->index, f.entry->subindex) + " \"" + escaped(f.entry->name) +
               "\"=" + device.value_text(f.entry->index, f.entry->subindex);
    }
    if (cmd == "set") {
        if (w.size() != 3) return "error: usage: set <entry name>|<index>:<subindex> <value>";
        const Found f = find_entry(device, device.dictionary(), w[1].text);
        if (f.entry == nullptr) return "error: " + f.error;
        const uint16_t index = f.entry->index;
        const uint8_t sub = f.entry->subindex;
        if (const std::string error = device.set_value(index, sub, w[2].text); !error.empty())
            return "error: " + error;
        return "ok " + where(index, sub) + "=" + device.value_text(index, sub);
    }
    return "error: unknown command '" + escaped(cmd) +
           "' (input, sto, limit-neg, limit-pos, home, stops, status, get, set)";
}

}  // namespace device
