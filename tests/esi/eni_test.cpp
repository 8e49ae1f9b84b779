// The ENI reader (esi/eni/eni_reader.hpp) and the ENI slave -> od::Product conversion
// (esi/eni/eni_product.hpp): every field of the example ENI (esi/eni/examples/mixed-line.xml), and bad input
// as a class: one message with file and line, never a crash.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <regex>
#include <string>

#include "esi/device/product.hpp"
#include "esi/eni/eni_modules.hpp"
#include "esi/eni/eni_product.hpp"
#include "esi/eni/eni_reader.hpp"
#include "esi/slots.hpp"

namespace {

using namespace esi::eni;

const std::string kExample = std::string(SOFTECAT_SOURCE_DIR) + "/esi/eni/examples/mixed-line.xml";

std::string wrap_slave(const std::string& inside) {
    return "<EtherCATConfig>\n<Config>\n<Slave>\n<Info><Name>S</Name><PhysAddr>1001</PhysAddr><VendorId>1</"
           "VendorId>"
           "<ProductCode>2</ProductCode><RevisionNo>3</RevisionNo></Info>\n" +
           inside + "\n</Slave>\n</Config>\n</EtherCATConfig>\n";
}

TEST(EniReader, ExampleSlavesInOrderWithIdentities) {
    const Config c = read_eni_file(kExample);
    EXPECT_EQ(c.master.name, "Device 1 (EtherCAT)");
    EXPECT_EQ(c.master.destination, std::vector<uint8_t>(6, 0xFF));
    EXPECT_EQ(c.master.init_cmds.size(), 3u);
    ASSERT_EQ(c.slaves.size(), 5u);
    const uint32_t products[] = {0x00011100, 0x03f03052, 0x07d03052, 0x0c203052, 0x00057200};
    const uint32_t revisions[] = {0x00010000, 0x00110000, 0x00100000, 0x00140000, 0x00010002};
    for (std::size_t i = 0; i < 5; ++i) {
        const Slave& s = c.slaves[i];
        EXPECT_EQ(s.info.vendor_id, 0x00000A5Eu);
        EXPECT_EQ(s.info.product_code, products[i]);
        EXPECT_EQ(s.info.revision, revisions[i]);
        EXPECT_EQ(s.info.phys_addr, 1001 + i);
        ASSERT_TRUE(s.info.auto_inc_addr);
        EXPECT_EQ(*s.info.auto_inc_addr, static_cast<uint16_t>(-static_cast<int>(i)));
        EXPECT_GT(s.line, 0);
    }
    EXPECT_EQ(c.slaves[0].info.name, "Term 1 (EXK1100)");
    EXPECT_EQ(c.slaves[0].info.physics, "YKY");
    EXPECT_EQ(c.slaves[0].previous_port(), nullptr);
    // The tree: terminals behind port B one after the other, the drive on port C of the coupler.
    for (std::size_t i = 1; i < 4; ++i) {
        ASSERT_NE(c.slaves[i].previous_port(), nullptr);
        EXPECT_EQ(c.slaves[i].previous_port()->port, 1);
        EXPECT_EQ(c.slaves[i].previous_port()->phys_addr, 1000 + i);
    }
    EXPECT_EQ(c.slaves[4].previous_port()->port, 2);
    EXPECT_EQ(c.slaves[4].previous_port()->phys_addr, 1001);
    EXPECT_TRUE(c.slaves[4].previous_port()->selected);
    EXPECT_EQ(c.find_phys_addr(1005), 4);
    EXPECT_EQ(c.find_phys_addr(7), -1);
}

TEST(EniReader, ExampleProcessDataMailboxInitCmdsDc) {
    const Config c = read_eni_file(kExample);
    const Slave& di = c.slaves[1];
    ASSERT_EQ(di.process_data.sms.size(), 1u);
    EXPECT_EQ(di.process_data.sms[0].number, 0);
    EXPECT_EQ(di.process_data.sms[0].type, "Inputs");
    EXPECT_EQ(di.process_data.sms[0].start, 0x1000);
    EXPECT_EQ(di.process_data.sms[0].control, 0x00);
    EXPECT_EQ(di.process_data.sms[0].pdos.size(), 8u);
    EXPECT_EQ(di.process_data.txpdos.size(), 8u);
    EXPECT_TRUE(di.process_data.txpdos[0].fixed);
    EXPECT_EQ(di.process_data.txpdos[0].sm, 0);
    EXPECT_EQ(di.input_bits(), 8u);
    EXPECT_EQ(di.output_bits(), 0u);
    EXPECT_FALSE(di.mailbox.present);

    const Slave& ai = c.slaves[3];
    EXPECT_TRUE(ai.mailbox.present);
    EXPECT_EQ(ai.mailbox.send.start, 0x1000);
    EXPECT_EQ(ai.mailbox.recv.start, 0x1080);
    EXPECT_EQ(ai.mailbox.recv.length, 128);
    EXPECT_EQ(ai.mailbox.protocol_bits(), 0x04);
    ASSERT_EQ(ai.mailbox.coe_init_cmds.size(), 9u);
    const CoeInitCmd& filter = ai.mailbox.coe_init_cmds.back();
    EXPECT_EQ(filter.index, 0x8000);
    EXPECT_EQ(filter.subindex, 6);
    EXPECT_EQ(filter.ccs, 1);
    EXPECT_EQ(filter.data, std::vector<uint8_t>{1});
    EXPECT_EQ(filter.transitions, std::vector<std::string>{"PS"});
    EXPECT_TRUE(filter.fixed);
    const Pdo* status = ai.process_data.pdo(0x1A08);
    ASSERT_NE(status, nullptr);
    EXPECT_EQ(status->bits(), 16u);
    EXPECT_EQ(status->entries[1].index, 0);  // a gap
    EXPECT_EQ(ai.input_bits(), 144u);

    const Slave& drive = c.slaves[4];
    EXPECT_EQ(drive.mailbox.protocols, (std::vector<std::string>{"CoE", "FoE"}));
    EXPECT_EQ(drive.mailbox.protocol_bits(), 0x0C);
    EXPECT_EQ(drive.output_bits(), 112u);
    EXPECT_EQ(drive.input_bits(), 176u);
    EXPECT_EQ(drive.process_data.pdo(0x1600)->entries.size(), 6u);
    EXPECT_EQ(drive.process_data.pdo(0x1600)->entries[0].data_type, "UINT");
    EXPECT_FALSE(drive.process_data.pdo(0x1600)->fixed);
    ASSERT_TRUE(drive.assign_activate());
    EXPECT_EQ(*drive.assign_activate(), 0x0300);
    EXPECT_TRUE(drive.dc.present);
    EXPECT_EQ(drive.dc.cycle_time0, 1000000u);
    EXPECT_EQ(drive.dc.shift_time0, 0);
    EXPECT_TRUE(drive.dc.potential_reference_clock);
    EXPECT_FALSE(c.slaves[1].assign_activate());

    // Register init commands: the station address by position, SMs, FMMUs, AL control with a Validate.
    const InitCmd& addr = drive.init_cmds.front();
    EXPECT_EQ(addr.cmd, 2);  // APWR
    EXPECT_EQ(addr.adp, static_cast<uint16_t>(-4));
    EXPECT_EQ(addr.ado, 0x0010);
    EXPECT_EQ(addr.data, (std::vector<uint8_t>{0xED, 0x03}));
    EXPECT_EQ(addr.cnt, 1);
    EXPECT_EQ(addr.retries, 3);
    int sm2 = 0;
    for (const InitCmd& ic : drive.init_cmds)
        if (ic.ado == 0x0810 && ic.transitions == std::vector<std::string>{"PS"}) {
            ++sm2;
            EXPECT_EQ(ic.data, (std::vector<uint8_t>{0x00, 0x18, 14, 0, 0x64, 0, 1, 0}));
        }
    EXPECT_EQ(sm2, 1);

    // Cyclic commands and the process image.
    ASSERT_EQ(c.cyclic.size(), 1u);
    EXPECT_EQ(c.cyclic[0].cycle_time, 1000u);
    ASSERT_EQ(c.cyclic[0].frames.size(), 1u);
    const auto& cmds = c.cyclic[0].frames[0].cmds;
    ASSERT_EQ(cmds.size(), 3u);
    EXPECT_EQ(cmds[0].cmd, 11);
    EXPECT_EQ(cmds[0].addr, 0x01000000u);
    EXPECT_EQ(cmds[0].data_length, 15);
    EXPECT_EQ(cmds[0].cnt, 2);
    EXPECT_EQ(cmds[0].state, "SAFEOP OP");
    EXPECT_EQ(cmds[1].cnt, 3);
    EXPECT_EQ(cmds[2].cnt, 5);
    EXPECT_EQ(cmds[2].ado, 0x0130);
    EXPECT_EQ(c.input_bytes, 41u);
    EXPECT_EQ(c.output_bytes, 15u);
}

TEST(EniReader, NumbersAsEtg2100WritesThem) {
    // Hex with #x, and a 32-bit identifier with the top bit set written as a negative xs:int.
    const Config c = read_eni_text(
        "<EtherCATConfig><Config><Slave><Info><PhysAddr>#x3e9</PhysAddr><VendorId>#x2</VendorId>"
        "<ProductCode>-1</ProductCode><RevisionNo>#x80000000</RevisionNo><SerialNo>7</SerialNo></Info></"
        "Slave>"
        "</Config></EtherCATConfig>");
    ASSERT_EQ(c.slaves.size(), 1u);
    EXPECT_EQ(c.slaves[0].info.phys_addr, 1001);
    EXPECT_EQ(c.slaves[0].info.product_code, 0xFFFFFFFFu);
    EXPECT_EQ(c.slaves[0].info.revision, 0x80000000u);
    EXPECT_EQ(c.slaves[0].info.serial, 7u);
}

// Bad input: each case gives one EniError that names the file and the line of the fault.
struct Bad {
    const char* what;
    std::string xml;
    int line;  // 0: no line (the whole file)
    const char* says;
};

TEST(EniReader, BadInputIsOneMessageWithFileAndLine) {
    const std::vector<Bad> cases = {
        {"malformed", "<EtherCATConfig>\n<Config>\n<Slave>\n</Config>\n", 5, "not well-formed"},
        {"an ESI", "<?xml version=\"1.0\"?>\n<EtherCATInfo>\n</EtherCATInfo>\n", 2, "not <EtherCATConfig>"},
        {"no Config", "<EtherCATConfig>\n</EtherCATConfig>", 1, "has no <Config>"},
        {"empty", "", 0, "empty"},
        {"blanks", "  \n\n", 0, "empty"},
        {"doctype", "<?xml version=\"1.0\"?>\n<!DOCTYPE x [<!ENTITY a \"b\">]>\n<EtherCATConfig/>", 2,
         "DOCTYPE"},
        {"entity bomb",
         "<?xml version=\"1.0\"?>\n<!DOCTYPE l [\n<!ENTITY a \"aaaaaaaaaa\">\n<!ENTITY b "
         "\"&a;&a;&a;&a;&a;&a;\">]>\n"
         "<EtherCATConfig><Config><Slave><Info><Name>&b;</Name></Info></Slave></Config></EtherCATConfig>",
         2, "DOCTYPE"},
        {"external entity", "<!DOCTYPE x SYSTEM \"file:///etc/passwd\">\n<EtherCATConfig/>", 1, "DOCTYPE"},
        {"no identity",
         "<EtherCATConfig>\n<Config>\n<Slave>\n<Info><PhysAddr>1</PhysAddr></Info>\n</Slave>\n</Config>\n</"
         "EtherCATConfig>",
         4, "has no <VendorId>"},
        {"bad number", wrap_slave("<InitCmds><InitCmd><Cmd>two</Cmd><Ado>0</Ado></InitCmd></InitCmds>"), 5,
         "'two' is not a number"},
        {"out of range", wrap_slave("<InitCmds><InitCmd><Cmd>2</Cmd><Ado>70000</Ado></InitCmd></InitCmds>"),
         5, "out of range"},
        {"unknown command", wrap_slave("<InitCmds><InitCmd><Cmd>99</Cmd><Ado>0</Ado></InitCmd></InitCmds>"),
         5, "not an EtherCAT command"},
        {"bad transition",
         wrap_slave(
             "<InitCmds><InitCmd><Transition>XY</Transition><Cmd>2</Cmd><Ado>0</Ado></InitCmd></InitCmds>"),
         5, "not a state transition"},
        {"odd hex",
         wrap_slave("<InitCmds><InitCmd><Cmd>2</Cmd><Ado>0</Ado><Data>123</Data></InitCmd></InitCmds>"), 5,
         "odd number of hex digits"},
        {"unknown SM type",
         wrap_slave("<ProcessData><Sm2><Type>Sideways</Type><StartAddress>0</StartAddress><ControlByte>0</"
                    "ControlByte>"
                    "<Enable>1</Enable></Sm2></ProcessData>"),
         5, "not MBoxOut, MBoxIn, Outputs or Inputs"},
        {"dangling Sm Pdo",
         wrap_slave("<ProcessData><Sm2><Type>Outputs</Type><StartAddress>0</StartAddress><ControlByte>0</"
                    "ControlByte>"
                    "<Enable>1</Enable><Pdo>#x1600</Pdo></Sm2></ProcessData>"),
         5, "does not declare"},
        {"dangling PDO Sm",
         wrap_slave(
             "<ProcessData><Sm3><Type>Inputs</Type><StartAddress>0</StartAddress><ControlByte>0</ControlByte>"
             "<Enable>1</Enable></Sm3>\n<TxPdo Sm=\"2\"><Index>#x1a00</Index></TxPdo></ProcessData>"),
         6, "does not declare"},
        {"PDO on an SM of the other direction",
         wrap_slave(
             "<ProcessData><Sm3><Type>Inputs</Type><StartAddress>0</StartAddress><ControlByte>0</ControlByte>"
             "<Enable>1</Enable></Sm3>\n<RxPdo Sm=\"3\"><Index>#x1600</Index></RxPdo></ProcessData>"),
         6, "of type Inputs"},
        {"entry without type",
         wrap_slave("<ProcessData>\n<TxPdo><Index>#x1a00</Index><Entry><Index>#x6000</Index><BitLen>8</"
                    "BitLen></Entry>"
                    "</TxPdo></ProcessData>"),
         6, "without a DataType"},
        {"unknown protocol",
         wrap_slave("<Mailbox><Send><Start>0</Start><Length>1</Length></Send><Recv><Start>0</"
                    "Start><Length>1</Length>"
                    "</Recv>\n<Protocol>XoE</Protocol></Mailbox>"),
         6, "not a mailbox protocol"},
        {"bad port", wrap_slave("<PreviousPort>\n<Port>E</Port><PhysAddr>1</PhysAddr></PreviousPort>"), 6,
         "not a port"},
        {"dangling PreviousPort",
         wrap_slave("<PreviousPort>\n<Port>B</Port><PhysAddr>999</PhysAddr></PreviousPort>"), 5,
         "not the station address of a slave before"},
        {"bad boolean", wrap_slave("<DC>\n<PotentialReferenceClock>yes</PotentialReferenceClock></DC>"), 6,
         "not a boolean"},
        {"station address twice",
         "<EtherCATConfig><Config>\n<Slave><Info><PhysAddr>5</PhysAddr><VendorId>1</VendorId><ProductCode>2</"
         "ProductCode>"
         "<RevisionNo>3</RevisionNo></Info></Slave>\n<Slave><Info><PhysAddr>5</PhysAddr><VendorId>1</"
         "VendorId>"
         "<ProductCode>2</ProductCode><RevisionNo>3</RevisionNo></Info></Slave>\n</Config></EtherCATConfig>",
         3, "station address of slave 0 already"},
    };
    for (const Bad& b : cases) {
        SCOPED_TRACE(b.what);
        try {
            (void)read_eni_text(b.xml, "bad.xml");
            ADD_FAILURE() << "accepted";
        } catch (const EniError& e) {
            const std::string msg = e.what();
            const std::string prefix = b.line > 0 ? "bad.xml:" + std::to_string(b.line) + ": " : "bad.xml: ";
            EXPECT_EQ(msg.rfind(prefix, 0), 0u) << msg;
            EXPECT_NE(msg.find(b.says), std::string::npos) << msg;
            EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
        }
    }
}

TEST(EniReader, FilesThatAreNotRegularOrTooLarge) {
    const auto dir = std::filesystem::temp_directory_path() / ("eni_test_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir);
    const std::string fifo = (dir / "fifo.xml").string();
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    const std::string huge = (dir / "huge.xml").string();
    {
        std::ofstream f(huge);
        f << "<EtherCATConfig><Config>";
        f.seekp(static_cast<std::streamoff>(kMaxEniBytes) + 10);
        f << "</Config></EtherCATConfig>";
    }
    for (const auto& [path, says] :
         std::vector<std::pair<std::string, std::string>>{{fifo, "not a regular file"},
                                                          {dir.string(), "not a regular file"},
                                                          {huge, "larger than"},
                                                          {(dir / "missing.xml").string(), "cannot open"}}) {
        SCOPED_TRACE(path);
        try {
            (void)read_eni_file(path);
            ADD_FAILURE() << "accepted";
        } catch (const EniError& e) {
            EXPECT_EQ(std::string(e.what()).rfind(path + ": ", 0), 0u) << e.what();
            EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
        }
    }
    std::filesystem::remove_all(dir);
}

// Damaged copies of the example: cut anywhere, an element's value replaced by garbage, a closing tag lost.
// Each is a Config whose slaves convert (or give an EniError) or an EniError with the file name: never
// another exception, never a crash.
TEST(EniReader, DamagedExamplesAreErrorsOrLines) {
    std::ifstream f(kExample);
    const std::string good((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    ASSERT_GT(good.size(), 10000u);
    std::vector<std::string> damaged;
    for (std::size_t cut = 0; cut < good.size(); cut += 997)
        damaged.push_back(good.substr(0, cut));
    for (std::size_t at = good.find('>'), k = 0; at != std::string::npos; at = good.find('>', at + 1), ++k) {
        if (k % 7 != 0) continue;
        const std::size_t end = good.find('<', at);
        if (end == std::string::npos) break;
        std::string v = good;
        v.replace(at + 1, end - at - 1, k % 2 ? "-99999999999" : "#xZZ");
        damaged.push_back(std::move(v));
        std::string w = good;
        const std::size_t close = good.find("</", at);
        if (close != std::string::npos) w.erase(close, good.find('>', close) - close + 1);
        damaged.push_back(std::move(w));
    }
    int configs = 0, errors = 0;
    for (const std::string& xml : damaged) {
        try {
            const Config c = read_eni_text(xml, "damaged.xml");
            ++configs;
            for (std::size_t k = 0; k < c.slaves.size(); ++k) {
                try {
                    const od::Product p = product_from_eni(c, k);
                    (void)p.make_dictionary(p.description);
                } catch (const EniError& e) {
                    EXPECT_EQ(std::string(e.what()).rfind("damaged.xml:", 0), 0u) << e.what();
                }
            }
        } catch (const EniError& e) {
            ++errors;
            EXPECT_EQ(std::string(e.what()).rfind("damaged.xml", 0), 0u) << e.what();
        }
    }
    EXPECT_GT(configs, 0);
    EXPECT_GT(errors, 100);
}

// ---- the conversion -------------------------------------------------------------------------------------

TEST(EniProduct, CouplerWithoutMailboxOrProcessData) {
    const Config c = read_eni_file(kExample);
    const od::Product p = product_from_eni(c, 0);
    EXPECT_EQ(p.description.identity.vendor_id, 0x00000A5Eu);
    EXPECT_EQ(p.description.identity.product_code, 0x00011100u);
    EXPECT_EQ(p.description.identity.revision, 0x00010000u);
    EXPECT_EQ(p.description.identity.order_code, "EXK1100");
    EXPECT_EQ(p.description.identity.device_name, "Term 1 (EXK1100)");
    EXPECT_TRUE(p.description.sync_managers.empty());
    EXPECT_EQ(p.description.mailbox_protocols, 0);
    EXPECT_TRUE(p.description.dc_modes.empty());
    EXPECT_TRUE(p.warnings.empty());
    EXPECT_EQ(p.application, od::Application::None);
    EXPECT_TRUE(p.eeprom.empty());
    EXPECT_NE(p.source.find("slave 0"), std::string::npos);
}

TEST(EniProduct, DigitalTerminalsProcessDataOnSm0) {
    const Config c = read_eni_file(kExample);
    for (std::size_t k : {std::size_t{1}, std::size_t{2}}) {
        const od::Product p = product_from_eni(c, k);
        ASSERT_EQ(p.description.sync_managers.size(), 1u);
        const od::SyncManagerDefault& sm = p.description.sync_managers[0];
        EXPECT_EQ(sm.kind, k == 1 ? od::SmKind::Inputs : od::SmKind::Outputs);
        EXPECT_EQ(sm.start, k == 1 ? 0x1000 : 0x0F00);
        EXPECT_EQ(sm.control, k == 1 ? 0x00 : 0x44);
        EXPECT_EQ(sm.default_size, 1);
        od::Dictionary d = p.make_dictionary(p.description);
        // SM0's assignment (0x1C10) with the eight PDOs; each channel's entry exists, mappable its way.
        EXPECT_EQ(d.get<uint8_t>(0x1C10, 0), 8);
        const uint16_t pdo0 = k == 1 ? 0x1A00 : 0x1600;
        EXPECT_EQ(d.get<uint16_t>(0x1C10, 8), pdo0 + 7);
        EXPECT_EQ(d.get<uint32_t>(pdo0 + 2, 1), (k == 1 ? 0x60200101u : 0x70200101u));
        const od::Entry* e = d.find(k == 1 ? 0x6070 : 0x7070, 1);
        ASSERT_NE(e, nullptr);
        EXPECT_EQ(e->type, od::DataType::Boolean);
        EXPECT_EQ(k == 1 ? e->tx_mappable() : e->rx_mappable(), true);
        EXPECT_FALSE(d.find(pdo0)->entries[1].writable(od::AlState::PreOp));  // Fixed
        for (const std::string& w : p.warnings)
            ADD_FAILURE() << w;
    }
}

TEST(EniProduct, AnalogTerminalWithCoeInitCmds) {
    const Config c = read_eni_file(kExample);
    const od::Product p = product_from_eni(c, 3);
    const auto& sms = p.description.sync_managers;
    ASSERT_EQ(sms.size(), 4u);
    EXPECT_EQ(sms[0].kind, od::SmKind::MBoxOut);
    EXPECT_EQ(sms[0].default_size, 128);
    EXPECT_EQ(sms[1].start, 0x1080);
    EXPECT_FALSE(sms[2].enable);
    EXPECT_EQ(sms[3].default_size, 18);
    EXPECT_EQ(p.description.standard_mailbox.in_start, 0x1080);
    EXPECT_EQ(p.description.mailbox_protocols, od::mailbox_protocol::CoE);
    od::Dictionary d = p.make_dictionary(p.description);
    EXPECT_EQ(d.get<uint8_t>(0x1C13, 0), 5);
    EXPECT_EQ(d.get<uint16_t>(0x1C13, 5), 0x1A08);
    // What the master writes in PS exists and takes the write in Pre-Op.
    const uint8_t one = 1;
    EXPECT_EQ(d.write(0x8000, 6, od::AlState::PreOp, {&one, 1}), od::Status::Ok);
    const uint8_t zero = 0;
    EXPECT_EQ(d.write(0x1C13, 0, od::AlState::PreOp, {&zero, 1}), od::Status::Ok);
    const uint8_t pdo[2] = {0x00, 0x1A};
    EXPECT_EQ(d.write(0x1C13, 1, od::AlState::PreOp, pdo), od::Status::Ok);
    // The BIT2 limits are entries of two bits; the Sync error entry (0x1C33:20) exists.
    EXPECT_NE(d.find(0x1C33, 0x20), nullptr);
    ASSERT_NE(d.find(0x6000, 3), nullptr);
    EXPECT_EQ(d.find(0x6000, 3)->type, od::DataType::Bit2);
    EXPECT_EQ(d.find(0x6000, 3)->bit_length, 2);
    EXPECT_EQ(d.get<uint32_t>(0x1A00, 3), 0x60000302u);
    EXPECT_EQ(d.get<uint32_t>(0x1A00, 6), 0x00000009u);  // the gap
    for (const std::string& w : p.warnings)
        ADD_FAILURE() << w;
}

TEST(EniProduct, DriveFromEniDataIsProcessDataWithDc) {
    const Config c = read_eni_file(kExample);
    const od::Product p = product_from_eni(c, 4);
    const auto& sms = p.description.sync_managers;
    ASSERT_EQ(sms.size(), 4u);
    EXPECT_EQ(sms[2].default_size, 14);
    EXPECT_EQ(sms[3].default_size, 22);
    EXPECT_EQ(sms[2].start, 0x1800);
    EXPECT_EQ(p.description.standard_mailbox.out_size, 256);
    EXPECT_EQ(p.description.mailbox_protocols, od::mailbox_protocol::CoE | od::mailbox_protocol::FoE);
    ASSERT_EQ(p.description.dc_modes.size(), 2u);
    EXPECT_EQ(p.description.dc_modes[1].assign_activate, 0x0300);
    od::DeviceDescription other = p.description;
    other.identity.serial_number = 42;
    od::Dictionary d = p.make_dictionary(other);
    EXPECT_EQ(d.get<uint32_t>(0x1018, 4), 42u);
    EXPECT_EQ(d.get<uint32_t>(0x1018, 2), 0x00057200u);
    EXPECT_EQ(d.get<uint32_t>(0x1600, 2), 0x607A0020u);
    EXPECT_EQ(d.get<uint32_t>(0x1600, 5), 0x00000008u);                    // the gap
    EXPECT_TRUE(d.find(0x1600)->entries[1].writable(od::AlState::PreOp));  // not Fixed
    EXPECT_EQ(d.find(0x607A, 0)->type, od::DataType::Integer32);
    EXPECT_TRUE(d.find(0x607A, 0)->rx_mappable());
    EXPECT_EQ(d.find(0x6060, 0)->type, od::DataType::Integer8);
    EXPECT_TRUE(d.find(0x6060, 0)->writable(od::AlState::PreOp));
    // Served as process data, and said so once.
    EXPECT_EQ(p.application, od::Application::None);
    ASSERT_EQ(p.warnings.size(), 1u) << p.warnings[0] << "\n" << p.warnings[1];
    EXPECT_NE(p.warnings[0].find("CiA 402"), std::string::npos);
}

TEST(EniProduct, UnemulatedThingsAreWarningsOnePerElement) {
    const Config c = read_eni_text(wrap_slave(
        "<ProcessData><Sm3><Type>Inputs</Type><StartAddress>#x1180</StartAddress><ControlByte>32</"
        "ControlByte>"
        "<Enable>1</Enable></Sm3><TxPdo "
        "Sm=\"3\"><Index>#x1a00</Index><Entry><Index>#x6000</Index><SubIndex>1</SubIndex>"
        "<BitLen>16</BitLen><DataType>STRING(2)</DataType></Entry><Entry><Index>#x1018</Index><SubIndex>1</"
        "SubIndex>"
        "<BitLen>32</BitLen><DataType>UDINT</DataType></Entry></TxPdo></ProcessData>"
        "<Mailbox><Send><Start>4096</Start><Length>128</Length></Send><Recv><Start>4224</Start><Length>128</"
        "Length>"
        "</Recv><Protocol>CoE</Protocol><Protocol>EoE</Protocol><Protocol>SoE</Protocol>"
        "<CoE><InitCmds><InitCmd "
        "CompleteAccess=\"true\"><Transition>PS</Transition><Ccs>1</Ccs><Index>#x8000</Index>"
        "<SubIndex>0</SubIndex><Data>0102030405</Data></InitCmd>"
        "<InitCmd><Transition>PS</Transition><Ccs>1</Ccs><Index>#x8010</Index><SubIndex>1</SubIndex>"
        "<Data>0102030405</Data></InitCmd></InitCmds></CoE>"
        "<EoE><InitCmds><InitCmd/></InitCmds></EoE></Mailbox>"));
    const od::Product p = product_from_eni(c, 0);
    std::string all;
    for (const std::string& w : p.warnings)
        all += w + "\n";
    EXPECT_EQ(p.warnings.size(), 6u) << all;
    EXPECT_NE(all.find("0x1018:0x01"), std::string::npos) << all;
    EXPECT_NE(all.find("Protocol EoE"), std::string::npos) << all;
    EXPECT_NE(all.find("Protocol SoE"), std::string::npos) << all;
    EXPECT_NE(all.find("EoE/InitCmds"), std::string::npos) << all;
    EXPECT_NE(all.find("STRING(2)"), std::string::npos) << all;
    EXPECT_NE(all.find("complete access"), std::string::npos) << all;
    // A 5-byte write: an octet string that takes it.
    od::Dictionary d = p.make_dictionary(p.description);
    const uint8_t five[5] = {1, 2, 3, 4, 5};
    EXPECT_EQ(d.write(0x8010, 1, od::AlState::PreOp, five), od::Status::Ok);
}

}  // namespace

// A modular device served from its ESI gets the modules the ENI was configured with (eni_modules.hpp), by the
// class of ways an ENI says so: the configured module ident list 0xF030 the master downloads (complete access
// from subindex 0 or 1, or one subindex at a time), else the PDOs of each slot's module; a configuration no
// module reproduces is refused with the PDO that no slot explains.
namespace modules {

const std::string kModularEsi = std::string(SOFTECAT_SOURCE_DIR) + "/esi/examples/modular-io.xml";
const std::string kModularEni = std::string(SOFTECAT_SOURCE_DIR) + "/esi/eni/examples/modular-line.xml";
constexpr uint32_t kDi8 = 0x1001, kDo8 = 0x2001, kAi2 = 0x3001;
using Modules = std::vector<std::optional<uint32_t>>;

esi::eni::CoeInitCmd f030(uint8_t sub, bool ca, std::vector<uint8_t> data) {
    esi::eni::CoeInitCmd c;
    c.transitions = {"PS"};
    c.ccs = 1;
    c.index = 0xF030;
    c.subindex = sub;
    c.complete_access = ca;
    c.data = std::move(data);
    return c;
}

std::vector<uint8_t> le32(uint32_t v) {
    return {uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16), uint8_t(v >> 24)};
}

TEST(EniModules, ThePdosOfTheEniChooseEachSlotsModule) {
    const esi::EsiFile f = esi::read_esi_file(kModularEsi);
    const esi::eni::Config eni = esi::eni::read_eni_file(kModularEni);
    ASSERT_EQ(eni.slaves.size(), 1u);
    const auto m = esi::eni::modules_from_eni(f, f.devices.at(0), eni.slaves[0]);
    ASSERT_TRUE(m);
    EXPECT_EQ(m->modules, (Modules{kAi2, kAi2, std::nullopt, kDo8}));
    EXPECT_EQ(m->how, "its PDOs");
    // The product built with them has the ENI's PDOs and not the default modules': EXM-AI2's two entries in
    // 0x1A00 and 0x1A01, EXM-DO8's 0x1603, nothing at 0x1601 (default EXM-DO8) or 0x1A02 (default EXM-AI2).
    const od::Product p = esi::load_product(f, f.devices.at(0), m->modules);
    const od::Dictionary dict = p.make_dictionary(p.description);
    for (uint16_t index : {0x1A00, 0x1A01, 0x1603})
        EXPECT_NE(dict.find(index), nullptr) << std::hex << index;
    for (uint16_t index : {0x1601, 0x1A02})
        EXPECT_EQ(dict.find(index), nullptr) << std::hex << index;
    EXPECT_EQ(dict.find(0x1A00)->entries.size(), 3u);  // :00 and two 16-bit values
}

TEST(EniModules, TheDefaultModulesWhereTheEniHasTheirPdos) {
    const esi::EsiFile f = esi::read_esi_file(kModularEsi);
    esi::eni::Config eni = esi::eni::read_eni_file(kModularEni);
    esi::eni::Slave s = eni.slaves[0];
    // The ENI as the default configuration would give it: DI8 in slot 1, DO8 in 2, AI2 in 3.
    s.process_data.rxpdos.clear();
    s.process_data.txpdos.clear();
    esi::eni::Pdo di{false, 0x1A00, 3, true, false, "DI", {}, 0};
    for (uint8_t k = 1; k <= 8; ++k)
        di.entries.push_back({0x6000, k, 1, "In", "BOOL"});
    esi::eni::Pdo do8{true, 0x1601, 2, true, false, "DO", {}, 0};
    for (uint8_t k = 1; k <= 8; ++k)
        do8.entries.push_back({0x7010, k, 1, "Out", "BOOL"});
    esi::eni::Pdo ai{
        false, 0x1A02, 3, true, false, "AI", {{0x6020, 1, 16, "V1", "INT"}, {0x6020, 2, 16, "V2", "INT"}}, 0};
    s.process_data.txpdos = {di, ai};
    s.process_data.rxpdos = {do8};
    const auto m = esi::eni::modules_from_eni(f, f.devices.at(0), s);
    ASSERT_TRUE(m);
    EXPECT_EQ(m->modules, (Modules{kDi8, kDo8, kAi2, std::nullopt}));
    EXPECT_EQ(m->modules, esi::default_modules(f.devices.at(0)));
}

TEST(EniModules, TheConfiguredModuleIdentListEveryWayItIsWritten) {
    const esi::EsiFile f = esi::read_esi_file(kModularEsi);
    const esi::eni::Config eni = esi::eni::read_eni_file(kModularEni);
    const Modules want{kDo8, std::nullopt, kDi8, kAi2};
    std::vector<uint8_t> from1;
    for (uint32_t v : {kDo8, 0u, kDi8, kAi2})
        for (uint8_t b : le32(v))
            from1.push_back(b);
    std::vector<uint8_t> from0{4, 0};
    from0.insert(from0.end(), from1.begin(), from1.end());
    std::vector<std::vector<esi::eni::CoeInitCmd>> ways{
        {f030(0, true, from0)},
        {f030(1, true, from1)},
        {f030(0, false, {0}), f030(1, false, le32(kDo8)), f030(3, false, le32(kDi8)),
         f030(4, false, le32(kAi2)), f030(0, false, {4})},
    };
    for (const auto& cmds : ways) {
        esi::eni::Slave s = eni.slaves[0];  // its PDOs say otherwise: the list wins
        s.mailbox.coe_init_cmds.insert(s.mailbox.coe_init_cmds.begin(), cmds.begin(), cmds.end());
        const auto m = esi::eni::modules_from_eni(f, f.devices.at(0), s);
        ASSERT_TRUE(m);
        EXPECT_EQ(m->modules, want);
        EXPECT_EQ(m->how, "its 0xF030 init command");
    }
    // A list naming a module the file lacks, or a truncated complete access: the PDOs decide.
    for (const auto& bad : {f030(1, false, le32(0x9999)), f030(0, true, {4, 0, 1, 0x10})}) {
        esi::eni::Slave s = eni.slaves[0];
        s.mailbox.coe_init_cmds.push_back(bad);
        const auto m = esi::eni::modules_from_eni(f, f.devices.at(0), s);
        ASSERT_TRUE(m);
        EXPECT_EQ(m->how, "its PDOs");
        EXPECT_EQ(m->modules, (Modules{kAi2, kAi2, std::nullopt, kDo8}));
    }
}

TEST(EniModules, APdoNoModuleExplainsIsRefusedAndNamed) {
    const esi::EsiFile f = esi::read_esi_file(kModularEsi);
    const esi::eni::Config eni = esi::eni::read_eni_file(kModularEni);
    // Every way a PDO can differ from each module's: another bit length, another subindex, an entry more, an
    // index no slot has.
    for (int variant = 0; variant < 4; ++variant) {
        esi::eni::Slave s = eni.slaves[0];
        esi::eni::Pdo& p = s.process_data.txpdos.at(1);  // 0x1A01, slot 2's EXM-AI2
        if (variant == 0) p.entries[1].bit_len = 32;
        if (variant == 1) p.entries[1].subindex = 3;
        if (variant == 2) p.entries.push_back({0x6010, 3, 16, "V3", "INT"});
        if (variant == 3) p.index = 0x1A09;
        std::string why;
        EXPECT_FALSE(esi::eni::modules_from_eni(f, f.devices.at(0), s, &why)) << variant;
        EXPECT_NE(why.find(variant == 3 ? "0x1A09" : "0x1A01"), std::string::npos) << why;
    }
    // A device without slots: nothing to choose.
    const esi::EsiFile plain =
        esi::read_esi_file(std::string(SOFTECAT_SOURCE_DIR) + "/esi/examples/analog-in.xml");
    EXPECT_FALSE(esi::eni::modules_from_eni(plain, plain.devices.at(0), eni.slaves[0]));
}

// What the master was configured for and the ESI's device lacks: every PDO of the ENI that the device does
// not declare, or whose entries differ from the device's fixed PDO; nothing for a consistent pair.
TEST(EniModules, PdoMismatchesNameWhatTheDeviceLacks) {
    const esi::EsiFile f = esi::read_esi_file(kModularEsi);
    const esi::eni::Config eni = esi::eni::read_eni_file(kModularEni);
    const esi::eni::Slave& s = eni.slaves[0];
    EXPECT_TRUE(esi::eni::pdo_mismatches(f, f.devices.at(0), {kAi2, kAi2, std::nullopt, kDo8}, s).empty());
    // Served with its defaults (DI8, DO8, AI2, -): 0x1A00 is DI8's (eight bits, not two values), 0x1A01 and
    // 0x1603 are no PDO of that configuration.
    const auto w = esi::eni::pdo_mismatches(f, f.devices.at(0), esi::default_modules(f.devices.at(0)), s);
    ASSERT_EQ(w.size(), 3u);
    std::string all;
    for (const auto& x : w) {
        EXPECT_GT(x.line, 0);
        all += x.what + "\n";
    }
    EXPECT_NE(all.find("TxPDO 0x1A00 maps other entries than the device's fixed PDO"), std::string::npos)
        << all;
    EXPECT_NE(all.find("TxPDO 0x1A01 is not a PDO of the device"), std::string::npos) << all;
    EXPECT_NE(all.find("RxPDO 0x1603 is not a PDO of the device"), std::string::npos) << all;
    // The example line and the example ESIs agree, slave by slave.
    const esi::eni::Config mixed = esi::eni::read_eni_file(kExample);
    for (const esi::eni::Slave& x : mixed.slaves) {
        bool found = false;
        for (const char* name : {"coupler.xml", "digital-io.xml", "analog-in.xml", "drive402.xml"}) {
            const esi::EsiFile e =
                esi::read_esi_file(std::string(SOFTECAT_SOURCE_DIR) + "/esi/examples/" + name);
            for (const esi::EsiDevice& d : e.devices)
                if (d.product_code == x.info.product_code && d.revision == x.info.revision) {
                    found = true;
                    EXPECT_TRUE(esi::eni::pdo_mismatches(e, d, esi::default_modules(d), x).empty())
                        << x.info.name;
                }
        }
        EXPECT_TRUE(found) << x.info.name;
    }
}

// From the ENI's data alone, an object the master writes whole from subindex 0 as a count, its padding byte
// and that many values of one size (0xF030, ETG.5001.1) is that array; written again the same way it stays
// one object; any other complete-access structure is not emulated and said.
TEST(EniModules, AnArrayWrittenWholeIsServedFromTheEniData) {
    esi::eni::Config eni = esi::eni::read_eni_file(kModularEni);
    auto& cmds = eni.slaves[0].mailbox.coe_init_cmds;
    std::vector<uint8_t> list{4, 0};
    for (uint32_t v : {kAi2, kAi2, 0u, kDo8})
        for (uint8_t b : le32(v))
            list.push_back(b);
    cmds.push_back(f030(0, true, list));
    cmds.push_back(f030(0, true, list));                        // again, in another transition
    esi::eni::CoeInitCmd odd = f030(0, true, {2, 0, 1, 2, 3});  // two entries in three bytes
    odd.index = 0x8000;
    cmds.push_back(odd);
    const od::Product p = esi::eni::product_from_eni(eni, 0);
    const od::Dictionary dict = p.make_dictionary(p.description);
    const od::Object* o = dict.find(0xF030);
    ASSERT_NE(o, nullptr);
    ASSERT_EQ(o->entries.size(), 5u);
    EXPECT_EQ(std::get<uint64_t>(o->entries[0].default_value), 4u);
    EXPECT_EQ(o->entries[1].type, od::DataType::Unsigned32);
    EXPECT_EQ(std::get<uint64_t>(o->entries[1].default_value), kAi2);
    EXPECT_EQ(std::get<uint64_t>(o->entries[4].default_value), kDo8);
    EXPECT_NE(o->entries[4].access & od::access::WritePreOp, 0);
    std::string warnings;
    for (const auto& w : p.warnings)
        warnings += w + "\n";
    EXPECT_EQ(warnings.find("0xF030"), std::string::npos) << warnings;
    EXPECT_NE(warnings.find("0x8000"), std::string::npos) << warnings;
    EXPECT_EQ(dict.find(0x8000), nullptr);
}

}  // namespace modules
