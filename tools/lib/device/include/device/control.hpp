#pragma once
// The run-time control socket of the soft drive: a UNIX datagram socket, read in the runtime's event loop,
// that changes the simulated machine. One command per datagram (several lines allowed):
//
//   input <1..6> on|off       a digital input pin (DigIN1..6; 5/6 are the STO inputs)
//   sto on|off                both STO inputs (on = released, the power stage may run)
//   limit-neg <inc>|none      negative limit switch, active at and below <inc> (raw increments)
//   limit-pos <inc>|none      positive limit switch, active at and above <inc>
//   home <from> <to>|none     home switch, active on [from, to]
//   stops <lo> <hi>|none      mechanical stops
//   status                    AL state, statusword, actual position
//
// A sender with an address of its own (e.g. `socat - UNIX-SENDTO:PATH,bind=/tmp/me`) gets one reply per
// line ("ok ..." or "error: ..."); `echo 'input 4 on' | nc -uU -w0 PATH` works without one.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace device {

class Device;

class ControlSocket {
  public:
    // Creates the socket at path (a stale socket file there is replaced). Throws std::runtime_error.
    explicit ControlSocket(std::filesystem::path path);
    ~ControlSocket();
    ControlSocket(const ControlSocket&) = delete;
    ControlSocket& operator=(const ControlSocket&) = delete;

    int fd() const { return fd_; }
    const std::filesystem::path& path() const { return path_; }
    // Reads every waiting datagram, applies its lines to device, answers senders that have an address.
    void service(Device& device, uint64_t now_ns);
    // The same with another interpreter of the lines (a segment's, device/line.hpp).
    void service(const std::function<std::string(std::string_view)>& apply);

    // Applies one command line; returns the answer ("ok ..." or "error: ..."); "" for an empty line.
    static std::string apply(Device& device, std::string_view line);

  private:
    std::filesystem::path path_;
    int fd_ = -1;
    std::vector<char> buffer_;
};

}  // namespace device
