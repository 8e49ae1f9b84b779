#include "common.hpp"

#include <cstdio>

#include "format.hpp"

namespace ecatctl {

int exit_code(master::Error e) {
    using master::Error;
    switch (e) {
        case Error::Ok:
            return kExitOk;
        case Error::Timeout:
            return kExitNoSlave;
        case Error::InvalidArgument:
            return kExitUsage;
        case Error::SendFailed:
            return kExitFailure;
        default:
            return kExitProtocol;
    }
}

int report_sdo_failure(const master::SdoClient& sdo, master::Error e, const std::string& what,
                       int (*fail)(master::Error, const std::string&)) {
    if (e == master::Error::SdoAbort) {
        std::fprintf(stderr, "ecatctl: %s: SDO abort 0x%08x (%s)\n", what.c_str(), sdo.last_abort(),
                     std::string(master::sdo_abort_text(sdo.last_abort())).c_str());
        return kExitProtocol;
    }
    if (e == master::Error::MailboxError) {
        std::fprintf(stderr, "ecatctl: %s: mailbox error 0x%04x\n", what.c_str(), sdo.last_mailbox_error());
        return kExitProtocol;
    }
    return fail(e, what);
}

}  // namespace ecatctl
