// The catalogue: every group's tests, in run order.
#include "conform.hpp"

namespace conform {

const std::vector<std::string>& group_names() {
    static const std::vector<std::string> g = {"esc",     "sii", "esm", "mbx", "sdo",
                                               "sdoinfo", "pd",  "dc",  "foe", "cia402"};
    return g;
}

std::string group_title(const std::string& g) {
    if (g == "esc") return "ESC and data link";
    if (g == "sii") return "SII EEPROM";
    if (g == "esm") return "EtherCAT state machine";
    if (g == "mbx") return "Mailbox";
    if (g == "sdo") return "CoE SDO";
    if (g == "sdoinfo") return "SDO information";
    if (g == "pd") return "Process data";
    if (g == "dc") return "Distributed clocks";
    if (g == "foe") return "FoE and Bootstrap";
    if (g == "cia402") return "CiA 402 drive profile";
    return g;
}

Catalogue build_catalogue() {
    Catalogue c;
    add_esc_tests(c);
    add_sii_tests(c);
    add_esm_tests(c);
    add_mbx_tests(c);
    add_emcy_tests(c);
    add_sdo_tests(c);
    add_sdoinfo_tests(c);
    add_pd_tests(c);
    add_io_tests(c);
    add_dc_tests(c);
    add_foe_tests(c);
    add_cia402_tests(c);
    return c;
}

}  // namespace conform
