// The line of an ENI (see eni_line.hpp).
#include "eni_line.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "esi/device/product.hpp"
#include "esi/eni/eni_modules.hpp"
#include "esi/eni/eni_product.hpp"
#include "esi/eni/eni_reader.hpp"
#include "esi/model.hpp"
#include "esi/slots.hpp"

namespace ecat_slave {

namespace {

// A topology name for slave k: "<k>-<order code>" in the characters a device name may have.
std::string unit_name(std::size_t k, const std::string& order) {
    std::string name = std::to_string(k) + "-";
    for (char c : order) {
        if (name.size() >= slave::kMaxNameLength) break;
        const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                        c == '_' || c == '.' || c == '-';
        name.push_back(ok ? c : '_');
    }
    return name;
}

bool port_has_phy(const std::string& physics, int port) {
    return static_cast<std::size_t>(port) < physics.size() && physics[static_cast<std::size_t>(port)] != ' ';
}

}  // namespace

EsiIndex index_esi_dir(const std::string& dir) {
    namespace fs = std::filesystem;
    EsiIndex index;
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw std::runtime_error(dir + ": not a folder");
    std::vector<fs::path> files;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
        if (it->path().extension() == ".xml" && it->is_regular_file(ec)) files.push_back(it->path());
    if (ec) throw std::runtime_error(dir + ": " + ec.message());
    std::sort(files.begin(), files.end());  // the first file declaring an identity wins, in name order
    for (const fs::path& path : files) {
        std::shared_ptr<const esi::EsiFile> file;
        try {
            file = std::make_shared<const esi::EsiFile>(esi::read_esi_file(path.string()));
        } catch (const std::exception& e) {
            index.skipped.push_back(e.what());
            continue;
        }
        for (const esi::EsiDevice& d : file->devices)
            index.devices.emplace(std::make_tuple(d.vendor_id, d.product_code, d.revision),
                                  EsiIndex::Found{file, &d, path.string()});
    }
    return index;
}

EniLine eni_line(const std::string& file, const EsiIndex* esis) {
    const esi::eni::Config eni = esi::eni::read_eni_file(file);
    if (eni.slaves.empty()) throw esi::eni::EniError(file + ": the ENI declares no slave");
    if (eni.slaves.size() > slave::kMaxDevices)
        throw esi::eni::EniError(file + ": more than " + std::to_string(slave::kMaxDevices) + " slaves");
    EniLine out;
    out.topology.file = file;
    for (std::size_t k = 0; k < eni.slaves.size(); ++k) {
        const esi::eni::Slave& s = eni.slaves[k];
        std::shared_ptr<od::Product> product;
        std::string modules_note;  // the module configuration taken from the ENI, said in the report
        if (esis) {
            auto it =
                esis->devices.find(std::make_tuple(s.info.vendor_id, s.info.product_code, s.info.revision));
            if (it != esis->devices.end()) {
                // A modular device gets the modules the master was configured with (eni_modules.hpp).
                const esi::EsiFile& f = *it->second.file;
                const esi::EsiDevice& dev = *it->second.device;
                std::string why;
                std::vector<std::optional<uint32_t>> modules = esi::default_modules(dev);
                if (auto m = esi::eni::modules_from_eni(f, dev, s, &why)) {
                    modules = m->modules;
                    product = std::make_shared<od::Product>(esi::load_product(f, dev, m->modules));
                    std::string list;
                    for (const auto& id : m->modules) {
                        const esi::EsiModule* mod = id ? f.module(*id) : nullptr;
                        list += (list.empty() ? "" : ",") + (mod ? mod->type_name : std::string("-"));
                    }
                    modules_note = "; modules " + list + " (from " + m->how + ")";
                } else {
                    product = std::make_shared<od::Product>(esi::load_product(f, dev));
                    if (!why.empty())
                        product->warnings.push_back(eni.where(s.line) +
                                                    ": the default modules are served, as the ENI's "
                                                    "configuration matches none: " +
                                                    why);
                }
                // What the master was configured for and the device lacks, said at start: the master will
                // stop where a real device like it would stop it.
                for (const esi::eni::PdoMismatch& w : esi::eni::pdo_mismatches(f, dev, modules, s))
                    product->warnings.push_back(eni.where(w.line) + ": " + w.what + " (" + it->second.path +
                                                ")");
            }
        }
        std::string other_revisions;  // an ESI of DIR with this device in other revisions: said, not used
        if (esis && !product)
            for (const auto& [id, found] : esis->devices)
                if (std::get<0>(id) == s.info.vendor_id && std::get<1>(id) == s.info.product_code) {
                    char rev[16];
                    std::snprintf(rev, sizeof rev, "0x%08X", std::get<2>(id));
                    other_revisions +=
                        (other_revisions.empty() ? "" : ", ") + std::string(rev) + " (" + found.path + ")";
                }
        if (!product) product = std::make_shared<od::Product>(esi::eni::product_from_eni(eni, k));
        slave::TopologyDevice d;
        d.name = unit_name(k, product->description.identity.order_code);
        d.line = s.line;
        if (s.info.serial != 0) d.serial = s.info.serial;
        if (const esi::eni::PreviousPort* pp = s.previous_port()) {
            d.parent = eni.find_phys_addr(pp->phys_addr);
            d.parent_port = pp->port;
        } else if (k > 0) {
            d.parent = static_cast<int>(k) - 1;
            d.parent_port = 1;
        }
        // The ESC has the ports the device's Physics declares (its ESI's, or the ENI's; ETG.2000), so that
        // 0x0007 and the SII General category agree; a port the wiring uses is added below.
        d.descriptor = esi::physics_port_descriptor(product->description.physics);
        if (d.descriptor == 0)  // no Physics: two ports, four if the ENI's own Physics names port 2 or 3
            d.descriptor = port_has_phy(s.info.physics, 2) || port_has_phy(s.info.physics, 3) ? 0xFF : 0x0F;
        char station[16];
        std::snprintf(station, sizeof station, "0x%04X", s.info.phys_addr);
        out.report.push_back(
            "ENI slave " + std::to_string(k) + " '" + s.info.name + "' (station address " + station +
            " from the master): served from " + product->source + modules_note +
            (product->warnings.empty()
                 ? ""
                 : "; not emulated: " + std::to_string(product->warnings.size()) + " (said below)") +
            (other_revisions.empty() ? "" : "; the ESIs have only revision(s) " + other_revisions));
        out.topology.devices.push_back(std::move(d));
        out.products.push_back(std::move(product));
    }
    // A device plugged into port 2 or 3 of another needs a four-port ESC there, whatever Physics says.
    for (std::size_t k = 1; k < out.topology.devices.size(); ++k) {
        slave::TopologyDevice& d = out.topology.devices[k];
        if (d.parent < 0 || d.parent >= static_cast<int>(k))
            throw esi::eni::EniError(eni.where(d.line) + ": PreviousPort names no slave before this one");
        slave::TopologyDevice& parent = out.topology.devices[static_cast<std::size_t>(d.parent)];
        if (d.parent_port < 4 && !parent.has_port(d.parent_port))
            parent.descriptor = static_cast<uint8_t>(parent.descriptor | (0x3u << (2 * d.parent_port)));
        for (std::size_t j = 1; j < k; ++j)
            if (out.topology.devices[j].parent == d.parent &&
                out.topology.devices[j].parent_port == d.parent_port)
                throw esi::eni::EniError(
                    eni.where(d.line) + ": port " + std::string(1, char('A' + d.parent_port)) + " of slave " +
                    std::to_string(d.parent) + " is taken by slave " + std::to_string(j) + " already");
        if (d.parent_port == 0)
            throw esi::eni::EniError(eni.where(d.line) +
                                     ": PreviousPort A: port A of a slave faces the master");
    }
    // The ENI lists the slaves in the order a frame passes them (their auto-increment positions); the wiring
    // must give that order, through each ESC's ports in processing order A, D, B, C (ESC datasheet, "frame
    // processing"), or the master would not find the line it was configured for.
    auto child_at = [&](int parent, int port) {
        for (std::size_t j = 1; j < out.topology.devices.size(); ++j)
            if (out.topology.devices[j].parent == parent && out.topology.devices[j].parent_port == port)
                return static_cast<int>(j);
        return -1;
    };
    std::vector<int> order;
    std::vector<int> todo{0};
    while (!todo.empty()) {
        const int v = todo.back();
        todo.pop_back();
        order.push_back(v);
        for (int port : {2, 1, 3})  // pushed in reverse: D first, then B, then C
            if (const int c = child_at(v, port); c >= 0) todo.push_back(c);
    }
    for (std::size_t k = 0; k < order.size(); ++k)
        if (order[k] != static_cast<int>(k))
            throw esi::eni::EniError(eni.where(eni.slaves[static_cast<std::size_t>(order[k])].line) +
                                     ": slave " + std::to_string(order[k]) + " is at position " +
                                     std::to_string(k) +
                                     " by its PreviousPort wiring (ports in processing order A, D, B, C)");
    return out;
}

}  // namespace ecat_slave
