// The soft drive's control socket (see device/control.hpp).
#include "device/control.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "device/device.hpp"

namespace device {

namespace {

constexpr std::size_t kMaxDatagram = 4096;

std::vector<std::string_view> words(std::string_view line) {
    std::vector<std::string_view> out;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r'))
            ++i;
        std::size_t j = i;
        while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r')
            ++j;
        if (j > i) out.push_back(line.substr(i, j - i));
        i = j;
    }
    return out;
}

bool number(std::string_view s, double& out) {
    const std::string text(s);
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || errno != 0 || !std::isfinite(v)) return false;
    out = v;
    return true;
}

bool level(std::string_view s, bool& out) {
    if (s == "on" || s == "1" || s == "high" || s == "true") return out = true, true;
    if (s == "off" || s == "0" || s == "low" || s == "false") return out = false, true;
    return false;
}

const char* state_name(od::AlState s) {
    switch (s) {
        case od::AlState::Init:
            return "INIT";
        case od::AlState::PreOp:
            return "PREOP";
        case od::AlState::Boot:
            return "BOOT";
        case od::AlState::SafeOp:
            return "SAFEOP";
        case od::AlState::Op:
            return "OP";
    }
    return "?";
}

}  // namespace

ControlSocket::ControlSocket(std::filesystem::path path) : path_(std::move(path)), buffer_(kMaxDatagram) {
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    const std::string p = path_.string();
    if (p.empty() || p.size() >= sizeof addr.sun_path)
        throw std::runtime_error("control socket path '" + p + "' is empty or too long");
    std::memcpy(addr.sun_path, p.c_str(), p.size() + 1);
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd_ < 0) throw std::runtime_error(std::string("control socket: ") + std::strerror(errno));
    std::error_code ec;
    if (std::filesystem::is_socket(path_, ec)) std::filesystem::remove(path_, ec);
    if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
        const int err = errno;
        ::close(fd_);
        fd_ = -1;
        throw std::runtime_error("control socket '" + p + "': " + std::strerror(err));
    }
}

ControlSocket::~ControlSocket() {
    if (fd_ >= 0) {
        ::close(fd_);
        std::error_code ec;
        std::filesystem::remove(path_, ec);
    }
}

void ControlSocket::service(Device& device, uint64_t /*now_ns*/) {
    service([&device](std::string_view line) { return apply(device, line); });
}

void ControlSocket::service(const std::function<std::string(std::string_view)>& apply_line) {
    for (int i = 0; i < 64; ++i) {  // bounded: a flood cannot starve the event loop
        sockaddr_un from{};
        socklen_t from_len = sizeof from;
        const ssize_t n =
            ::recvfrom(fd_, buffer_.data(), buffer_.size(), 0, reinterpret_cast<sockaddr*>(&from), &from_len);
        if (n < 0) return;  // EAGAIN: drained (other errors: nothing more to read either)
        std::string reply;
        std::string_view text(buffer_.data(), static_cast<std::size_t>(n));
        while (!text.empty()) {
            const std::size_t nl = text.find('\n');
            const std::string answer = apply_line(text.substr(0, nl));
            if (!answer.empty()) reply += answer + '\n';
            text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
        }
        if (!reply.empty() && from_len > sizeof(sa_family_t))
            (void)::sendto(fd_, reply.data(), reply.size(), MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&from),
                           from_len);
    }
}

std::string ControlSocket::apply(Device& device, std::string_view line) {
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    const auto w = words(line);
    if (w.empty()) return {};
    const std::string_view cmd = w[0];
    EnvironmentOptions env = device.environment();
    const bool none = w.size() == 2 && w[1] == "none";
    double a = 0, b = 0;
    bool on = false;
    if (cmd == "input") {
        double pin = 0;
        if (w.size() != 3 || !number(w[1], pin) || !level(w[2], on) || pin != std::floor(pin) ||
            !device.set_input(static_cast<int>(pin), on))
            return "error: usage: input <1..6> on|off";
        return "ok input " + std::string(w[1]) + (on ? " on" : " off");
    }
    if (cmd == "sto") {
        if (w.size() != 2 || !level(w[1], on)) return "error: usage: sto on|off";
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
        s << "ok state " << state_name(device.stack().state()) << " statusword 0x" << std::hex
          << d.get<uint16_t>(0x6041, 0) << std::dec << " position " << d.get<int32_t>(0x6064, 0)
          << " error 0x" << std::hex << d.get<uint16_t>(0x603F, 0);
        return s.str();
    }
    return "error: unknown command '" + std::string(cmd) +
           "' (input, sto, limit-neg, limit-pos, home, stops, status)";
}

}  // namespace device
