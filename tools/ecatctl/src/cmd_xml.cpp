// ecatctl xml [slave] [-o FILE]: an ESI file (ETG.2000, EtherCATInfo schema 1.14) built from what the slave
// itself reports - the SII (identity, name, group, SMs, FMMUs, mailbox, protocols, CoE details, DC modes,
// ConfigData) and the SDO information service (the object dictionary with types, access, PDO mapping
// flags, every PDO mapping object and its entries) - for a slave whose vendor file is lost. The PDOs
// assigned now are marked with their SM. Values and limits are not carried (SDO information gives them only
// per entry on request, and a configuration tool does not need them to configure the slave).
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <set>

#include "cmd_verbs.hpp"
#include "coe_view.hpp"
#include "esi/sii_reader.hpp"
#include "format.hpp"
#include "util/le.hpp"

namespace ecatctl {

namespace {

using master::Error;

struct XmlArgs {
    SlaveArg slave;
    std::string output;
};

std::string esc(const std::string& s) {
    std::string o;
    for (char c : s) {
        switch (c) {
            case '<':
                o += "&lt;";
                break;
            case '>':
                o += "&gt;";
                break;
            case '&':
                o += "&amp;";
                break;
            case '"':
                o += "&quot;";
                break;
            default:
                if (static_cast<unsigned char>(c) >= 0x20 || c == '\t') o += c;
        }
    }
    return o;
}

// Each line of `text` (every line ends with '\n') with `indent` before it.
std::string indented(const std::string& text, const std::string& indent) {
    std::string out;
    for (std::size_t i = 0; i < text.size();) {
        const std::size_t nl = text.find('\n', i);
        out += indent + text.substr(i, nl - i + 1);
        i = nl + 1;
    }
    return out;
}

std::string hx(uint64_t v, int digits = 0) {
    char b[24];
    std::snprintf(b, sizeof b, "#x%0*llx", digits, static_cast<unsigned long long>(v));
    return b;
}

std::string hex_upper(std::span<const uint8_t> d) {
    std::string s;
    char b[4];
    for (uint8_t x : d) {
        std::snprintf(b, sizeof b, "%02X", x);
        s += b;
    }
    return s;
}

// The ESI type name of an entry and its bit size, registered for the DataTypes section.
std::string type_of(const EntryView& e, std::map<std::string, unsigned>& types) {
    std::string name;
    switch (e.data_type) {
        case dtype::VisibleString:
            name = "STRING(" + std::to_string(e.bit_length / 8) + ")";
            break;
        case dtype::OctetString:
            name = e.bit_length < 8 ? "ARRAY [0..0] OF BYTE"
                                    : "ARRAY [0.." + std::to_string(e.bit_length / 8 - 1) + "] OF BYTE";
            break;
        case dtype::UnicodeString:
            name = "UNICODE_STRING(" + std::to_string(e.bit_length / 16) + ")";
            break;
        default:
            name = std::string(esi_type_name(e.data_type));
            if (e.data_type == dtype::Boolean && e.bit_length == 1) name = "BOOL";
            if (name.empty()) {
                char b[16];
                std::snprintf(b, sizeof b, "DT%04X", e.data_type);
                name = b;
            }
    }
    types.emplace(name, e.bit_length);
    return name;
}

std::string access_flags(uint16_t access, const char* indent) {
    const bool r = access & 0x07, w = access & 0x38;
    std::string s = std::string(indent) + "<Flags>\n" + indent + "  <Access>" +
                    (w ? (r ? "rw" : "wo") : "ro") + "</Access>\n";
    const bool rx = access & 0x40, tx = access & 0x80;
    if (rx || tx)
        s += std::string(indent) + "  <PdoMapping>" + (rx && tx ? "RT" : rx ? "R" : "T") + "</PdoMapping>\n";
    return s + indent + "</Flags>\n";
}

struct PdoObject {
    PdoView view;
    int sm = -1;
    bool rx = false;  // the direction of the SM that assigns it, else the SII's PDO category, else the range
};

Error read_mapping(master::SdoClient& sdo, uint16_t index, PdoView& pv) {
    uint8_t b[4] = {};
    auto n = sdo.upload(index, 0, b);
    if (!n) return n.error();
    pv.index = index;
    for (unsigned k = 1; k <= b[0]; ++k) {
        uint8_t v[4] = {};
        auto m = sdo.upload(index, static_cast<uint8_t>(k), v);
        if (!m) return m.error();
        PdoEntryView e;
        e.index = util::get16(v + 2);
        e.subindex = v[1];
        e.bit_length = v[0];
        if (e.index != 0)
            if (auto d = sdo.entry_description(e.index, e.subindex, 0)) {
                e.name = d->name;
                e.data_type = d->data_type;
            }
        pv.entries.push_back(std::move(e));
    }
    return Error::Ok;
}

// ETG.2000 Device Physics from the SII General category's physical ports (ETG.2010 bytes 16-17, 4 bits a
// port: 1 MII -> Y, 3 EBUS -> K, 4 fast hot connect -> H, 0 not used -> a blank; trailing blanks dropped).
// Two MII ports when the SII says none or port 0 is not used.
std::string physics_of(uint16_t ports) {
    std::string p;
    for (int k = 0; k < 4; ++k) {
        const unsigned n = (ports >> (4 * k)) & 0x0Fu;
        p += n == 1 ? 'Y' : n == 3 ? 'K' : n == 4 ? 'H' : ' ';
    }
    while (!p.empty() && p.back() == ' ')
        p.pop_back();
    return p.empty() || p[0] == ' ' ? "YY" : p;
}

int run_xml(master::Master& m, const XmlArgs& x) {
    auto a = x.slave.address();
    if (!a) return kExitUsage;
    auto img = m.sii_read_image(*a);
    if (!img) return report_error(nullptr, img.error(), "reading the SII of " + slave_label(*a));
    const esi::SiiInfo sii = esi::parse_sii(*img);
    const bool coe = (sii.mailbox_protocols & 0x04) != 0;

    std::map<std::string, unsigned> types;  // base types used, with their bit size
    std::string structured;                 // DataType elements of ARRAY/RECORD objects
    std::string objects;
    std::map<uint16_t, PdoObject> pdos;
    if (coe) {
        master::Mailbox mbx(m, *a);
        if (Error e = open_coe_mailbox(m, mbx, *a); e != Error::Ok)
            return report_error(nullptr, e, "opening the mailbox of " + slave_label(*a));
        master::SdoClient sdo(mbx);
        auto list = sdo.od_list(1);
        if (!list) return report_error(&sdo, list.error(), "reading the object list (SDO information)");
        for (uint16_t index : *list) {
            auto od = sdo.object_description(index);
            if (!od) return report_error(&sdo, od.error(), "describing object " + hx(index, 4));
            std::vector<EntryView> entries;
            if (Error e = describe_entries(sdo, index, od->object_code == 7 ? 0 : od->max_subindex, entries);
                e != Error::Ok)
                return report_error(&sdo, e, "describing the entries of " + hx(index, 4));
            if (entries.empty()) continue;
            std::string o = "          <Object>\n            <Index>" + hx(index, 4) +
                            "</Index>\n            <Name>" + esc(od->name) + "</Name>\n";
            if (od->object_code == 7) {
                const EntryView& e = entries.front();
                o += "            <Type>" + esc(type_of(e, types)) + "</Type>\n            <BitSize>" +
                     std::to_string(e.bit_length) + "</BitSize>\n" + access_flags(e.access, "            ");
            } else {
                char dtn[16];
                std::snprintf(dtn, sizeof dtn, "DT%04X", index);
                std::string sub;
                unsigned bit = 0;
                for (const auto& e : entries) {
                    const unsigned bits = e.subindex == 0 ? 8 : e.bit_length;
                    if (bits % 8 == 0) bit = (bit + 7) / 8 * 8;
                    std::string name = e.name.empty() ? "SubIndex " + std::to_string(e.subindex) : e.name;
                    sub += "          <SubItem>\n            <SubIdx>" + std::to_string(e.subindex) +
                           "</SubIdx>\n            <Name>" + esc(name) + "</Name>\n            <Type>" +
                           esc(type_of(e, types)) + "</Type>\n            <BitSize>" + std::to_string(bits) +
                           "</BitSize>\n            <BitOffs>" + std::to_string(bit) + "</BitOffs>\n" +
                           access_flags(e.access, "            ") + "          </SubItem>\n";
                    bit += e.subindex == 0 ? 16 : bits;
                }
                structured += std::string("        <DataType>\n          <Name>") + dtn +
                              "</Name>\n          <BitSize>" + std::to_string(bit) + "</BitSize>\n" + sub +
                              "        </DataType>\n";
                o += std::string("            <Type>") + dtn + "</Type>\n            <BitSize>" +
                     std::to_string(bit) + "</BitSize>\n";
            }
            objects += o + "          </Object>\n";
            // A mapping object: one in the standard ranges, or one the SII's PDO categories name (a device
            // may put its PDOs at other indices; the direction is then the category's, not the range's).
            bool sii_rx = false, sii_tx = false;
            for (const auto& sp : sii.rx_pdos)
                sii_rx = sii_rx || sp.index == index;
            for (const auto& sp : sii.tx_pdos)
                sii_tx = sii_tx || sp.index == index;
            const bool range_rx = index >= 0x1600 && index <= 0x17FF;
            const bool range_tx = index >= 0x1A00 && index <= 0x1BFF;
            if (sii_rx || sii_tx || range_rx || range_tx) {
                PdoObject p;
                p.rx = sii_rx || (!sii_tx && range_rx);
                p.view.name = od->name;
                if (Error e = read_mapping(sdo, index, p.view); e != Error::Ok)
                    return report_error(&sdo, e, "reading PDO mapping " + hx(index, 4));
                pdos[index] = std::move(p);
            }
        }
        std::vector<SyncView> syncs;
        if (Error e = read_pdo_config(sdo, syncs, false); e != Error::Ok)
            return report_error(&sdo, e, "reading the PDO assignment");
        for (const auto& sv : syncs)
            for (const auto& p : sv.pdos)
                if (auto it = pdos.find(p.index); it != pdos.end()) {
                    it->second.sm = sv.sm;
                    it->second.rx = sv.output;  // the SM's direction is the PDO's
                }
    }

    std::string x_out;
    auto w = [&](const std::string& s) { x_out += s; };
    const std::string dev_name =
        sii.general && !sii.general->name.empty() ? sii.general->name : "Device " + hx(sii.product_code, 8);
    const std::string group = sii.general && !sii.general->group.empty() ? sii.general->group : "Devices";
    const std::string order = sii.general && !sii.general->order.empty() ? sii.general->order : dev_name;
    w("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    w("<!-- Built by ecatctl xml from the slave's SII and SDO information (no vendor file). -->\n");
    w("<EtherCATInfo xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
      "xsi:noNamespaceSchemaLocation=\"EtherCATInfo.xsd\" Version=\"1.14\">\n");
    w("  <Vendor>\n    <Id>" + hx(sii.vendor_id, 8) + "</Id>\n    <Name LcId=\"1033\">Vendor " +
      hx(sii.vendor_id, 8) + "</Name>\n  </Vendor>\n");
    w("  <Descriptions>\n    <Groups>\n      <Group>\n        <Type>" + esc(group) +
      "</Type>\n        <Name LcId=\"1033\">" + esc(group) +
      "</Name>\n      </Group>\n    </Groups>\n    <Devices>\n");
    w("      <Device Physics=\"" + physics_of(sii.general ? sii.general->physical_ports : 0) +
      "\">\n        <Type ProductCode=\"" + hx(sii.product_code, 8) + "\" RevisionNo=\"" +
      hx(sii.revision, 8) + "\">" + esc(order) + "</Type>\n");
    w("        <Name LcId=\"1033\">" + esc(dev_name) + "</Name>\n");
    w("        <GroupType>" + esc(group) + "</GroupType>\n");
    if (coe) {
        w("        <Profile>\n");
        if (sii.general && sii.general->ds402_channels) w("          <ProfileNo>402</ProfileNo>\n");
        w("          <Dictionary>\n            <DataTypes>\n");
        for (const auto& [name, bits] : types)
            w("              <DataType>\n                <Name>" + esc(name) +
              "</Name>\n                <BitSize>" + std::to_string(bits) +
              "</BitSize>\n              </DataType>\n");
        // Structured types, indented one level deeper.
        w(indented(structured, "      "));
        w("            </DataTypes>\n            <Objects>\n");
        w(indented(objects, "    "));
        w("            </Objects>\n          </Dictionary>\n        </Profile>\n");
    }
    for (uint8_t f : sii.fmmus) {
        const char* t = f == 1 ? "Outputs" : f == 2 ? "Inputs" : f == 3 ? "MBoxState" : "";
        w(std::string("        <Fmmu>") + t + "</Fmmu>\n");
    }
    for (const auto& sm : sii.sync_managers) {
        static const char* const kSm[] = {"", "MBoxOut", "MBoxIn", "Outputs", "Inputs"};
        const char* t = sm.type <= 4 ? kSm[sm.type] : "";
        std::string s = std::string("        <Sm");
        if (sm.length) s += " DefaultSize=\"" + std::to_string(sm.length) + "\"";
        s += " StartAddress=\"" + hx(sm.start, 4) + "\" ControlByte=\"" + hx(sm.control, 2) + "\" Enable=\"" +
             std::to_string(sm.enable & 1u) + "\">" + t + "</Sm>\n";
        w(s);
    }
    for (bool rx : {true, false})
        for (const auto& [index, p] : pdos) {
            if (p.rx != rx) continue;
            std::string s = std::string("        <") + (rx ? "RxPdo" : "TxPdo");
            if (p.sm >= 0) s += " Sm=\"" + std::to_string(p.sm) + "\"";
            s += ">\n          <Index>" + hx(index, 4) + "</Index>\n          <Name LcId=\"1033\">" +
                 esc(p.view.name) + "</Name>\n";
            for (const auto& e : p.view.entries) {
                s += "          <Entry>\n            <Index>" + hx(e.index, 4) + "</Index>\n";
                if (e.index != 0)
                    s += "            <SubIndex>" + std::to_string(e.subindex) + "</SubIndex>\n";
                s += "            <BitLen>" + std::to_string(e.bit_length) + "</BitLen>\n";
                if (e.index != 0) {
                    s += "            <Name LcId=\"1033\">" + esc(e.name) + "</Name>\n";
                    EntryView ev;
                    ev.data_type = e.data_type;
                    ev.bit_length = e.bit_length;
                    std::map<std::string, unsigned> unused;
                    if (e.data_type != 0)
                        s += "            <DataType>" + esc(type_of(ev, unused)) + "</DataType>\n";
                }
                s += "          </Entry>\n";
            }
            w(s + "        </" + (rx ? "RxPdo" : "TxPdo") + ">\n");
        }
    if (sii.mailbox_protocols) {
        const uint16_t p = sii.mailbox_protocols;
        const uint8_t cd = sii.general ? sii.general->coe_details : 0;
        auto b = [](bool v) { return v ? "true" : "false"; };
        w("        <Mailbox DataLinkLayer=\"true\">\n");
        if (p & 0x01) w("          <AoE/>\n");
        if (p & 0x02) w("          <EoE/>\n");
        if (p & 0x04)
            w(std::string("          <CoE SdoInfo=\"") + b(cd & 0x02) + "\" PdoAssign=\"" + b(cd & 0x04) +
              "\" PdoConfig=\"" + b(cd & 0x08) + "\" PdoUpload=\"" + b(cd & 0x10) + "\" CompleteAccess=\"" +
              b(cd & 0x20) + "\"/>\n");
        if (p & 0x08) w("          <FoE/>\n");
        if (p & 0x10) w("          <SoE/>\n");
        if (p & 0x20) w("          <VoE/>\n");
        w("        </Mailbox>\n");
    }
    if (!sii.dc_modes.empty()) {
        w("        <Dc>\n");
        for (const auto& d : sii.dc_modes) {
            w("          <OpMode>\n            <Name>" + esc(d.name.empty() ? "DC" : d.name) + "</Name>\n");
            if (!d.description.empty()) w("            <Desc>" + esc(d.description) + "</Desc>\n");
            w("            <AssignActivate>" + hx(d.assign_activate) + "</AssignActivate>\n");
            if (d.assign_activate != 0)
                w("            <CycleTimeSync0 Factor=\"" + std::to_string(d.sync0_cycle_factor) +
                  "\">0</CycleTimeSync0>\n            <ShiftTimeSync0>" + std::to_string(d.sync0_shift_time) +
                  "</ShiftTimeSync0>\n");
            w("          </OpMode>\n");
        }
        w("        </Dc>\n");
    }
    w("        <Eeprom>\n          <ByteSize>" + std::to_string(sii.eeprom_bytes()) + "</ByteSize>\n");
    if (img->size() >= 16)
        w("          <ConfigData>" + hex_upper(std::span<const uint8_t>(*img).subspan(0, 14)) +
          "</ConfigData>\n");
    if (img->size() >= 0x30 && sii.bootstrap_mailbox.out_size != 0)
        w("          <BootStrap>" + hex_upper(std::span<const uint8_t>(*img).subspan(0x28, 8)) +
          "</BootStrap>\n");
    w("        </Eeprom>\n      </Device>\n    </Devices>\n  </Descriptions>\n</EtherCATInfo>\n");

    if (x.output.empty() || x.output == "-") {
        std::fwrite(x_out.data(), 1, x_out.size(), stdout);
        return kExitOk;
    }
    std::ofstream f(x.output, std::ios::binary | std::ios::trunc);
    f << x_out;
    if (!f) {
        std::fprintf(stderr, "ecatctl: cannot write %s\n", x.output.c_str());
        return kExitFailure;
    }
    return kExitOk;
}

}  // namespace

void add_xml_command(CLI::App& app, MasterRunner run, int& rc) {
    auto x = std::make_shared<XmlArgs>();
    auto* c = app.add_subcommand("xml", "Write an ESI file built from the slave's SII and SDO information");
    x->slave.add_to(c);
    c->add_option("-o,--output", x->output, "Write it to this file ('-': stdout, the default)");
    c->callback(
        [x, run = std::move(run), &rc] { rc = run([&](master::Master& m) { return run_xml(m, *x); }); });
}

}  // namespace ecatctl
