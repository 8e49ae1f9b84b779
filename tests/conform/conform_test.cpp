// ecat-conform's own parts without a slave: the ESI reader, the report writers (JUnit XML well-formed,
// JSON well-formed), the SII walker, and the catalogue's invariants.
#include <gtest/gtest.h>
#include <libxml/parser.h>

#include <cctype>
#include <set>
#include <sstream>

#include "conform.hpp"
#include "esc/wire/sii.hpp"
#include "report.hpp"

namespace conform {
namespace {

const char* kEsi = R"(<?xml version="1.0"?>
<EtherCATInfo Version="1.14">
  <Vendor><Id>#x000000fb</Id><Name>V</Name></Vendor>
  <Descriptions><Devices>
    <Device>
      <Type ProductCode="#x30010000" RevisionNo="#x01200000">ORDER-1</Type>
      <Name LcId="1033">Dev</Name>
      <Info><IdentificationReg134>true</IdentificationReg134></Info>
      <GroupType>Drives</GroupType>
      <Profile><ProfileNo>402</ProfileNo><Dictionary>
        <DataTypes>
          <DataType><Name>DTARR</Name><BaseType>UDINT</BaseType><BitSize>64</BitSize>
            <ArrayInfo><LBound>1</LBound><Elements>2</Elements></ArrayInfo></DataType>
          <DataType><Name>DT1010</Name><BitSize>80</BitSize>
            <SubItem><SubIdx>0</SubIdx><Name>SubIndex 000</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs><Flags><Access>ro</Access></Flags></SubItem>
            <SubItem><Name>Elements</Name><Type>DTARR</Type><BitSize>64</BitSize><BitOffs>16</BitOffs><Flags><Access WriteRestrictions="PreOP">rw</Access></Flags></SubItem>
          </DataType>
          <DataType><Name>DT1018</Name><BitSize>48</BitSize>
            <SubItem><SubIdx>0</SubIdx><Name>Highest</Name><Type>USINT</Type><BitSize>8</BitSize><BitOffs>0</BitOffs><Flags><Access>ro</Access></Flags></SubItem>
            <SubItem><SubIdx>1</SubIdx><Name>Vendor ID</Name><Type>UDINT</Type><BitSize>32</BitSize><BitOffs>16</BitOffs><Flags><Access>ro</Access><PdoMapping>T</PdoMapping></Flags></SubItem>
          </DataType>
        </DataTypes>
        <Objects>
          <Object><Index>#x1000</Index><Name>Device Type</Name><Type>UDINT</Type><BitSize>32</BitSize>
            <Info><DefaultData>92010200</DefaultData></Info><Flags><Access>ro</Access></Flags></Object>
          <Object><Index>#x1010</Index><Name>Store</Name><Type>DT1010</Type><BitSize>80</BitSize>
            <Info><SubItem><Name>SubIndex 000</Name><Info><DefaultData>02</DefaultData></Info></SubItem></Info></Object>
          <Object><Index>#x1018</Index><Name>Identity</Name><Type>DT1018</Type><BitSize>48</BitSize>
            <Info><SubItem><Name>Highest</Name><Info><MinValue>0</MinValue><MaxValue>#x4</MaxValue></Info></SubItem></Info></Object>
        </Objects>
      </Dictionary></Profile>
      <Fmmu>Outputs</Fmmu><Fmmu>Inputs</Fmmu>
      <Sm DefaultSize="128" StartAddress="#x1000" ControlByte="#x26" Enable="1">MBoxOut</Sm>
      <Sm DefaultSize="128" StartAddress="#x1080" ControlByte="#x22" Enable="1">MBoxIn</Sm>
      <RxPdo Sm="2" Fixed="1"><Index>#x1600</Index><Name>R</Name>
        <Entry><Index>#x6040</Index><SubIndex>0</SubIndex><BitLen>16</BitLen><DataType>UINT</DataType></Entry>
        <Entry><Index>#x0</Index><BitLen>8</BitLen></Entry></RxPdo>
      <Mailbox><CoE SdoInfo="true" CompleteAccess="1" PdoAssign="false"/><FoE/></Mailbox>
      <Dc><OpMode><Name>DC</Name><AssignActivate>#x300</AssignActivate><CycleTimeSync0 Factor="1">1000</CycleTimeSync0></OpMode></Dc>
      <Eeprom><ByteSize>2048</ByteSize><ConfigData>050c</ConfigData><BootStrap>0010000400140004</BootStrap></Eeprom>
    </Device>
  </Devices></Descriptions>
</EtherCATInfo>)";

TEST(EsiReader, ReadsIdentityObjectsAndLayout) {
    EsiFile f = read_esi_text(kEsi);
    ASSERT_EQ(f.devices.size(), 1u);
    const EsiDevice& d = f.devices[0];
    EXPECT_EQ(d.vendor_id, 0xFBu);
    EXPECT_EQ(d.product_code, 0x30010000u);
    EXPECT_EQ(d.revision, 0x01200000u);
    EXPECT_EQ(d.type_name, "ORDER-1");
    EXPECT_EQ(d.group_type, "Drives");
    ASSERT_TRUE(d.profile_no);
    EXPECT_EQ(*d.profile_no, 402u);
    EXPECT_TRUE(d.identification_reg134);

    const EsiObject* dt = d.object(0x1000);
    ASSERT_NE(dt, nullptr);
    EXPECT_EQ(dt->object_code, 7);
    ASSERT_EQ(dt->entries.size(), 1u);
    EXPECT_EQ(dt->entries[0].default_data, (std::vector<uint8_t>{0x92, 0x01, 0x02, 0x00}));
    EXPECT_EQ(dt->entries[0].access, "ro");

    const EsiObject* arr = d.object(0x1010);
    ASSERT_NE(arr, nullptr);
    EXPECT_EQ(arr->object_code, 8);  // SubIndex 0 + an ArrayInfo subitem
    EXPECT_EQ(arr->max_subindex(), 2);
    ASSERT_NE(arr->entry(2), nullptr);
    EXPECT_EQ(arr->entry(2)->type, "UDINT");
    EXPECT_EQ(arr->entry(2)->bit_size, 32);
    EXPECT_EQ(arr->entry(2)->write_restrictions, "PreOP");
    EXPECT_EQ(arr->entry(0)->default_data, std::vector<uint8_t>{0x02});

    const EsiObject* rec = d.object(0x1018);
    ASSERT_NE(rec, nullptr);
    EXPECT_EQ(rec->object_code, 9);
    EXPECT_EQ(rec->entry(1)->pdo_mapping, "T");
    ASSERT_TRUE(rec->entry(0)->max);
    EXPECT_EQ(*rec->entry(0)->max, 4);

    ASSERT_EQ(d.sms.size(), 2u);
    EXPECT_EQ(d.sms[1].start, 0x1080);
    EXPECT_EQ(d.sms[1].control, 0x22);
    EXPECT_EQ(d.sms[0].type, "MBoxOut");
    EXPECT_EQ(d.fmmus, (std::vector<std::string>{"Outputs", "Inputs"}));
    ASSERT_EQ(d.rxpdos.size(), 1u);
    EXPECT_EQ(d.rxpdos[0].sm, 2);
    EXPECT_TRUE(d.rxpdos[0].fixed);
    EXPECT_EQ(d.rxpdos[0].bits(), 24u);
    EXPECT_TRUE(d.coe.present);
    EXPECT_TRUE(d.coe.sdo_info);
    EXPECT_TRUE(d.coe.complete_access);
    EXPECT_FALSE(d.coe.pdo_assign);
    EXPECT_TRUE(d.foe);
    EXPECT_EQ(d.mailbox_protocols(), 0x0C);
    ASSERT_EQ(d.op_modes.size(), 1u);
    EXPECT_EQ(d.op_modes[0].assign_activate, 0x300);
    EXPECT_EQ(d.op_modes[0].cycle_time_sync0, 1000u);
    EXPECT_EQ(d.eeprom_bytes, 2048u);
    EXPECT_EQ(d.config_data, (std::vector<uint8_t>{0x05, 0x0C}));
    EXPECT_EQ(d.bootstrap.size(), 8u);
}

TEST(EsiReader, RejectsWhatIsNotAnEsi) {
    EXPECT_THROW(read_esi_text("<Other/>"), std::runtime_error);
    EXPECT_THROW(read_esi_text("<EtherCATInfo><Descriptions>"), std::runtime_error);
    EXPECT_THROW(read_esi_text("<EtherCATInfo><Descriptions><Devices/></Descriptions></EtherCATInfo>"),
                 std::runtime_error);
    EXPECT_THROW(read_esi_file("/nonexistent/esi.xml"), std::runtime_error);
}

TEST(EsiReader, NumbersAndTypes) {
    EXPECT_EQ(parse_esi_number("#x1A00"), 0x1A00);
    EXPECT_EQ(parse_esi_number("0x10"), 16);
    EXPECT_EQ(parse_esi_number("-5"), -5);
    EXPECT_EQ(parse_esi_number("42"), 42);
    EXPECT_FALSE(parse_esi_number(""));
    EXPECT_FALSE(parse_esi_number("#xZZ"));
    EXPECT_EQ(esi_basic_bits("UDINT"), 32u);
    EXPECT_EQ(esi_basic_bits("STRING(6)"), 48u);
    EXPECT_EQ(esi_basic_bits("BIT3"), 3u);
    EXPECT_EQ(esi_coe_type("SINT"), 0x0002);
    EXPECT_EQ(esi_coe_type("UDINT"), 0x0007);
    EXPECT_EQ(esi_coe_type("STRING(3)"), 0x0009);
    EXPECT_EQ(esi_coe_type("DT1018"), 0);
}

TEST(Sii, WalksCategoriesAndChecksums) {
    SiiImage s;
    s.bytes.assign(256, 0xFF);
    for (int i = 0; i < 0x80; ++i)
        s.bytes[static_cast<std::size_t>(i)] = 0;
    // STRINGS (10): 2 strings "ab", "c"; then the end word.
    const uint8_t cat[] = {10, 0, 3, 0, 2, 2, 'a', 'b', 1, 'c'};
    std::copy(std::begin(cat), std::end(cat), s.bytes.begin() + 0x80);
    s.bytes[0x8A] = 0xFF;
    s.bytes[0x8B] = 0xFF;
    s.parse();
    EXPECT_EQ(s.error, "");
    ASSERT_EQ(s.categories.size(), 1u);
    EXPECT_EQ(s.string(1), "ab");
    EXPECT_EQ(s.string(2), "c");
    EXPECT_EQ(s.string(3), "");
    // A category longer than the EEPROM.
    s.bytes[0x82] = 0xF0;
    s.parse();
    EXPECT_NE(s.error, "");
    // CRC-8 (0x07, seed 0xFF, no final xor): the message followed by its CRC gives 0.
    std::vector<uint8_t> m = {0x05, 0x0C, 0x00, 0xCC, 0xE8, 0x03, 0, 0, 0, 0, 0, 0, 0, 0};
    const uint8_t crc = esc::sii::crc8(m.data(), m.size());
    m.push_back(crc);
    EXPECT_EQ(esc::sii::crc8(m.data(), m.size()), 0);
}

// SII PDO entries (ETG.2010: PDO header of 8 bytes, entries of 8: index, subindex, name, data type, bit
// length, flags): a data type of fixed size must name the entry's bit length.
TEST(Sii, PdoEntryDataTypeAgainstBitLength) {
    std::vector<uint8_t> pdo = {0x00, 0x1A, 3, 3, 0,    0,  0, 0,   // 0x1A00, 3 entries, SM3
                                0x41, 0x60, 0, 0, 0x06, 16, 0, 0,   // 0x6041:00 UNSIGNED16, 16 bits
                                0x64, 0x60, 0, 0, 0x04, 32, 0, 0,   // 0x6064:00 INTEGER32, 32 bits
                                0x00, 0x00, 0, 0, 0x00, 8,  0, 0};  // padding (index 0), not judged
    EXPECT_EQ(sii_pdo_entry_types(pdo), "");
    pdo[12] = 0x07;  // the statusword given as UNSIGNED32 with 16 bits
    EXPECT_NE(sii_pdo_entry_types(pdo).find("0x6041"), std::string::npos);
    pdo[12] = 0x33;  // BIT4 with 16 bits
    EXPECT_NE(sii_pdo_entry_types(pdo), "");
    pdo[12] = 0x01;  // BOOLEAN: ESIs map it as 1 or 8 bits, not judged
    EXPECT_EQ(sii_pdo_entry_types(pdo), "");
}

// A small JSON well-formedness checker (the report's JSON must load anywhere).
struct Json {
    const std::string& s;
    std::size_t p = 0;
    void ws() {
        while (p < s.size() && std::isspace(static_cast<unsigned char>(s[p])))
            ++p;
    }
    bool str() {
        if (s[p] != '"') return false;
        for (++p; p < s.size(); ++p) {
            const unsigned char c = static_cast<unsigned char>(s[p]);
            if (c < 0x20) return false;
            if (c == '\\') {
                ++p;
                continue;
            }
            if (c == '"') {
                ++p;
                return true;
            }
        }
        return false;
    }
    bool value() {
        ws();
        if (p >= s.size()) return false;
        if (s[p] == '{' || s[p] == '[') {
            const char close = s[p] == '{' ? '}' : ']';
            const bool obj = s[p] == '{';
            ++p;
            ws();
            if (s[p] == close) return ++p, true;
            for (;;) {
                ws();
                if (obj) {
                    if (!str()) return false;
                    ws();
                    if (s[p++] != ':') return false;
                }
                if (!value()) return false;
                ws();
                if (s[p] == ',') {
                    ++p;
                    continue;
                }
                if (s[p] == close) return ++p, true;
                return false;
            }
        }
        if (s[p] == '"') return str();
        const std::size_t b = p;
        while (p < s.size() && (std::isalnum(static_cast<unsigned char>(s[p])) || s[p] == '-' || s[p] == '.'))
            ++p;
        return p > b;
    }
};

std::vector<TestResult> sample(const Catalogue& c) {
    std::vector<TestResult> r(4);
    for (std::size_t i = 0; i < 4; ++i)
        r[i].test = &c[i];
    r[0].outcome = pass("ok", "1");
    r[1].outcome = fail("bad <value> & \"quotes\" 'x' \x01", "a\nb", "c\\d");
    r[2].outcome = skip("no ESI");
    r[3].outcome = Outcome{Status::Warn, "minor", "1", "2"};
    return r;
}

// The report of the sample results, as `write` gives it for the run `info`.
std::string sample_report(const RunInfo& info,
                          void (*write)(std::ostream&, const std::vector<TestResult>&, const RunInfo&)) {
    const Catalogue c = build_catalogue();
    const std::vector<TestResult> r = sample(c);
    std::ostringstream o;
    write(o, r, info);
    return o.str();
}

TEST(Report, JunitIsWellFormedXmlWithCounts) {
    const std::string x = sample_report(
        {"veth0", "dev \"x\" <y>", std::chrono::milliseconds(1234), {"note & more"}}, write_junit);
    xmlDoc* doc = xmlReadMemory(x.data(), static_cast<int>(x.size()), "j.xml", nullptr,
                                XML_PARSE_NONET | XML_PARSE_NOERROR);
    ASSERT_NE(doc, nullptr) << x;
    xmlNode* root = xmlDocGetRootElement(doc);
    EXPECT_STREQ(reinterpret_cast<const char*>(root->name), "testsuites");
    xmlChar* failures = xmlGetProp(root, reinterpret_cast<const xmlChar*>("failures"));
    EXPECT_STREQ(reinterpret_cast<const char*>(failures), "1");
    xmlFree(failures);
    xmlFreeDoc(doc);
    EXPECT_NE(x.find("<failure"), std::string::npos);
    EXPECT_NE(x.find("<skipped"), std::string::npos);
}

TEST(Report, JsonIsWellFormed) {
    // A device string with an ISO-8859-1 byte (a vendor's SII name): the JSON stays valid UTF-8.
    const std::string s =
        sample_report({"veth0", "dev \"x\" Ger\xE4t", std::chrono::milliseconds(5), {"n\t1"}}, write_json);
    Json j{s};
    EXPECT_TRUE(j.value()) << s;
    j.ws();
    EXPECT_EQ(j.p, s.size());
    EXPECT_NE(s.find("\"failed\":1"), std::string::npos);
    EXPECT_NE(s.find("Ger\xC3\xA4t"), std::string::npos);
}

TEST(Report, TextEndsWithTheTotalsAndHasNoColourOffATerminal) {
    Catalogue c = build_catalogue();
    auto r = sample(c);
    RunInfo info{"veth0", "dev", std::chrono::milliseconds(5), {}};
    std::ostringstream o;
    write_text(o, r, info, false, false);
    const std::string s = o.str();
    EXPECT_EQ(s.find('\033'), std::string::npos);
    EXPECT_NE(s.find("FAIL"), std::string::npos);
    EXPECT_NE(s.find("clause: "), std::string::npos);
    const std::string last = "1 passed, 1 failed, 1 skipped\n";
    ASSERT_GE(s.size(), last.size());
    EXPECT_EQ(s.substr(s.size() - last.size()), last);
    std::ostringstream col;
    write_text(col, r, info, true, false);
    EXPECT_NE(col.str().find('\033'), std::string::npos);
}

TEST(Catalogue, Invariants) {
    Catalogue c = build_catalogue();
    EXPECT_GE(c.size(), 150u);
    std::set<std::string> ids;
    std::map<std::string, int> per_group;
    const auto& groups = group_names();
    for (const auto& t : c) {
        EXPECT_TRUE(ids.insert(t.id).second) << "duplicate id " << t.id;
        EXPECT_EQ(t.id.rfind(t.group + ".", 0), 0u) << t.id;
        EXPECT_NE(std::find(groups.begin(), groups.end(), t.group), groups.end()) << t.id;
        EXPECT_FALSE(t.title.empty()) << t.id;
        EXPECT_TRUE(t.clause.find("ETG.") != std::string::npos ||
                    t.clause.find("IEC 61800") != std::string::npos)
            << t.id << ": clause names no standard: " << t.clause;
        EXPECT_TRUE(static_cast<bool>(t.run)) << t.id;
        for (char ch : t.id)
            EXPECT_TRUE(std::islower(static_cast<unsigned char>(ch)) ||
                        std::isdigit(static_cast<unsigned char>(ch)) || ch == '.' || ch == '_')
                << t.id;
        ++per_group[t.group];
    }
    for (const auto& g : groups)
        EXPECT_GE(per_group[g], 5) << "group " << g;
}

TEST(Report, SlaveStringsAreEscapedInTheTextReport) {
    EXPECT_EQ(printable("MAXPOS 50/5"), "MAXPOS 50/5");
    EXPECT_EQ(printable(std::string("a\x01\n\x7f\xff\\b", 7)), "a\\x01\\x0a\\x7f\\xff\\\\b");
    Catalogue c = build_catalogue();
    std::vector<TestResult> r(1);
    r[0].test = &c.front();
    r[0].outcome = fail("name", std::string("bad\x1b[2Jname", 11), "good");
    std::ostringstream o;
    std::string group;
    write_text_result(o, r[0], group, false, false);
    EXPECT_EQ(o.str().find('\033'), std::string::npos);
    EXPECT_NE(o.str().find("bad\\x1b[2Jname"), std::string::npos);
}

}  // namespace
}  // namespace conform
