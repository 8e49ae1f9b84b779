#pragma once
// FoE client (ETG.1000.6 FoE): read and write a file over a configured Mailbox. A DATA packet
// shorter than the largest one ends the file (an empty one when the length is a multiple of it); BUSY
// answers to a DATA packet make the client send that packet again.
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "master/mailbox.hpp"

namespace master {

// Progress of a transfer: bytes acknowledged so far, the total (0 when unknown, as on a read), and whether
// the slave's last answer was BUSY (e.g. storing the image after the last DATA packet).
struct FoeProgress {
    std::size_t done = 0;
    std::size_t total = 0;
    bool busy = false;
};

class FoeClient {
  public:
    explicit FoeClient(Mailbox& mailbox);

    // Called after each acknowledged DATA packet and each BUSY answer (never when empty).
    void set_progress(std::function<void(const FoeProgress&)> callback) { progress_ = std::move(callback); }

    Result<std::vector<uint8_t>> read(std::string_view name, uint32_t password = 0,
                                      std::size_t max_size = 64u << 20);
    Error write(std::string_view name, std::span<const uint8_t> data, uint32_t password = 0);

    // Of the last Error::FoeError: the code (0x8000 + n) and the text the slave sent with it.
    uint32_t last_error() const { return last_error_; }
    const std::string& last_error_text() const { return last_error_text_; }
    uint64_t busy_answers() const { return busy_; }

  private:
    Error send(uint8_t opcode, uint32_t value, std::span<const uint8_t> data);
    // Waits for the next FoE message; opcode and the 32-bit field; data after the 6-byte FoE header.
    Error receive(uint8_t& opcode, uint32_t& value, std::span<const uint8_t>& data);

    Mailbox& mbx_;
    std::vector<uint8_t> buf_;
    uint32_t last_error_ = 0;
    std::string last_error_text_;
    uint64_t busy_ = 0;
    std::function<void(const FoeProgress&)> progress_;
};

}  // namespace master
