#include "send_control.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ostream>
#include <sstream>

namespace ecat_slave {

namespace {

struct Fd {
    int fd = -1;
    ~Fd() {
        if (fd >= 0) ::close(fd);
    }
};

// The client's own address, a socket file the slave answers to: beside the slave's socket (a folder both see,
// whatever their network namespaces or private /tmp), else in a private folder of $TMPDIR. An abstract
// address would not do: it is seen only in the network namespace it was made in. Removed on destruction.
struct ClientAddress {
    std::string file, dir;
    ~ClientAddress() {
        if (!file.empty()) ::unlink(file.c_str());
        if (!dir.empty()) ::rmdir(dir.c_str());
    }
    bool bind(int fd, const std::string& server, std::string& why) {
        static constexpr std::size_t kMax = sizeof(sockaddr_un::sun_path) - 1;
        const std::size_t slash = server.rfind('/');
        const std::string folder = slash == std::string::npos ? "." : server.substr(0, slash + 1);
        const std::string beside = folder + (slash == std::string::npos ? "/" : "") + ".ecat-control-" +
                                   std::to_string(::getpid()) + ".sock";
        if (beside.size() <= kMax && try_bind(fd, beside)) return true;
        const char* tmp = std::getenv("TMPDIR");
        std::string templ = std::string(tmp && *tmp ? tmp : "/tmp") + "/ecat-control-XXXXXX";
        if (::mkdtemp(templ.data()) == nullptr) {
            why = "cannot make a folder for the answer socket: " + std::string(std::strerror(errno));
            return false;
        }
        dir = templ;
        ::chmod(dir.c_str(), 0711);  // a slave running as another user reaches the socket
        if (dir.size() + 2 <= kMax && try_bind(fd, dir + "/c")) return true;
        why = "cannot bind the answer socket: " + std::string(std::strerror(errno));
        return false;
    }

  private:
    bool try_bind(int fd, const std::string& path) {
        sockaddr_un a{};
        a.sun_family = AF_UNIX;
        std::memcpy(a.sun_path, path.data(), path.size());
        if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) < 0) return false;
        file = path;
        ::chmod(path.c_str(), 0666);
        return true;
    }
};

}  // namespace

int send_control(const std::string& path, const std::vector<std::string>& lines, std::ostream& out,
                 std::ostream& err, std::chrono::milliseconds timeout) {
    sockaddr_un to{};
    to.sun_family = AF_UNIX;
    if (path.empty() || path.size() >= sizeof to.sun_path) {
        err << "ecat-slave: --control " << path << ": a UNIX socket path has 1 to " << sizeof to.sun_path - 1
            << " bytes; this one has " << path.size() << " (use a shorter or relative path)\n";
        return 2;
    }
    std::memcpy(to.sun_path, path.data(), path.size());
    Fd s{::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0)};
    if (s.fd < 0) {
        err << "ecat-slave: socket(AF_UNIX): " << std::strerror(errno) << '\n';
        return 1;
    }
    ClientAddress self;
    if (std::string why; !self.bind(s.fd, path, why)) {
        err << "ecat-slave: --control " << path << ": " << why << '\n';
        return 1;
    }
    std::string message;
    for (const auto& line : lines)
        message += line + '\n';
    if (::sendto(s.fd, message.data(), message.size(), 0, reinterpret_cast<sockaddr*>(&to), sizeof to) < 0) {
        const int e = errno;
        err << "ecat-slave: --control " << path << ": " << std::strerror(e)
            << (e == ENOENT || e == ECONNREFUSED ? " (is an ecat-slave running with --control at this path?)"
                                                 : "")
            << '\n';
        return e == ENOENT || e == ECONNREFUSED || e == ENOTSOCK ? 2 : 1;
    }
    // The slave answers a datagram with one datagram: the answers of its lines, each "ok ..." (some with more
    // lines after it, e.g. `segment`) or "error: ...".
    pollfd p{s.fd, POLLIN, 0};
    int ready = 0;
    while ((ready = ::poll(&p, 1, static_cast<int>(timeout.count()))) < 0 && errno == EINTR) {
    }
    if (ready <= 0) {
        err << "ecat-slave: --control " << path << ": no answer within " << timeout.count() << " ms\n";
        return 1;
    }
    std::string buffer(65536, '\0');
    const ssize_t n = ::recv(s.fd, buffer.data(), buffer.size(), 0);
    if (n < 0) {
        err << "ecat-slave: --control " << path << ": " << std::strerror(errno) << '\n';
        return 1;
    }
    bool failed = false;
    std::istringstream in(std::string(buffer.data(), static_cast<std::size_t>(n)));
    for (std::string line; std::getline(in, line);) {
        out << line << '\n';
        if (line.rfind("error", 0) == 0) failed = true;
    }
    return failed ? 1 : 0;
}

}  // namespace ecat_slave
