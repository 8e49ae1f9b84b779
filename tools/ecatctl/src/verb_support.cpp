#include <cstdio>

#include "cmd_verbs.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "format.hpp"

namespace ecatctl {

using master::Address;
using master::Error;

void SlaveArg::add_to(CLI::App* c) {
    c->add_option("slave", slave, "Slave position (or station address with --station)")
        ->capture_default_str();
    c->add_flag("-s,--station", station, "<slave> is a station address");
}

std::optional<Address> SlaveArg::address() const {
    auto v = parse_number(slave, 0xFFFF);
    if (!v) {
        std::fprintf(stderr, "ecatctl: bad slave '%s'\n", slave.c_str());
        return std::nullopt;
    }
    return station ? Address::station(static_cast<uint16_t>(*v))
                   : Address::position(static_cast<uint16_t>(*v));
}

Error open_coe_mailbox(master::Master& m, master::Mailbox& mbx, Address a) {
    return open_mailbox(m, mbx, a);
}

int read_slave_pdo_config(master::Master& m, Address a, std::vector<SyncView>& syncs) {
    master::Mailbox mbx(m, a);
    if (Error e = open_coe_mailbox(m, mbx, a); e != Error::Ok)
        return report_error(nullptr, e, "opening the mailbox of " + slave_label(a));
    master::SdoClient sdo(mbx);
    if (Error e = read_pdo_config(sdo, syncs); e != Error::Ok)
        return report_error(&sdo, e, "reading the PDO configuration");
    return kExitOk;
}

int report_error(const master::SdoClient* sdo, Error e, const std::string& what) {
    if (sdo && e == Error::SdoAbort) {
        std::fprintf(stderr, "ecatctl: %s: SDO abort 0x%08x (%s)\n", what.c_str(), sdo->last_abort(),
                     std::string(master::sdo_abort_text(sdo->last_abort())).c_str());
        return kExitProtocol;
    }
    if (sdo && e == Error::MailboxError) {
        std::fprintf(stderr, "ecatctl: %s: mailbox error 0x%04x\n", what.c_str(), sdo->last_mailbox_error());
        return kExitProtocol;
    }
    std::fprintf(stderr, "ecatctl: %s: %s\n", what.c_str(), std::string(master::to_string(e)).c_str());
    return exit_code(e);
}

}  // namespace ecatctl
