// bench-echo: the baseline for bench-rtt. Receives EtherCAT frames on an interface with the same link
// backend the slave uses and sends each straight back (source MAC bit 1 set, as an ESC does), without
// processing anything. Runs until SIGINT/SIGTERM.
#include <poll.h>

#include <csignal>
#include <cstdio>
#include <string>
#include <vector>

#include "esc/link.hpp"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) {
    g_stop = 1;
}
}  // namespace

int main(int argc, char** argv) {
    std::string iface, backend;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--iface" && i + 1 < argc) {
            iface = argv[++i];
        } else if (a == "--backend" && i + 1 < argc) {
            backend = argv[++i];
        } else {
            std::fprintf(stderr, "usage: bench-echo --iface NAME [--backend pcap|packet]\n");
            return 2;
        }
    }
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    try {
        auto link = esc::open_link(iface, backend);
        std::vector<uint8_t> buf(esc::kMaxFrameSize);
        pollfd p{link->fd(), POLLIN, 0};
        while (g_stop == 0) {
            if (::poll(&p, 1, -1) < 0) continue;  // EINTR: check g_stop
            for (int i = 0; i < 64; ++i) {
                const std::size_t n = link->receive(buf);
                if (n == 0) break;
                if (n >= 12) buf[6] |= 0x02;
                link->send(std::span<const uint8_t>(buf.data(), n));
            }
        }
    } catch (const esc::LinkError& e) {
        std::fprintf(stderr, "bench-echo: %s\n", e.what());
        return 2;
    }
    return 0;
}
