#pragma once
// The ESC the tests of tests/esc start from: a manual clock set to StartNs, the default EscConfig and station
// address 0x1001 (set through ECAT, see frame.hpp). Fixtures derive from it and add their own set-up.
#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <vector>

#include "esc/wire/sii.hpp"
#include "frame.hpp"

namespace esc_test {

template <uint64_t StartNs = 1'000'000>
struct EscFixture : ::testing::Test {
    esc::ManualClock clk;
    std::optional<esc::Esc> e;
    void SetUp() override {
        clk.set(StartNs);
        e.emplace(esc::EscConfig{}, clk);
        set_station(*e, 0x1001);
    }
};

// The 8 bytes of a SyncManager register block (0x0800 + 8n): start, length, control, status, activate, PDI
// control.
inline std::vector<uint8_t> sm_bytes(uint16_t start, uint16_t len, uint8_t ctrl, uint8_t act) {
    std::vector<uint8_t> b = le(start, 2);
    auto l = le(len, 2);
    b.insert(b.end(), l.begin(), l.end());
    b.push_back(ctrl);
    b.push_back(0);
    b.push_back(act);
    b.push_back(0);
    return b;
}

// Rewrites the SII header checksum (word 7, low byte) after a test changed words 0..6 (ETG.2010).
inline void fix_sii_header_crc(std::vector<uint8_t>& img) {
    img[14] = esc::sii::crc8(img.data(), 14);
}

}  // namespace esc_test
