#pragma once
// Small helpers shared by the tests_<group>.cpp files.
#include <algorithm>
#include <cstring>
#include <map>
#include <string>
#include <vector>

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
    // A test whose body runs when each of `needs` is met, in PREOP (in_preop below).
    void operator()(std::string id, std::string title, std::string clause,
                    std::initializer_list<std::string (Context::*)() const> needs, Outcome (*body)(Context&),
                    std::string applies = {}, Severity sev = Severity::Error) const;
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

// What a test needs of the slave (Context::need_coe, need_esi, ...): "" when met, else the reason to skip.
using Need = std::string (Context::*)() const;

// The test body, run when each of `needs` is met (in their order; the first unmet one skips the test) and
// the slave is in PREOP with its standard mailbox (else the test fails, as CONFORM_PREOP says).
inline std::function<Outcome(Context&)> in_preop(std::initializer_list<Need> needs,
                                                 Outcome (*body)(Context&)) {
    return [n = std::vector<Need>(needs), body](Context& ctx) -> Outcome {
        for (Need need : n)
            CONFORM_NEED((ctx.*need)());
        CONFORM_PREOP(ctx);
        return body(ctx);
    };
}

inline void Adder::operator()(std::string id, std::string title, std::string clause,
                              std::initializer_list<Need> needs, Outcome (*body)(Context&),
                              std::string applies, Severity sev) const {
    (*this)(std::move(id), std::move(title), std::move(clause), in_preop(needs, body), std::move(applies),
            sev);
}

}  // namespace conform
