#pragma once
// Small helpers shared by the tests_<group>.cpp files.
#include <algorithm>
#include <cstring>
#include <map>
#include <string>

#include "conform.hpp"
#include "util/le.hpp"

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

// Little-endian access: the project's one set of helpers (util/le.hpp).
using util::get16;
using util::get32;
using util::put16;
using util::put32;

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
