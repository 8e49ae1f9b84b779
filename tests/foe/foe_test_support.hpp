#pragma once
#include <stdlib.h>

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "ecat/mailbox_handler.hpp"
#include "foe/image.hpp"
#include "support/temp_dir.hpp"
#include "util/le.hpp"

namespace foe_test {

constexpr foe::ImageIdentity kMaxpos{0x000000FB, 0x30010000};

// A fresh temporary directory, removed with the object.
struct TempDir : test_support::TempDir {
    TempDir() : test_support::TempDir("foe_test_") {}
};

// Collects what a handler sends.
struct FakeSender final : ecat::MailboxSender {
    std::size_t max = 128 - 6;  // SM1 of 128 bytes
    std::vector<std::vector<uint8_t>> sent;
    bool send(ecat::MailboxType type, std::span<const uint8_t> payload) override {
        if (type != ecat::MailboxType::FoE || payload.size() > max) return false;
        sent.emplace_back(payload.begin(), payload.end());
        return true;
    }
    std::size_t max_payload() const override { return max; }
    std::vector<uint8_t> take() {
        if (sent.empty()) return {};
        auto m = sent.front();
        sent.erase(sent.begin());
        return m;
    }
};

inline std::vector<uint8_t> payload_bytes(std::size_t n, uint32_t seed) {
    std::vector<uint8_t> v(n);
    uint32_t x = seed * 2654435761u + 1;
    for (auto& b : v) {
        x = x * 1103515245u + 12345u;
        b = static_cast<uint8_t>(x >> 16);
    }
    return v;
}

inline uint32_t le32(const std::vector<uint8_t>& m, std::size_t at) {
    return util::get32(m, at);
}

// A FoE packet (ETG.1000.6 FoE header: opcode, reserved byte, 32-bit packet number / password / error code)
// followed by tail.
inline std::vector<uint8_t> foe_packet(uint8_t op, uint32_t value, std::span<const uint8_t> tail = {}) {
    std::vector<uint8_t> m{op, 0};
    util::append32(m, value);
    for (auto c : tail)
        m.push_back(c);  // (vector::insert here trips GCC 12's -Warray-bounds at -O2)
    return m;
}

}  // namespace foe_test
