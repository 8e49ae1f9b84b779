#pragma once
// Test helper: runs a function on a new thread that first moves itself into a new, anonymous network
// namespace. Sockets opened there keep the namespace alive; when the last one closes the kernel destroys
// the namespace with every interface in it, so nothing is left behind even if a test fails or crashes.
#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <exception>
#include <stdexcept>
#include <string>
#include <thread>

namespace linktest {

inline bool is_root() {
    return ::geteuid() == 0;
}

template <typename F>
void in_new_netns(F&& fn) {
    std::exception_ptr error;
    std::thread t([&] {
        try {
            if (::unshare(CLONE_NEWNET) != 0)
                throw std::runtime_error(std::string("unshare(CLONE_NEWNET): ") + std::strerror(errno));
            fn();
        } catch (...) {
            error = std::current_exception();
        }
    });
    t.join();
    if (error) std::rethrow_exception(error);
}

// Runs fn on a new thread inside the network namespace open at ns_fd (e.g. kept from
// open("/proc/thread-self/ns/net") inside in_new_netns).
template <typename F>
void in_netns(int ns_fd, F&& fn) {
    std::exception_ptr error;
    std::thread t([&] {
        try {
            if (::setns(ns_fd, CLONE_NEWNET) != 0)
                throw std::runtime_error(std::string("setns: ") + std::strerror(errno));
            fn();
        } catch (...) {
            error = std::current_exception();
        }
    });
    t.join();
    if (error) std::rethrow_exception(error);
}

}  // namespace linktest
