// (3) Mailbox payloads (the bytes after the 6-byte mailbox header) into the CoE server, on the drive's full
// object dictionary with its PDO validators and diagnosis history: SDO upload/download (expedited, normal,
// segmented, complete access), SDO information, anything else. Input: one byte for the reply mailbox size,
// then a sequence of [control byte][16-bit length][payload]; the control byte picks the AL state (and so a
// state change), whether the reply queue is full, and how far the clock moves before poll().
// Per input: the dictionary (built once) is put back into its built state (fuzz_support.hpp), the server is
// built afresh.
#include <functional>

#include "coe/diagnosis.hpp"
#include "coe/pdo_validation.hpp"
#include "coe/sdo_server.hpp"
#include "drive/drive.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"
#include "maxpos/maxpos.hpp"

namespace fuzz::coe_mailbox {
namespace {

constexpr od::AlState kStates[4] = {od::AlState::PreOp, od::AlState::SafeOp, od::AlState::Op,
                                    od::AlState::Init};

// The drive's dictionary, built once and put back into its built state for each input.
od::Dictionary& fresh_dictionary() {
    static const od::DeviceDescription desc = maxpos::description();
    static PristineDictionary pristine(maxpos::dictionary(desc), [](od::Dictionary& d) {
        (void)drive::commission(d, maxpos::drive_objects());
        coe::install_pdo_validators(d);
    });
    return pristine.fresh();
}

}  // namespace

int fuzz_one(const uint8_t* data, std::size_t size) {
    Input in(data, size);
    // Mailbox sizes a configuration can give: 10 .. 1024 payload bytes.
    const std::size_t max_payload = 10 + (in.u8() * 4u) % 1015u;
    od::Dictionary& dict = fresh_dictionary();
    od::AlState state = od::AlState::PreOp;
    coe::CoeServer server(dict, [&state] { return state; });
    coe::DiagnosisHistory diag(dict, &server.emergency());
    CheckingSender out(max_payload);
    uint64_t now = 1'000'000'000;
    while (!in.empty()) {
        const uint8_t ctl = in.u8();
        const auto payload = in.record();
        const od::AlState next = kStates[ctl & 3];
        if (next != state) {
            const od::AlState from = state;
            state = next;
            server.on_state_change(from, next);
        }
        out.full = (ctl & 4) != 0;
        if (server.available(state)) server.handle(payload, out);
        now += static_cast<uint64_t>(ctl >> 3) * 100'000'000;  // up to 3.1 s: segmented transfers time out
        out.full = false;
        server.poll(now, out);
    }
    return 0;
}

}  // namespace fuzz::coe_mailbox
