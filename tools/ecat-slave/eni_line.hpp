#pragma once
// `ecat-slave --eni FILE`: the line an ENI describes (docs/eni.md): one device per Config/Slave in the ENI's
// order, each plugged in where its PreviousPort says (a tree: port C or D of a four-port ESC), its serial
// number from Info/SerialNo, served from the ENI's own data (esi/eni/eni_product.hpp).
#include <memory>
#include <string>
#include <vector>

#include "od/product.hpp"
#include "slave/topology.hpp"

namespace ecat_slave {

struct EniLine {
    slave::Topology topology;
    std::vector<std::shared_ptr<const od::Product>> products;  // one per device
    std::vector<std::string>
        report;  // per slave: where its description came from (the device says its warnings)
};

// Throws esi::eni::EniError ("FILE:LINE: message").
EniLine eni_line(const std::string& file);

}  // namespace ecat_slave
