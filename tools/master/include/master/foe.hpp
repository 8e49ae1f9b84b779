#pragma once
// FoE client (ethercat-protocol.md §10): read and write a file over a configured Mailbox. A DATA packet
// shorter than the largest one ends the file (an empty one when the length is a multiple of it); BUSY
// answers to a DATA packet make the client send that packet again.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "master/mailbox.hpp"

namespace master {

class FoeClient {
  public:
    explicit FoeClient(Mailbox& mailbox);

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
};

}  // namespace master
