// The ENI reader (ETG.2100 EtherCATConfig, see esi/eni/eni_reader.hpp) on libxml2's tree API.
#include "esi/eni/eni_reader.hpp"

#include <libxml/parser.h>
#include <libxml/tree.h>

#include <algorithm>
#include <cctype>
#include <limits>
#include <memory>

#include "util/input_file.hpp"
#include "xml_tree.hpp"

namespace esi::eni {

namespace {

using xml::child;
using xml::children;
using xml::is;
using xml::name_of;
using xml::Node;
using xml::text;
using xml::trim;

std::optional<std::string> attr(Node n, const char* name) {
    if (!n) return std::nullopt;
    xmlChar* v = xmlGetProp(n, reinterpret_cast<const xmlChar*>(name));
    if (!v) return std::nullopt;
    std::string s = reinterpret_cast<const char*>(v);
    xmlFree(v);
    return trim(s);
}
int line_of(Node n) {
    return n ? static_cast<int>(xmlGetLineNo(n)) : 0;
}

// Reads one document; every message names the file and the line of the element at fault.
class Reader {
  public:
    explicit Reader(std::string file) : file_(std::move(file)) {}

    [[noreturn]] void fail(Node n, const std::string& what) const {
        throw EniError(file_ + ":" + std::to_string(line_of(n)) + ": " + what);
    }
    Node require(Node parent, const char* name) const {
        Node c = child(parent, name);
        if (!c) fail(parent, "<" + name_of(parent) + "> has no <" + name + ">");
        return c;
    }

    // HexDecValue: "#x1A00" (also "0x1A00"), or decimal with an optional '-'.
    int64_t integer(Node where, const std::string& what, const std::string& s) const {
        auto bad = [&]() { fail(where, what + ": '" + s + "' is not a number (decimal or #x hexadecimal)"); };
        if (s.empty()) bad();
        std::size_t i = 0;
        int base = 10;
        bool neg = false;
        if (s.size() > 2 && (s.compare(0, 2, "#x") == 0 || s.compare(0, 2, "#X") == 0 ||
                             s.compare(0, 2, "0x") == 0 || s.compare(0, 2, "0X") == 0)) {
            base = 16;
            i = 2;
        } else if (s[0] == '-') {
            neg = true;
            i = 1;
        }
        if (i >= s.size()) bad();
        uint64_t v = 0;
        for (; i < s.size(); ++i) {
            const char c = s[i];
            int d = 0;
            if (c >= '0' && c <= '9')
                d = c - '0';
            else if (base == 16 && std::isxdigit(static_cast<unsigned char>(c)))
                d = std::tolower(static_cast<unsigned char>(c)) - 'a' + 10;
            else
                bad();
            if (v > (std::numeric_limits<uint64_t>::max() >> 5))
                fail(where, what + ": " + s + " is out of range");
            v = v * static_cast<uint64_t>(base) + static_cast<uint64_t>(d);
        }
        if (v > static_cast<uint64_t>(std::numeric_limits<int64_t>::max()))
            fail(where, what + ": " + s + " is out of range");
        return neg ? -static_cast<int64_t>(v) : static_cast<int64_t>(v);
    }
    int64_t ranged(Node where, const std::string& what, const std::string& s, int64_t lo, int64_t hi) const {
        const int64_t v = integer(where, what, s);
        if (v < lo || v > hi)
            fail(where, what + ": " + s + " is out of range (" + std::to_string(lo) + ".." +
                            std::to_string(hi) + ")");
        return v;
    }
    template <class T>
    T value(Node n, const std::string& what) const {
        return static_cast<T>(
            ranged(n, what, text(n), std::numeric_limits<T>::min(), std::numeric_limits<T>::max()));
    }
    // A 32-bit identifier or logical address: xs:int writes the top bit as a negative number.
    uint32_t bits32(Node n, const std::string& what) const {
        return static_cast<uint32_t>(ranged(n, what, text(n), std::numeric_limits<int32_t>::min(),
                                            std::numeric_limits<uint32_t>::max()));
    }
    uint16_t bits16(Node n, const std::string& what) const {
        return static_cast<uint16_t>(ranged(n, what, text(n), std::numeric_limits<int16_t>::min(),
                                            std::numeric_limits<uint16_t>::max()));
    }
    template <class T>
    T req(Node parent, const char* name) const {
        return value<T>(require(parent, name), name);
    }
    template <class T>
    std::optional<T> opt(Node parent, const char* name) const {
        Node c = child(parent, name);
        if (!c) return std::nullopt;
        return value<T>(c, name);
    }
    bool boolean(Node where, const std::string& what, const std::string& s) const {
        if (s == "true" || s == "1") return true;
        if (s == "false" || s == "0") return false;
        fail(where, what + ": '" + s + "' is not a boolean (true, false, 1, 0)");
    }
    bool opt_bool(Node parent, const char* name) const {
        Node c = child(parent, name);
        return c ? boolean(c, name, text(c)) : false;
    }
    bool bool_attr(Node n, const char* name) const {
        auto a = attr(n, name);
        return a ? boolean(n, std::string("attribute ") + name, *a) : false;
    }
    std::vector<uint8_t> hex(Node n, const std::string& what) const {
        std::string s;
        for (char c : text(n))
            if (!std::isspace(static_cast<unsigned char>(c))) s.push_back(c);
        if (s.size() % 2 != 0) fail(n, what + ": an odd number of hex digits");
        std::vector<uint8_t> out;
        out.reserve(s.size() / 2);
        for (std::size_t i = 0; i < s.size(); i += 2) {
            auto h = [&](char c) -> int {
                if (!std::isxdigit(static_cast<unsigned char>(c)))
                    fail(n, what + ": '" + c + "' is not a hex digit");
                return c <= '9' ? c - '0' : std::tolower(static_cast<unsigned char>(c)) - 'a' + 10;
            };
            out.push_back(static_cast<uint8_t>(h(s[i]) * 16 + h(s[i + 1])));
        }
        return out;
    }
    std::vector<std::string> transitions(Node n) const {
        std::vector<std::string> out;
        for (Node t : children(n, "Transition")) {
            std::string s = text(t);
            static const std::string states = "IPSOB";
            if (s.size() != 2 || states.find(s[0]) == std::string::npos ||
                states.find(s[1]) == std::string::npos)
                fail(t, "Transition: '" + s + "' is not a state transition (IP, PS, SO, OI, IB, ...)");
            out.push_back(s);
        }
        return out;
    }

    void datagram(Node n, uint8_t& cmd, uint16_t& adp, uint16_t& ado, std::optional<uint32_t>& addr,
                  std::optional<uint16_t>& cnt, std::string& comment) const {
        comment = text(child(n, "Comment"));
        cmd = req<uint8_t>(n, "Cmd");
        if (cmd > 14)
            fail(child(n, "Cmd"), "Cmd: " + std::to_string(cmd) + " is not an EtherCAT command (0..14)");
        if (Node a = child(n, "Addr")) {
            addr = bits32(a, "Addr");
        } else {
            if (Node p = child(n, "Adp")) adp = bits16(p, "Adp");
            ado = req<uint16_t>(n, "Ado");
        }
        cnt = opt<uint16_t>(n, "Cnt");
    }

    InitCmd init_cmd(Node n) const {
        InitCmd c;
        c.line = line_of(n);
        c.transitions = transitions(n);
        datagram(n, c.cmd, c.adp, c.ado, c.addr, c.cnt, c.comment);
        if (Node d = child(n, "Data")) c.data = hex(d, "Data");
        if (Node l = child(n, "DataLength")) c.data.assign(value<uint16_t>(l, "DataLength"), 0);
        if (c.data.size() > 1486)
            fail(n, "InitCmd: " + std::to_string(c.data.size()) + " bytes do not fit a frame");
        c.retries = opt<uint16_t>(n, "Retries").value_or(0);
        return c;
    }
    std::vector<InitCmd> init_cmds(Node parent) const {
        std::vector<InitCmd> out;
        for (Node n : children(child(parent, "InitCmds"), "InitCmd"))
            out.push_back(init_cmd(n));
        return out;
    }

    CoeInitCmd coe_init_cmd(Node n) const {
        CoeInitCmd c;
        c.line = line_of(n);
        c.transitions = transitions(n);
        if (c.transitions.empty()) fail(n, "CoE InitCmd without a Transition");
        c.comment = text(child(n, "Comment"));
        c.ccs = req<uint8_t>(n, "Ccs");
        if (c.ccs != 1 && c.ccs != 2)
            fail(child(n, "Ccs"),
                 "Ccs: " + std::to_string(c.ccs) + " is neither 1 (download) nor 2 (upload)");
        c.index = req<uint16_t>(n, "Index");
        c.subindex = req<uint8_t>(n, "SubIndex");
        if (Node d = child(n, "Data")) c.data = hex(d, "Data");
        c.complete_access = bool_attr(n, "CompleteAccess");
        c.fixed = bool_attr(n, "Fixed");
        c.disabled = opt_bool(n, "Disabled");
        c.timeout_ms = opt<uint32_t>(n, "Timeout").value_or(0);
        return c;
    }

    MailboxArea area(Node n) const {
        return MailboxArea{req<uint16_t>(n, "Start"), req<uint16_t>(n, "Length")};
    }

    Mailbox mailbox(Node n) const {
        Mailbox m;
        if (!n) return m;
        m.present = true;
        m.line = line_of(n);
        m.send = area(require(n, "Send"));
        m.recv = area(require(n, "Recv"));
        Node boot = child(n, "Bootstrap");
        if (!boot) boot = child(n, "BootStrap");
        if (boot) {
            m.bootstrap_send = area(require(boot, "Send"));
            m.bootstrap_recv = area(require(boot, "Recv"));
        }
        static const std::vector<std::string> known = {"AoE", "EoE", "CoE", "FoE", "SoE", "VoE"};
        for (Node p : children(n, "Protocol")) {
            std::string s = text(p);
            if (std::find(known.begin(), known.end(), s) == known.end())
                fail(p, "Protocol: '" + s + "' is not a mailbox protocol (AoE, EoE, CoE, FoE, SoE, VoE)");
            m.protocols.push_back(s);
        }
        for (Node c : children(child(child(n, "CoE"), "InitCmds"), "InitCmd"))
            m.coe_init_cmds.push_back(coe_init_cmd(c));
        for (const char* proto : {"EoE", "SoE", "AoE", "FoE", "VoE"}) {
            const auto cmds = children(child(child(n, proto), "InitCmds"), "InitCmd");
            if (!cmds.empty()) m.other_init_cmds.emplace_back(proto, static_cast<int>(cmds.size()));
        }
        return m;
    }

    Pdo pdo(Node n, bool rx) const {
        Pdo p;
        p.rx = rx;
        p.line = line_of(n);
        p.index = req<uint16_t>(n, "Index");
        if (auto sm = attr(n, "Sm")) p.sm = static_cast<int>(ranged(n, "attribute Sm", *sm, 0, 15));
        p.fixed = bool_attr(n, "Fixed");
        p.mandatory = bool_attr(n, "Mandatory");
        p.name = text(child(n, "Name"));
        for (Node e : children(n, "Entry")) {
            PdoEntry pe;
            pe.index = req<uint16_t>(e, "Index");
            pe.subindex = opt<uint8_t>(e, "SubIndex").value_or(0);
            pe.bit_len = req<uint16_t>(e, "BitLen");
            pe.name = text(child(e, "Name"));
            pe.data_type = text(child(e, "DataType"));
            if (pe.index != 0 && pe.data_type.empty()) fail(e, "PDO entry without a DataType");
            if (pe.bit_len == 0) fail(e, "PDO entry of 0 bits");
            p.entries.push_back(std::move(pe));
        }
        return p;
    }

    ProcessData process_data(Node n) const {
        ProcessData pd;
        if (!n) return pd;
        auto range = [&](Node r) {
            return BitRange{req<uint32_t>(r, "BitStart"), req<uint32_t>(r, "BitLength")};
        };
        for (Node s : children(n, "Send"))
            pd.send.push_back(range(s));
        for (Node r : children(n, "Recv"))
            pd.recv.push_back(range(r));
        for (int k = 0; k < 8; ++k) {
            const std::string tag = "Sm" + std::to_string(k);
            for (Node s : children(n, tag.c_str())) {
                Sm sm;
                sm.number = k;
                sm.line = line_of(s);
                sm.type = text(child(s, "Type"));
                if (sm.type != "MBoxOut" && sm.type != "MBoxIn" && sm.type != "Outputs" &&
                    sm.type != "Inputs")
                    fail(s, tag + "/Type: '" + sm.type + "' is not MBoxOut, MBoxIn, Outputs or Inputs");
                sm.start = req<uint16_t>(s, "StartAddress");
                sm.control = req<uint8_t>(s, "ControlByte");
                sm.enable = boolean(require(s, "Enable"), "Enable", text(child(s, "Enable")));
                sm.default_size = opt<uint16_t>(s, "DefaultSize").value_or(0);
                sm.min_size = opt<uint16_t>(s, "MinSize");
                sm.max_size = opt<uint16_t>(s, "MaxSize");
                for (Node p : children(s, "Pdo"))
                    sm.pdos.push_back(value<uint16_t>(p, tag + "/Pdo"));
                if (pd.sm(k)) fail(s, tag + " twice");
                pd.sms.push_back(std::move(sm));
            }
        }
        for (Node p : children(n, "RxPdo"))
            pd.rxpdos.push_back(pdo(p, true));
        for (Node p : children(n, "TxPdo"))
            pd.txpdos.push_back(pdo(p, false));
        // Dangling references: an SM's Pdo or a PDO's Sm must name one declared here.
        for (const Sm& sm : pd.sms)
            for (uint16_t idx : sm.pdos) {
                const Pdo* p = pd.pdo(idx);
                if (!p)
                    fail(child(n, ("Sm" + std::to_string(sm.number)).c_str()),
                         "Sm" + std::to_string(sm.number) + " assigns PDO " + hex16(idx) +
                             ", which this slave does not declare");
            }
        for (const auto* list : {&pd.rxpdos, &pd.txpdos})
            for (const Pdo& p : *list) {
                if (p.sm && !pd.sms.empty() && !pd.sm(*p.sm))
                    throw EniError(file_ + ":" + std::to_string(p.line) + ": PDO " + hex16(p.index) +
                                   " is assigned to Sm" + std::to_string(*p.sm) +
                                   ", which this slave does not declare");
                if (p.sm) {
                    const Sm* sm = pd.sm(*p.sm);
                    if (sm && sm->type != (p.rx ? "Outputs" : "Inputs"))
                        throw EniError(file_ + ":" + std::to_string(p.line) + ": " +
                                       (p.rx ? "RxPdo " : "TxPdo ") + hex16(p.index) + " is assigned to Sm" +
                                       std::to_string(*p.sm) + " of type " + sm->type);
                }
            }
        return pd;
    }

    static std::string hex16(uint16_t v) {
        static const char* digits = "0123456789ABCDEF";
        std::string s = "0x";
        for (int shift = 12; shift >= 0; shift -= 4)
            s.push_back(digits[(v >> shift) & 0xF]);
        return s;
    }

    Dc dc(Node n) const {
        Dc d;
        if (!n) return d;
        d.present = true;
        d.line = line_of(n);
        d.potential_reference_clock = opt_bool(n, "PotentialReferenceClock");
        d.reference_clock = opt_bool(n, "ReferenceClock");
        d.cycle_time0 = opt<uint32_t>(n, "CycleTime0");
        d.cycle_time1 = opt<int32_t>(n, "CycleTime1");
        d.shift_time0 = opt<int32_t>(n, "ShiftTime0");
        if (!d.shift_time0) d.shift_time0 = opt<int32_t>(n, "ShiftTime");
        d.shift_time1 = opt<int32_t>(n, "ShiftTime1");
        if (Node a = child(n, "AssignActivate")) d.assign_activate = value<uint16_t>(a, "AssignActivate");
        return d;
    }

    Slave slave(Node n) const {
        Slave s;
        s.line = line_of(n);
        Node info = require(n, "Info");
        s.info.name = text(child(info, "Name"));
        s.info.phys_addr = req<uint16_t>(info, "PhysAddr");
        if (Node a = child(info, "AutoIncAddr")) s.info.auto_inc_addr = bits16(a, "AutoIncAddr");
        s.info.vendor_id = bits32(require(info, "VendorId"), "VendorId");
        s.info.product_code = bits32(require(info, "ProductCode"), "ProductCode");
        s.info.revision = bits32(require(info, "RevisionNo"), "RevisionNo");
        if (Node sn = child(info, "SerialNo")) s.info.serial = bits32(sn, "SerialNo");
        if (Node p = child(info, "Physics")) {
            xmlChar* t = xmlNodeGetContent(p);  // blanks are meaningful here (a port without a PHY)
            s.info.physics = t ? reinterpret_cast<const char*>(t) : "";
            xmlFree(t);
        }
        s.process_data = process_data(child(n, "ProcessData"));
        s.mailbox = mailbox(child(n, "Mailbox"));
        s.init_cmds = init_cmds(n);
        for (Node p : children(n, "PreviousPort")) {
            PreviousPort pp;
            pp.line = line_of(p);
            pp.selected = bool_attr(p, "Selected");
            Node port = require(p, "Port");
            const std::string letter = text(port);
            if (letter.size() != 1 || letter[0] < 'A' || letter[0] > 'D')
                fail(port, "Port: '" + letter + "' is not a port (A, B, C, D)");
            pp.port = letter[0] - 'A';
            pp.phys_addr = req<uint16_t>(p, "PhysAddr");
            s.previous_ports.push_back(pp);
        }
        s.dc = dc(child(n, "DC"));
        return s;
    }

    CyclicCmd cyclic_cmd(Node n) const {
        CyclicCmd c;
        c.line = line_of(n);
        std::string state;
        for (Node st : children(n, "State")) {
            if (!state.empty()) state += ' ';
            state += text(st);
        }
        c.state = state;
        datagram(n, c.cmd, c.adp, c.ado, c.addr, c.cnt, c.comment);
        c.data_length = req<uint16_t>(n, "DataLength");
        c.input_offs = opt<uint32_t>(n, "InputOffs");
        c.output_offs = opt<uint32_t>(n, "OutputOffs");
        return c;
    }

    Config config(xmlDoc* doc) const {
        Node root = xmlDocGetRootElement(doc);
        if (!root) throw EniError(file_ + ": an empty document: not an ENI (EtherCATConfig) file");
        if (!is(root, "EtherCATConfig"))
            fail(root,
                 "the root element is <" + name_of(root) + ">, not <EtherCATConfig>: not an ENI file" +
                     (name_of(root) == "EtherCATInfo" ? " (an ESI file: give it with --esi or --esi-dir)"
                                                      : ""));
        Node cfg = require(root, "Config");
        Config c;
        c.file = file_;
        if (Node m = child(cfg, "Master")) {
            Node info = child(m, "Info");
            c.master.name = text(child(info, "Name"));
            if (Node d = child(info, "Destination")) c.master.destination = hex(d, "Destination");
            if (Node s = child(info, "Source")) c.master.source = hex(s, "Source");
            c.master.init_cmds = init_cmds(m);
        }
        const auto slaves = children(cfg, "Slave");
        if (slaves.size() > 1000) fail(slaves[1000], "more than 1000 slaves");
        for (Node s : slaves)
            c.slaves.push_back(slave(s));
        for (Node cy : children(cfg, "Cyclic")) {
            Cyclic cyc;
            cyc.cycle_time = opt<uint32_t>(cy, "CycleTime");
            for (Node f : children(cy, "Frame")) {
                Frame fr;
                for (Node cmd : children(f, "Cmd"))
                    fr.cmds.push_back(cyclic_cmd(cmd));
                cyc.frames.push_back(std::move(fr));
            }
            c.cyclic.push_back(std::move(cyc));
        }
        if (Node img = child(cfg, "ProcessImage")) {
            if (Node in = child(img, "Inputs")) c.input_bytes = opt<uint32_t>(in, "ByteSize").value_or(0);
            if (Node out = child(img, "Outputs")) c.output_bytes = opt<uint32_t>(out, "ByteSize").value_or(0);
        }
        // The wiring: station addresses are unique, and a PreviousPort names a slave before this one.
        for (std::size_t i = 0; i < c.slaves.size(); ++i) {
            const Slave& s = c.slaves[i];
            const int first = c.find_phys_addr(s.info.phys_addr);
            if (first != static_cast<int>(i))
                throw EniError(c.where(s.line) + ": PhysAddr " + std::to_string(s.info.phys_addr) +
                               " is the station address of slave " + std::to_string(first) + " already");
            for (const PreviousPort& pp : s.previous_ports) {
                const int up = c.find_phys_addr(pp.phys_addr);
                if (up < 0 || up >= static_cast<int>(i))
                    throw EniError(c.where(pp.line) + ": PreviousPort PhysAddr " +
                                   std::to_string(pp.phys_addr) +
                                   " is not the station address of a slave before this one");
            }
        }
        return c;
    }

  private:
    std::string file_;
};

// Where in the text the DOCTYPE is (its line), for the message.
int doctype_line(const std::string& xml) {
    const auto at = xml.find("<!DOCTYPE");
    if (at == std::string::npos) return 1;
    return 1 + static_cast<int>(std::count(xml.begin(), xml.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

struct DocFree {
    void operator()(xmlDoc* d) const { xmlFreeDoc(d); }
};
struct CtxtFree {
    void operator()(xmlParserCtxt* c) const { xmlFreeParserCtxt(c); }
};

}  // namespace

uint16_t Mailbox::protocol_bits() const {
    uint16_t bits = 0;
    for (const std::string& p : protocols) {
        if (p == "AoE") bits |= 0x01;
        if (p == "EoE") bits |= 0x02;
        if (p == "CoE") bits |= 0x04;
        if (p == "FoE") bits |= 0x08;
        if (p == "SoE") bits |= 0x10;
        if (p == "VoE") bits |= 0x20;
    }
    return bits;
}

bool Mailbox::has(const std::string& protocol) const {
    return std::find(protocols.begin(), protocols.end(), protocol) != protocols.end();
}

unsigned Pdo::bits() const {
    unsigned b = 0;
    for (const PdoEntry& e : entries)
        b += e.bit_len;
    return b;
}

const Sm* ProcessData::sm(int number) const {
    for (const Sm& s : sms)
        if (s.number == number) return &s;
    return nullptr;
}

const Pdo* ProcessData::pdo(uint16_t index) const {
    for (const auto* list : {&rxpdos, &txpdos})
        for (const Pdo& p : *list)
            if (p.index == index) return &p;
    return nullptr;
}

const PreviousPort* Slave::previous_port() const {
    for (const PreviousPort& p : previous_ports)
        if (p.selected) return &p;
    return previous_ports.empty() ? nullptr : &previous_ports.front();
}

std::optional<uint16_t> Slave::assign_activate() const {
    // Register 0x0980 (cyclic unit control) and 0x0981 (activation): TwinCAT writes 0x0980 as one word, the
    // AssignActivate of the ESI op mode (ETG.2000 OpMode/AssignActivate, ESC datasheet "DC activation").
    for (const InitCmd& c : init_cmds) {
        if (c.addr) continue;
        if (c.ado == 0x0980 && c.data.size() >= 2) return static_cast<uint16_t>(c.data[0] | (c.data[1] << 8));
        if (c.ado == 0x0981 && !c.data.empty()) return static_cast<uint16_t>(c.data[0] << 8);
    }
    return dc.assign_activate;
}

uint32_t Slave::output_bits() const {
    uint32_t b = 0;
    for (const BitRange& r : process_data.send)
        b += r.length;
    return b;
}

uint32_t Slave::input_bits() const {
    uint32_t b = 0;
    for (const BitRange& r : process_data.recv)
        b += r.length;
    return b;
}

std::string Config::where(int line) const {
    return file + ":" + std::to_string(line);
}

int Config::find_phys_addr(uint16_t phys_addr) const {
    for (std::size_t i = 0; i < slaves.size(); ++i)
        if (slaves[i].info.phys_addr == phys_addr) return static_cast<int>(i);
    return -1;
}

// An ENI is untrusted input as an ESI is (esi_reader.cpp, docs/robustness.md): parsed from memory (read
// through the one bounded reader), no network (XML_PARSE_NONET), no external DTD, no entity substitution,
// libxml2's limits on depth kept (no XML_PARSE_HUGE); a document with a DOCTYPE is refused altogether
// (ETG.2100 files carry none).
Config read_eni_text(const std::string& xml, const std::string& name) {
    if (xml.size() > kMaxEniBytes)
        throw EniError(name + ": larger than " + std::to_string(kMaxEniBytes) + " bytes: not an ENI file");
    if (xml.find_first_not_of(" \t\r\n") == std::string::npos)
        throw EniError(name + ": an empty file: not an ENI (EtherCATConfig) file");
    std::unique_ptr<xmlParserCtxt, CtxtFree> ctxt(xmlNewParserCtxt());
    if (!ctxt) throw EniError(name + ": out of memory");
    std::unique_ptr<xmlDoc, DocFree> doc(
        xmlCtxtReadMemory(ctxt.get(), xml.data(), static_cast<int>(xml.size()), name.c_str(), nullptr,
                          XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING | XML_PARSE_BIG_LINES));
    if (doc && (doc->intSubset != nullptr || doc->extSubset != nullptr))
        throw EniError(name + ":" + std::to_string(doctype_line(xml)) +
                       ": a DOCTYPE (DTD or entity declarations) is not allowed in an ENI file");
    if (!doc) {
        const xmlError* e = xmlCtxtGetLastError(ctxt.get());
        std::string msg = e && e->message ? trim(e->message) : "not well-formed XML";
        if (xml.find("<!DOCTYPE") != std::string::npos)
            throw EniError(name + ":" + std::to_string(doctype_line(xml)) +
                           ": a DOCTYPE (DTD or entity declarations) is not allowed in an ENI file");
        throw EniError(name + ":" + std::to_string(e ? e->line : 0) + ": not well-formed XML: " + msg);
    }
    return Reader(name).config(doc.get());
}

Config read_eni_file(const std::string& path) {
    std::string text;
    try {
        text = util::read_input_file(path, kMaxEniBytes, "ENI file");
    } catch (const util::InputFileError& e) {
        throw EniError(e.what());
    }
    return read_eni_text(text, path);
}

}  // namespace esi::eni
