// ecatctl cstruct [slave]: the live PDO configuration (read over CoE, as `pdos`) as the C arrays IgH's
// ecrt_slave_config_pdos() takes - ec_pdo_entry_info_t, ec_pdo_info_t, ec_sync_info_t - in the layout of
// IgH's `ethercat cstruct`: a comment with the identity, entries, PDOs, one sync line per SM and {0xff}.
// The direction of an SM and its watchdog come from the SII SyncM category (control register bit 2:
// write = output; bit 6: watchdog); SMs the SII does not describe are taken from 0x1C00.
#include <cstdio>

#include "cmd_verbs.hpp"
#include "coe_view.hpp"
#include "esi/sii_reader.hpp"
#include "format.hpp"

namespace ecatctl {

namespace {

int run_cstruct(master::Master& m, const SlaveArg& s) {
    auto a = s.address();
    if (!a) return kExitUsage;
    auto img = m.sii_read_image(*a);
    if (!img) return report_error(nullptr, img.error(), "reading the SII of " + slave_label(*a));
    const esi::SiiInfo sii = esi::parse_sii(*img);
    std::vector<SyncView> syncs;
    if (int rc = read_slave_pdo_config(m, *a, syncs); rc != kExitOk) return rc;

    const unsigned pos = a->value;  // the position (or station address) names the arrays
    const std::string name = sii.general ? sii.general->name : std::string();
    std::printf("/* Master 0, Slave %u, \"%s\"\n", pos, name.c_str());
    std::printf(" * Vendor ID:       0x%08x\n", sii.vendor_id);
    std::printf(" * Product code:    0x%08x\n", sii.product_code);
    std::printf(" * Revision number: 0x%08x\n", sii.revision);
    std::printf(" */\n\n");

    std::printf("ec_pdo_entry_info_t slave_%u_pdo_entries[] = {\n", pos);
    for (const auto& sv : syncs)
        for (const auto& p : sv.pdos)
            for (const auto& e : p.entries)
                std::printf("    {0x%04x, 0x%02x, %u}, /* %s */\n", e.index, e.subindex, e.bit_length,
                            e.index == 0 ? "Gap" : e.name.c_str());
    std::printf("};\n\n");

    std::printf("ec_pdo_info_t slave_%u_pdos[] = {\n", pos);
    unsigned entry_no = 0;
    for (const auto& sv : syncs)
        for (const auto& p : sv.pdos) {
            std::printf("    {0x%04x, %zu, slave_%u_pdo_entries + %u}, /* %s */\n", p.index, p.entries.size(),
                        pos, entry_no, p.name.c_str());
            entry_no += static_cast<unsigned>(p.entries.size());
        }
    std::printf("};\n\n");

    std::printf("ec_sync_info_t slave_%u_syncs[] = {\n", pos);
    const std::size_t n_sm =
        std::max<std::size_t>(sii.sync_managers.size(), syncs.empty() ? 0 : syncs.back().sm + 1u);
    unsigned pdo_no = 0;
    std::vector<unsigned> first_pdo(n_sm, 0);
    for (const auto& sv : syncs) {
        if (sv.sm < n_sm) first_pdo[sv.sm] = pdo_no;
        pdo_no += static_cast<unsigned>(sv.pdos.size());
    }
    for (std::size_t i = 0; i < n_sm; ++i) {
        const SyncView* sv = nullptr;
        for (const auto& v : syncs)
            if (v.sm == i) sv = &v;
        bool output = i == 0;  // mailbox out (SM0) is written by the master
        bool watchdog = false;
        if (i < sii.sync_managers.size()) {
            output = (sii.sync_managers[i].control & 0x0C) == 0x04;
            watchdog = (sii.sync_managers[i].control & 0x40) != 0;
        } else if (sv) {
            output = sv->output;
        }
        const char* dir = output ? "EC_DIR_OUTPUT" : "EC_DIR_INPUT";
        const char* wd = watchdog ? "EC_WD_ENABLE" : "EC_WD_DISABLE";
        if (sv && !sv->pdos.empty())
            std::printf("    {%zu, %s, %zu, slave_%u_pdos + %u, %s},\n", i, dir, sv->pdos.size(), pos,
                        first_pdo[i], wd);
        else
            std::printf("    {%zu, %s, 0, NULL, %s},\n", i, dir, wd);
    }
    std::printf("    {0xff}\n};\n");
    return kExitOk;
}

}  // namespace

void add_cstruct_command(CLI::App& app, MasterRunner run, int& rc) {
    auto s = std::make_shared<SlaveArg>();
    auto* c = app.add_subcommand(
        "cstruct",
        "Print the PDO configuration as C for IgH's ecrt_slave_config_pdos() (IgH `ethercat cstruct`)");
    s->add_to(c);
    c->callback(
        [s, run = std::move(run), &rc] { rc = run([&](master::Master& m) { return run_cstruct(m, *s); }); });
}

}  // namespace ecatctl
