// ecatctl pdos [slave]: the PDO assignment and mapping the slave has now, read over CoE (0x1C00, 0x1C1n,
// 0x16xx/0x1Axx) with names from SDO information, printed as IgH's `ethercat pdos` prints them: each SM
// (address, default size, control register, enable from the SII SyncM category), its PDOs, their entries.
#include <cstdio>

#include "cmd_verbs.hpp"
#include "coe_view.hpp"
#include "esi/sii_reader.hpp"
#include "format.hpp"

namespace ecatctl {

namespace {

int run_pdos(master::Master& m, const SlaveArg& s, bool quiet) {
    auto a = s.address();
    if (!a) return kExitUsage;
    esi::SiiInfo sii;
    if (auto img = m.sii_read_image(*a)) sii = esi::parse_sii(*img);
    std::vector<SyncView> syncs;
    if (int rc = read_slave_pdo_config(m, *a, syncs); rc != kExitOk) return rc;
    const std::size_t n_sm = std::max<std::size_t>(sii.sync_managers.size(), 4);
    for (std::size_t i = 0; i < n_sm; ++i) {
        const SyncView* sv = nullptr;
        for (const auto& v : syncs)
            if (v.sm == i) sv = &v;
        if (i < sii.sync_managers.size()) {
            const auto& sm = sii.sync_managers[i];
            std::printf("SM%zu: PhysAddr 0x%04x, DefaultSize %4u, ControlRegister 0x%02x, Enable %u\n", i,
                        sm.start, sm.length, sm.control, sm.enable & 1u);
        } else if (sv) {
            std::printf("SM%zu:\n", i);
        }
        if (!sv) continue;
        for (const auto& p : sv->pdos) {
            std::printf("  %cxPDO 0x%04x \"%s\"\n", sv->output ? 'R' : 'T', p.index, p.name.c_str());
            if (quiet) continue;
            for (const auto& e : p.entries)
                std::printf("    PDO entry 0x%04x:%02x, %2u bit, \"%s\"\n", e.index, e.subindex, e.bit_length,
                            e.index == 0 ? "Gap" : e.name.c_str());
        }
    }
    return kExitOk;
}

}  // namespace

void add_pdos_command(CLI::App& app, MasterRunner run, int& rc) {
    auto s = std::make_shared<SlaveArg>();
    auto quiet = std::make_shared<bool>(false);
    auto* c = app.add_subcommand("pdos",
                                 "Show the PDO assignment and mapping, read over CoE (IgH `ethercat pdos`)");
    s->add_to(c);
    c->add_flag("-q,--quiet", *quiet, "PDOs only, no entries");
    c->callback([s, quiet, run = std::move(run), &rc] {
        rc = run([&](master::Master& m) { return run_pdos(m, *s, *quiet); });
    });
}

}  // namespace ecatctl
