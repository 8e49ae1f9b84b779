#include "harness.hpp"

#include <errno.h>
#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace bench {

uint64_t now_ns() {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<uint64_t>(ts.tv_sec) * 1'000'000'000ull + static_cast<uint64_t>(ts.tv_nsec);
}

Child::Child(const std::vector<std::string>& args, const std::string& output, int term_wait_ms)
    : term_wait_ms_(term_wait_ms) {
    const pid_t parent = ::getpid();
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
    if (pid_ == 0) {
        ::prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (::getppid() != parent) ::_exit(127);
        if (!output.empty()) {
            const int fd = ::open(output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            if (fd >= 0) {
                ::dup2(fd, 1);
                ::dup2(fd, 2);
            }
        }
        std::vector<char*> argv;
        for (const auto& a : args)
            argv.push_back(const_cast<char*>(a.c_str()));
        argv.push_back(nullptr);
        ::execv(argv[0], argv.data());
        std::fprintf(stderr, "%s: cannot run %s: %s\n", program_invocation_short_name, argv[0],
                     std::strerror(errno));
        ::_exit(127);
    }
}

bool Child::alive() {
    if (pid_ <= 0) return false;
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        status_ = status;
        pid_ = -1;
        return false;
    }
    return true;
}

int Child::wait() {
    if (pid_ <= 0) return status_;
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    pid_ = -1;
    status_ = status;
    return status_;
}

int Child::stop() {
    if (pid_ <= 0) return status_;
    ::kill(pid_, SIGTERM);
    for (int i = 0; i < term_wait_ms_ / 10; ++i) {
        int status = 0;
        if (::waitpid(pid_, &status, WNOHANG) == pid_) {
            pid_ = -1;
            status_ = status;
            return status_;
        }
        ::usleep(10'000);
    }
    ::kill(pid_, SIGKILL);
    return wait();
}

int exit_code(int wait_status) {
    if (wait_status == -1) return -1;
    return WIFEXITED(wait_status) ? WEXITSTATUS(wait_status) : -1;
}

std::string option_value(int argc, char** argv, int& i, void (*usage)()) {
    if (i + 1 >= argc) {
        usage();
        std::exit(2);
    }
    return argv[++i];
}

bool require_root(const char* why) {
    if (::geteuid() == 0) return true;
    std::fprintf(stderr, "%s: needs root %s\n", program_invocation_short_name, why);
    return false;
}

bool enter_network_namespace() {
    if (::unshare(CLONE_NEWNET) == 0) return true;
    std::fprintf(stderr, "%s: unshare(CLONE_NEWNET): %s\n", program_invocation_short_name,
                 std::strerror(errno));
    return false;
}

TempDir::TempDir(const std::string& prefix) {
    std::string tmpl = "/tmp/" + prefix + ".XXXXXX";
    if (::mkdtemp(tmpl.data()) == nullptr)
        throw std::runtime_error("mkdtemp " + tmpl + ": " + std::strerror(errno));
    path_ = tmpl;
}

TempDir::~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
}

}  // namespace bench
