#pragma once
// `ecat-slave --eni FILE`: the line an ENI describes (docs/eni.md): one device per Config/Slave in the ENI's
// order, each plugged in where its PreviousPort says (a tree: port C or D of a four-port ESC), its serial
// number from Info/SerialNo, served from the ESI of esi_dir whose device has the slave's vendor id, product
// code and revision (esi::load_product), or else from the ENI's own data (esi/eni/eni_product.hpp).
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "esi/esi_reader.hpp"
#include "od/product.hpp"
#include "slave/topology.hpp"

namespace ecat_slave {

struct EniLine {
    slave::Topology topology;
    std::vector<std::shared_ptr<const od::Product>> products;  // one per device
    std::vector<std::string>
        report;  // per slave: where its description came from (the device says its warnings)
};

// The ESI files of a folder, indexed by the identity of each device they declare: every regular *.xml file
// directly in it is read once; a file that is not an ESI is left out and named in `skipped`.
struct EsiIndex {
    struct Found {
        std::shared_ptr<const esi::EsiFile> file;
        const esi::EsiDevice* device = nullptr;
        std::string path;
    };
    std::map<std::tuple<uint32_t, uint32_t, uint32_t>, Found> devices;  // (vendor, product, revision)
    std::vector<std::string> skipped;
};
// Throws std::runtime_error when the folder cannot be read.
EsiIndex index_esi_dir(const std::string& dir);

// Throws esi::eni::EniError ("FILE:LINE: message"), or esi::InputError for an ESI that matches a slave but
// cannot be served.
EniLine eni_line(const std::string& file, const EsiIndex* esis = nullptr);

}  // namespace ecat_slave
