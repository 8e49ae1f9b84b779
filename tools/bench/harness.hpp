#pragma once
// Process and namespace plumbing the veth-pair benchmarks share (bench-rtt, bench-sdo, bench-cycle,
// bench-foe): a monotonic clock, child processes that die with the benchmark, and the private network
// namespace the veth pairs live in.
#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace bench {

// CLOCK_MONOTONIC in nanoseconds.
uint64_t now_ns();

// A child process (args[0] run with args), killed with us (PR_SET_PDEATHSIG) and by the destructor
// (stop()). Its stdout and stderr go to the file output (created or truncated; "/dev/null" to silence it),
// or stay ours when output is empty.
class Child {
  public:
    Child(const std::vector<std::string>& args, const std::string& output, int term_wait_ms = 5000);
    ~Child() { (void)stop(); }
    Child(const Child&) = delete;
    Child& operator=(const Child&) = delete;

    // False once the child has exited (its wait status is kept).
    bool alive();
    // Waits for the exit; returns the wait status (-1 if it was collected already and none was kept).
    int wait();
    // SIGTERM, wait up to term_wait_ms, then SIGKILL. Returns the wait status (-1 if it was gone already).
    int stop();

  private:
    pid_t pid_ = -1;
    int status_ = -1;
    int term_wait_ms_;
};

// The exit code in a wait status; -1 if the process did not exit normally (or for status -1).
int exit_code(int wait_status);

// The value of the option at argv[i] (argv[i + 1]; i moves on to it). Without one: usage(), exit status 2.
std::string option_value(int argc, char** argv, int& i, void (*usage)());

// Prints "<program>: needs root <why>" and returns false unless running as root.
bool require_root(const char* why);

// Moves this process into a new network namespace (unshare), which the kernel removes with the veth pairs
// in it when this program and its children exit, however they exit. Prints why and returns false if
// refused.
bool enter_network_namespace();

// A fresh directory /tmp/<prefix>.XXXXXX, removed with everything in it when the object goes. Throws
// std::runtime_error if it cannot be created.
class TempDir {
  public:
    explicit TempDir(const std::string& prefix);
    ~TempDir();
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::filesystem::path& path() const { return path_; }

  private:
    std::filesystem::path path_;
};

}  // namespace bench
