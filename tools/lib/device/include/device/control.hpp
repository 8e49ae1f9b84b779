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
//   status                    AL state; a drive: statusword, actual position, error code; a device
//                             without application: its mapped outputs and inputs, `0x7000:01 "Output"=1`
//   get <entry>               the value of an entry
//   set <entry> <value>       sets a process-data input (TxPDO-mappable entry); on a device without
//                             application it is held there (device/io_model.hpp)
//
// <entry> is index:subindex (numbers, 0x for hex: 0x6000:1) or a name: the entry's, or
// "<object name>/<entry name>", any case, looked up among the mapped entries first; a name that fits
// several entries is an error listing them. Drive commands (input .. stops) need a device with drive.
//
// A sender with an address of its own (e.g. `socat - UNIX-SENDTO:PATH,bind=/tmp/me`) gets one reply per
// line ("ok ..." or "error: ..."); `echo 'input 4 on' | nc -uU -w0 PATH` works without one. Lines follow
// the one lexer of the line formats (util/lex.hpp: words, quoting, '#' comments, numbers with range checks).
//
// Who may drive it (docs/segment.md, "Control socket"): the socket is created mode 0600 (0660 and the
// group's with a control group), and every datagram's sender credentials (SCM_CREDENTIALS, the datagram
// form of SO_PEERCRED) are checked: the owner, root, or a member of the control group. A path that holds
// anything but a stale socket of the same user is never replaced, a live socket (another program's, or
// another of this process) is refused, and only the socket this object created is removed when it goes.
//
// A datagram longer than kMaxDatagram is refused whole (nothing of it is executed) with an error answer.
// The work per service() is bounded in time (kBudgetNs, at least one line): the rest of a datagram, and
// the datagrams behind it, wait for the next wake-up, so the runtime handles frames in between; fd() stays
// readable while work is left (an epoll descriptor over the socket and an eventfd).
#include <sys/socket.h>
#include <sys/types.h>
#include <sys/un.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace device {

class Device;

class ControlSocket {
  public:
    static constexpr std::size_t kMaxDatagram = 4096;
    static constexpr uint64_t kBudgetNs = 500'000;  // control work per wake-up (at least one line)
    static constexpr gid_t kNoGroup = static_cast<gid_t>(-1);

    // Creates the socket at path (a stale socket file of the same user there is replaced); group: the
    // control group (kNoGroup: owner and root only). Throws std::runtime_error.
    explicit ControlSocket(std::filesystem::path path, gid_t group = kNoGroup);
    ~ControlSocket();
    ControlSocket(const ControlSocket&) = delete;
    ControlSocket& operator=(const ControlSocket&) = delete;

    int fd() const { return fd_; }
    const std::filesystem::path& path() const { return path_; }
    // Reads waiting datagrams, applies their lines to device, answers senders that have an address; stops
    // when budget_ns is spent (after at least one line) and goes on at the next call.
    void service(Device& device, uint64_t now_ns);
    // The same with another interpreter of the lines (a segment's, device/line.hpp).
    void service(const std::function<std::string(std::string_view)>& apply, uint64_t budget_ns = kBudgetNs);
    // Lines of a datagram are waiting for the next service().
    bool busy() const { return pending_.has_value(); }

    // Applies one command line; returns the answer ("ok ..." or "error: ..."); "" for an empty line.
    static std::string apply(Device& device, std::string_view line);

    // Why a sender with these credentials may not use the socket, or "" if it may.
    std::string refuse(uid_t uid, gid_t gid) const;

  private:
    struct Pending {
        std::string text;    // the datagram
        std::size_t at = 0;  // its first line not yet applied
        std::string reply;
        sockaddr_un from{};
        socklen_t from_len = 0;
    };
    bool receive();  // the next datagram into pending_ (or an answer for a refused one); false: none
    void answer(const Pending& p) const;
    void set_busy(bool busy);

    std::filesystem::path path_;
    gid_t group_ = kNoGroup;
    int sock_ = -1;
    int event_ = -1;  // eventfd: readable while pending_ holds lines
    int fd_ = -1;     // epoll over sock_ and event_: what the runtime watches
    dev_t dev_ = 0;   // the socket file created, removed at the end only if it is still this one
    ino_t ino_ = 0;
    std::vector<char> buffer_;
    std::optional<Pending> pending_;
    bool event_set_ = false;
};

}  // namespace device
