#pragma once
// Small helpers shared by the tests_<group>.cpp files.
#include <algorithm>
#include <cstring>
#include <map>
#include <string>

#include "conform.hpp"

namespace conform {

struct Adder {
    Catalogue& c;
    std::string group;
    void operator()(std::string id, std::string title, std::string clause,
                    std::function<Outcome(Context&)> fn, std::string applies = {},
                    Severity sev = Severity::Error) const {
        c.push_back(TestCase{group + "." + id, group, std::move(title), std::move(clause), sev,
                             std::move(applies), std::move(fn)});
    }
};

inline uint16_t get16(const uint8_t* p) {
    return static_cast<uint16_t>(p[0] | (p[1] << 8));
}
inline uint32_t get32(const uint8_t* p) {
    return static_cast<uint32_t>(p[0] | (p[1] << 8) | (p[2] << 16) | (static_cast<uint32_t>(p[3]) << 24));
}
inline void put16(uint8_t* p, uint16_t v) {
    p[0] = static_cast<uint8_t>(v);
    p[1] = static_cast<uint8_t>(v >> 8);
}
inline void put32(uint8_t* p, uint32_t v) {
    for (int i = 0; i < 4; ++i)
        p[i] = static_cast<uint8_t>(v >> (8 * i));
}
inline std::string dec(long long v) {
    return std::to_string(v);
}
inline std::string err(master::Error e) {
    return std::string(master::to_string(e));
}
// Skips with the reason when non-empty.
#define CONFORM_NEED(expr)                                         \
    do {                                                           \
        if (std::string _r = (expr); !_r.empty()) return skip(_r); \
    } while (0)
// Fails when the slave cannot be brought to PREOP with its standard mailbox.
#define CONFORM_PREOP(ctx)                                                                 \
    do {                                                                                   \
        if (master::Error _e = (ctx).to_preop(); _e != master::Error::Ok)                  \
            return fail("cannot reach PREOP with the SII's standard mailbox: " + err(_e)); \
    } while (0)

}  // namespace conform
