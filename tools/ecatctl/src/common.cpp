#include "common.hpp"

#include <cstdio>
#include <iostream>

#include "esi/sii_reader.hpp"
#include "format.hpp"
#include "util/strfmt.hpp"

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

std::string slave_label(master::Address a) {
    return a.mode == master::Address::Mode::Station ? util::strprintf("station 0x%04x", a.value)
                                                    : util::strprintf("slave %u", a.value);
}

std::optional<master::Address> parse_slave_address(const std::string& text, bool station) {
    auto v = parse_number(text, 0xFFFF);
    if (!v) return std::nullopt;
    return station ? master::Address::station(static_cast<uint16_t>(*v))
                   : master::Address::position(static_cast<uint16_t>(*v));
}

int usage_error(const std::string& what) {
    std::cerr << "ecatctl: " << what << "\n";
    return kExitUsage;
}

int report_error(master::Error e, const std::string& what) {
    std::cerr << "ecatctl: " << what << ": " << master::to_string(e);
    if (e == master::Error::Timeout)
        std::cerr << " (check that a slave is connected and running on the interface)";
    if (e == master::Error::WorkingCounter)
        // Not only a missing slave: a slave refuses an access it cannot take (a mailbox write while its
        // last request is still unread, as after a lost reply and a retry) with the same counter.
        std::cerr << " (no slave at that address, or the slave did not take the access; `ecatctl scan` lists "
                     "the slaves)";
    std::cerr << "\n";
    return exit_code(e);
}

int check_slave_present(master::Master& m, master::Address a) {
    if (a.mode == master::Address::Mode::Position) {
        auto n = m.count_slaves();
        if (!n) return report_error(n.error(), "counting slaves (BRD 0x0000)");
        if (a.value < *n) return kExitOk;
        std::cerr << "ecatctl: there is no slave " << a.value << ": " << *n << " slave"
                  << (*n == 1 ? "" : "s") << " on the line"
                  << (*n ? " (positions 0.." + std::to_string(*n - 1) + ")" : "") << "\n";
        return kExitNoSlave;
    }
    uint8_t b[2];
    const master::Error e = m.read(a, esc::reg::kAlStatus, b);  // AL status
    if (e == master::Error::Ok) return kExitOk;
    if (e == master::Error::WorkingCounter) {
        std::cerr << util::strprintf(
            "ecatctl: no slave has the station address 0x%04x (`ecatctl scan` assigns 0x1001..)\n", a.value);
        return kExitNoSlave;
    }
    return report_error(e, "reading the AL status of " + slave_label(a));
}

std::optional<std::string> sii_device_name(master::Master& m, master::Address a) {
    auto img = m.sii_read_image(a);
    if (!img) return std::nullopt;
    const esi::SiiInfo info = esi::parse_sii(*img);
    if (info.general && !info.general->name.empty()) return info.general->name;
    return std::nullopt;
}

std::string foe_names_hint(const std::string& prefix) {
    return prefix +
           ": the device takes firmware under its device name (0x1008, e.g. MAXPOS) or its firmware file "
           "name "
           "<name>_XXXXh_XXXXh_XXXXh_XXXXh.bin (`fwimage info FILE` prints it); --name chooses";
}

bool sii_problems(const std::string& what, const std::vector<uint8_t>& image) {
    if (image.empty()) {
        std::cerr << "ecatctl: " << what << " is empty: not an SII image\n";
        return true;
    }
    const esi::SiiInfo info = esi::parse_sii(image);
    if (info.problems.empty() && info.header_complete) return false;
    std::cerr << "ecatctl: " << what << " is not a valid SII image: "
              << (info.problems.empty() ? std::string("the header is incomplete") : info.problems.front());
    if (info.problems.size() > 1)
        std::cerr << " (and " << info.problems.size() - 1 << " more problems, above)";
    std::cerr << "\n";
    return true;
}

int report_usage_error(const CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
    // The first word that is not a global option or its value is the verb.
    std::string verb;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "-i" || a == "--iface" || a == "-b" || a == "--backend" || a == "-t" || a == "--timeout" ||
            a == "--retries") {
            ++i;
            continue;
        }
        if (!a.empty() && a[0] == '-') continue;
        verb = a;
        break;
    }
    const auto all = app.get_subcommands([](const CLI::App*) { return true; });
    bool known = false;
    std::string verbs;
    for (const CLI::App* c : all) {
        known = known || c->check_name(verb);
        verbs += (verbs.empty() ? "" : ", ") + c->get_name();
    }
    if (!verb.empty() && !known) {
        std::cerr << "ecatctl: unknown command '" << verb << "' (commands: " << verbs << ")\n";
        return kExitUsage;
    }
    std::cerr << "ecatctl: " << e.what() << " (ecatctl --help)\n";
    return kExitUsage;
}

std::vector<std::string> position_option_as_argument(int argc, char** argv) {
    std::vector<std::string> args(argv, argv + argc);
    auto global_with_value = [](const std::string& a) {
        return a == "-i" || a == "--iface" || a == "-b" || a == "--backend" || a == "-t" ||
               a == "--timeout" || a == "--retries";
    };
    std::size_t i = 1;
    while (i < args.size() && !args[i].empty() && args[i][0] == '-')
        i += global_with_value(args[i]) ? 2 : 1;
    if (i >= args.size()) return args;
    const std::string verb = args[i];
    std::size_t slave_at = i + 1;  // where the slave argument goes
    if (verb == "reg") {
        if (slave_at >= args.size() || (args[slave_at] != "read" && args[slave_at] != "write")) return args;
        ++slave_at;
    } else if (verb != "state" && verb != "upload" && verb != "download" && verb != "sdos" && verb != "pd" &&
               verb != "diag" && verb != "slaves" && verb != "pdos" && verb != "cstruct" && verb != "xml" &&
               verb != "alias") {
        return args;  // these verbs have -p/--position as an option of their own
    }
    for (std::size_t k = slave_at; k < args.size(); ++k) {
        const std::string& a = args[k];
        if (a == "--") break;
        std::string value;
        std::size_t take = 0;
        if ((a == "-p" || a == "--position") && k + 1 < args.size()) {
            value = args[k + 1];
            take = 2;
        } else if (a.rfind("--position=", 0) == 0) {
            value = a.substr(11);
            take = 1;
        } else if (a.size() > 2 && a.rfind("-p", 0) == 0) {
            value = a.substr(2);
            take = 1;
        }
        if (take == 0) continue;
        args.erase(args.begin() + static_cast<std::ptrdiff_t>(k),
                   args.begin() + static_cast<std::ptrdiff_t>(k + take));
        args.insert(args.begin() + static_cast<std::ptrdiff_t>(slave_at), value);
        break;
    }
    return args;
}

}  // namespace ecatctl
