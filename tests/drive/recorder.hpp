#pragma once
// An event sink that records what the drive (or one of its parts) announced.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "drive/event_sink.hpp"

namespace drive::test {

struct Recorder : EventSink {
    struct Raised {
        uint16_t code;
        uint8_t reg;
    };
    std::vector<Raised> raised;
    std::vector<uint16_t> cleared;
    std::vector<std::string> diags;
    void raise(uint16_t c, uint8_t r, const std::array<uint8_t, 5>&) override { raised.push_back({c, r}); }
    void clear(uint16_t c, uint8_t) override { cleared.push_back(c); }
    void diag(Severity, uint16_t, std::string_view t) override { diags.emplace_back(t); }
    bool has(uint16_t c) const {
        for (auto& r : raised)
            if (r.code == c) return true;
        return false;
    }
};

}  // namespace drive::test
