// (4) The FoE server (foe/src/server.cpp) against an in-memory firmware sink (memory_sink.hpp): mailbox
// payloads (after the mailbox header) of file reads and writes, DATA, ACK, BUSY and ERROR packets in any
// order, in Bootstrap and outside it. Input: one byte for the mailbox size, then a sequence of
// [control byte][16-bit length][payload]; the control byte picks Bootstrap or Pre-Op (a state change ends a
// transfer), whether the reply queue is full, and how far the clock moves before poll() (transfer timeout).
// Checked: nothing crashes, every reply fits the mailbox, no image stays open once the server is idle.
#include "foe/image.hpp"
#include "foe/server.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"
#include "memory_sink.hpp"

namespace fuzz::foe_server {

int fuzz_one(const uint8_t* data, std::size_t size) {
    Input in(data, size);
    const std::size_t max_payload = 10 + (in.u8() * 4u) % 1015u;
    const foe::ImageIdentity id{0x000000FB, 0x30010000};
    MemorySink sink(id, "MAXPOS", 64u << 10);
    std::vector<uint8_t> payload(300);
    for (std::size_t i = 0; i < payload.size(); ++i)
        payload[i] = static_cast<uint8_t>(i * 7);
    sink.install(0, foe::build_image(payload, id, 0x01200000));
    foe::ServerConfig config;
    config.commit_in_thread = false;
    config.timeout_ns = 1'000'000'000;
    {
        foe::FoeServer server(sink, config);
        od::AlState state = od::AlState::Boot;
        server.set_state(state);
        CheckingSender out(max_payload);
        uint64_t now = 1'000'000'000;
        while (!in.empty()) {
            const uint8_t ctl = in.u8();
            const auto message = in.record();
            const od::AlState next = (ctl & 1) ? od::AlState::PreOp : od::AlState::Boot;
            if (next != state) {
                server.on_state_change(state, next);
                state = next;
            }
            out.full = (ctl & 2) != 0;
            server.handle(message, out);
            now += static_cast<uint64_t>(ctl >> 2) * 50'000'000;  // up to 3.15 s
            out.full = false;
            server.poll(now, out);
            if (server.idle()) FUZZ_CHECK(sink.open_images() == 0);
        }
    }
    FUZZ_CHECK(sink.open_images() == 0);
    return 0;
}

}  // namespace fuzz::foe_server
