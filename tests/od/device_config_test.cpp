// Device configuration file: the example, every key, and errors with line numbers.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "maxpos/maxpos.hpp"
#include "od/device_config.hpp"

using namespace od;

namespace {

// Runs the parser and returns the ConfigError line (or -1 if it did not throw).
int error_line(const std::string& text, std::string* message = nullptr) {
    try {
        maxpos::parse_config(text, "t.conf");
    } catch (const ConfigError& e) {
        if (message) *message = e.what();
        return e.line();
    }
    return -1;
}

}  // namespace

TEST(DeviceConfig, ExampleFileLoads) {
    const DeviceDescription d = maxpos::load_config(std::filesystem::path(OD_EXAMPLES_DIR) / "device.conf");
    EXPECT_EQ(d.identity.vendor_id, 0xFBu);
    EXPECT_EQ(d.identity.product_code, 0x30010000u);
    EXPECT_EQ(d.identity.revision, 0x01200000u);
    EXPECT_EQ(d.identity.serial_number, 0x12345678u);
    EXPECT_EQ(d.identity.device_name, "MAXPOS");
    EXPECT_EQ(d.identity.vendor_name, "maxon motor ag");
    EXPECT_EQ(d.standard_mailbox.in_start, 0x1080);
    EXPECT_EQ(d.bootstrap_mailbox.in_size, 1024);
    EXPECT_EQ(d.eeprom_bytes, 2048);
    Dictionary dict = maxpos::dictionary(d);
    EXPECT_EQ(dict.get<uint32_t>(0x1018, 4), 0x12345678u);
}

TEST(DeviceConfig, EveryKeyAndValueForm) {
    const DeviceDescription d = maxpos::parse_config(R"(
vendor_id = 0x22        # top-level identity key
interface = veth0       # a program option before any section: ignored
[identity]
product_code = 4660
revision: 0x00010002
serial_number = 0XABCDEF01
vendor_name = 'single # quoted'
device_name = "say \"hi\" \\ ok"  ; trailing comment
hardware_version = bare words here # comment
software_version = ""
order_code = "X-1"
group_type = Servo
[link]
whatever = [1, 2, 3]
[mailbox]
out_start = 0x1800
out_size = 256
in_start = 0x1900
in_size = 256
[bootstrap_mailbox]
out_start = 0x1000
out_size = 512
in_start = 0x1200
in_size = 512
[eeprom]
bytes = 4096
station_alias = 7
pdi_control = 0x08
esc_config = 0x0E
pdi_config = 0x0102
sync_pulse_length = 500
)");
    EXPECT_EQ(d.identity.vendor_id, 0x22u);
    EXPECT_EQ(d.identity.product_code, 4660u);
    EXPECT_EQ(d.identity.revision, 0x00010002u);
    EXPECT_EQ(d.identity.serial_number, 0xABCDEF01u);
    EXPECT_EQ(d.identity.vendor_name, "single # quoted");
    EXPECT_EQ(d.identity.device_name, "say \"hi\" \\ ok");
    EXPECT_EQ(d.identity.hardware_version, "bare words here");
    EXPECT_EQ(d.identity.software_version, "");
    EXPECT_EQ(d.identity.order_code, "X-1");
    EXPECT_EQ(d.identity.group_type, "Servo");
    EXPECT_EQ(d.standard_mailbox.out_start, 0x1800);
    EXPECT_EQ(d.standard_mailbox.in_size, 256);
    EXPECT_EQ(d.bootstrap_mailbox.in_start, 0x1200);
    EXPECT_EQ(d.eeprom_bytes, 4096);
    EXPECT_EQ(d.station_alias, 7);
    EXPECT_EQ(d.pdi_control, 0x08);
    EXPECT_EQ(d.esc_config, 0x0E);
    EXPECT_EQ(d.pdi_config, 0x0102);
    EXPECT_EQ(d.sync_pulse_length, 500);
    // SyncManagers follow the configured mailbox
    ASSERT_EQ(d.sync_managers.size(), 4u);
    EXPECT_EQ(d.sync_managers[0].start, 0x1800);
    EXPECT_EQ(d.sync_managers[0].default_size, 256);
    EXPECT_EQ(d.sync_managers[1].start, 0x1900);
    EXPECT_GE(d.sync_managers[2].start, 0x1A00);
}

TEST(DeviceConfig, ErrorsNameTheLine) {
    std::string msg;
    EXPECT_EQ(error_line("[identity]\nvendor_id = 0xZZ\n", &msg), 2);
    EXPECT_NE(msg.find("t.conf:2:"), std::string::npos) << msg;
    EXPECT_EQ(error_line("\n\n[identity]\nvendor_id = 0x100000000\n"), 4);  // out of UNSIGNED32
    EXPECT_EQ(error_line("[identity]\nvendr_id = 1\n", &msg), 2);           // typo in a known section
    EXPECT_NE(msg.find("unknown key"), std::string::npos);
    EXPECT_EQ(error_line("[identity\n"), 1);
    EXPECT_EQ(error_line("[identity]\njust words\n"), 2);
    EXPECT_EQ(error_line("[identity]\n= 5\n"), 2);
    EXPECT_EQ(error_line("[identity]\ndevice_name = \"unterminated\n"), 2);
    EXPECT_EQ(error_line("[identity]\ndevice_name = \"a\" b\n"), 2);
    EXPECT_EQ(error_line("[identity]\nserial_number = 1\nserial_number = 2\n"), 3);  // duplicate
    EXPECT_EQ(error_line("[identity]\nserial_number = -1\n"), 2);
    EXPECT_EQ(error_line("[identity]\nserial_number =\n"), 2);
    EXPECT_EQ(error_line("[mailbox]\nout_size = 0x10000\n"), 2);
    EXPECT_EQ(error_line("[eeprom]\nbytes = 1000\n"), 2);
    EXPECT_EQ(error_line("[eeprom]\nbytes = 65536\n"), 2);
    EXPECT_EQ(error_line("[]\n"), 1);
    // whole-file checks carry line 0
    EXPECT_EQ(error_line("[mailbox]\nin_start = 0x1040\n", &msg), 0);  // overlaps SM0
    EXPECT_NE(msg.find("overlap"), std::string::npos);
    EXPECT_EQ(error_line("[mailbox]\nout_size = 8\n"), 0);
    EXPECT_EQ(error_line("[mailbox]\nout_start = 0x0800\n"), 0);
    EXPECT_EQ(error_line("[identity]\ndevice_name = \"\"\n"), 0);
    EXPECT_EQ(error_line("[mailbox]\nout_start = 0xFE00\nin_start = 0xFF00\n", &msg),
              0);  // no room for SM2/SM3
    EXPECT_NE(msg.find("process-data"), std::string::npos) << msg;
    EXPECT_EQ(error_line("# only a comment\n; and another\n"), -1);
}

TEST(DeviceConfig, MissingFileIsAnError) {
    EXPECT_THROW(maxpos::load_config("/nonexistent/dir/device.conf"), ConfigError);
}

// Issue 14, finding 3 (every loader checks sizes against the bytes present): a configuration path that
// names an endless or oversized source is an error, not an unbounded read. Issue 24, finding 5: a device
// (/dev/zero) is refused before anything is read, as not a regular file.
TEST(DeviceConfig, OversizedOrEndlessFileIsAnError) {
    try {
        maxpos::load_config("/dev/zero");
        ADD_FAILURE() << "/dev/zero was accepted";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("/dev/zero: not a regular file"), std::string::npos) << e.what();
    }
    const auto path = std::filesystem::temp_directory_path() / ("od-config-" + std::to_string(::getpid()));
    {
        std::ofstream f(path);
        f << "[identity]\nvendor_id = 0xFB\n";
        const std::string comment = "# " + std::string(1022, 'x') + "\n";
        while (f.tellp() <= static_cast<std::streamoff>(kMaxConfigBytes))
            f << comment;
    }
    EXPECT_THROW(maxpos::load_config(path), ConfigError);
    std::filesystem::resize_file(path, 200);  // the same file, short: reads
    EXPECT_EQ(maxpos::load_config(path).identity.vendor_id, 0xFBu);
    std::filesystem::remove(path);
}

TEST(DeviceConfig, MessagesNameTheFileAndALineOnlyWhenThereIsOne) {
    try {
        maxpos::load_config("/nonexistent/dir/device.conf");
        FAIL() << "no error";
    } catch (const ConfigError& e) {
        EXPECT_EQ(std::string(e.what()),
                  "/nonexistent/dir/device.conf: cannot open the device configuration file: No such file or "
                  "directory");
        EXPECT_EQ(e.line(), 0);
    }
    std::string msg;
    EXPECT_EQ(error_line("[identity]\ndevice_name = \"\"\n", &msg), 0);  // checked after the last line
    EXPECT_EQ(msg.rfind("t.conf: ", 0), 0u) << msg;
    EXPECT_EQ(error_line("[identity\n", &msg), 1);
    EXPECT_EQ(msg.rfind("t.conf:1: ", 0), 0u) << msg;
}

// Each of the drive's example configurations loads (od/examples/*.conf are shown in the README).
TEST(DeviceConfig, EveryExampleLoads) {
    int n = 0;
    for (const auto& f : std::filesystem::directory_iterator(OD_EXAMPLES_DIR)) {
        if (f.path().extension() != ".conf") continue;
        EXPECT_NO_THROW(maxpos::load_config(f.path())) << f.path();
        ++n;
    }
    EXPECT_GE(n, 2);
    const DeviceDescription d =
        maxpos::load_config(std::filesystem::path(OD_EXAMPLES_DIR) / "bootstrap-as-standard.conf");
    EXPECT_EQ(d.bootstrap_mailbox.out_start, d.standard_mailbox.out_start);
    EXPECT_EQ(d.bootstrap_mailbox.out_size, d.standard_mailbox.out_size);
    EXPECT_EQ(d.bootstrap_mailbox.in_start, d.standard_mailbox.in_start);
    EXPECT_EQ(d.bootstrap_mailbox.in_size, d.standard_mailbox.in_size);
}

// The parser is the object model's, not the MAXPOS's: it reads on top of any product's description and
// leaves what the file does not name as that product has it; the SyncManagers are placed by the product's
// own placer, or kept.
TEST(DeviceConfig, ReadsOnTopOfAnyProductsDescription) {
    DeviceDescription base;
    base.identity.vendor_id = 0x00000002;
    base.identity.product_code = 0x07D83052;
    base.identity.device_name = "EL2008";
    base.mailbox_protocols = 0;  // a device without a mailbox
    base.sync_managers = {{SmKind::Outputs, 0x0F00, 1, 0x44, true, 0, 0}};
    const DeviceDescription d = parse_device_config("[identity]\nserial_number = 7\n", "io.conf", base);
    EXPECT_EQ(d.identity.vendor_id, 0x00000002u);
    EXPECT_EQ(d.identity.product_code, 0x07D83052u);
    EXPECT_EQ(d.identity.serial_number, 7u);
    EXPECT_EQ(d.identity.device_name, "EL2008");
    ASSERT_EQ(d.sync_managers.size(), 1u);
    EXPECT_EQ(d.sync_managers[0].start, 0x0F00);
    int placed = 0;
    const DeviceDescription p =
        parse_device_config("[identity]\nserial_number = 8\n", "io.conf", base, [&](DeviceDescription& x) {
            ++placed;
            x.sync_managers.clear();
        });
    EXPECT_EQ(placed, 1);
    EXPECT_TRUE(p.sync_managers.empty());
    // A placer that finds no room is an error of the file.
    try {
        parse_device_config("[mailbox]\nout_start = 0x1000\n", "io.conf", base,
                            [](DeviceDescription&) { throw std::out_of_range("no room"); });
        FAIL() << "no error";
    } catch (const ConfigError& e) {
        EXPECT_EQ(std::string(e.what()), "io.conf: no room");
    }
}

// The identity of the generic model names no vendor: each product states its own.
TEST(DeviceConfig, IdentityDefaultsNameNoProduct) {
    const Identity id;
    EXPECT_EQ(id.vendor_id, 0u);
    EXPECT_TRUE(id.vendor_name.empty());
    EXPECT_TRUE(id.device_name.empty());
    EXPECT_TRUE(id.group_type.empty());
}
