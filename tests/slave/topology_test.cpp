// The topology file parser (tools/lib/slave, slave/topology.hpp).
#include "slave/topology.hpp"

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "support/temp_dir.hpp"

namespace {

slave::Topology parse(const std::string& text) {
    return slave::parse_topology(text, "line.topo", "/etc/softecat");
}

// The message of the TopologyError the text raises ("" if it parses).
std::string error_of(const std::string& text) {
    try {
        (void)parse(text);
    } catch (const slave::TopologyError& e) {
        return e.what();
    }
    return {};
}

TEST(Topology, ALineByDefault) {
    const auto t = parse(
        "# three drives\n"
        "timing processing-ns=400 forwarding-ns=300 cable-ns=15\n"
        "device a config=a.conf serial=7\n"
        "device b drift-ppm=-12.5 offset-ns=-3000 cable-ns=50\n"
        "\n"
        "device c state-dir=/tmp/c  # comment\n");
    ASSERT_EQ(t.devices.size(), 3u);
    EXPECT_EQ(t.timing.processing_delay_ns, 400u);
    EXPECT_EQ(t.timing.forwarding_delay_ns, 300u);
    EXPECT_EQ(t.timing.cable_delay_ns, 15u);
    EXPECT_EQ(t.devices[0].name, "a");
    EXPECT_EQ(t.devices[0].parent, -1);
    EXPECT_EQ(t.devices[0].config, "/etc/softecat/a.conf") << "relative to the topology file's folder";
    EXPECT_EQ(t.devices[0].serial, 7u);
    EXPECT_EQ(t.devices[1].parent, 0);
    EXPECT_EQ(t.devices[1].parent_port, 1);
    EXPECT_EQ(t.devices[1].port, 0);
    EXPECT_DOUBLE_EQ(t.devices[1].drift_ppm, -12.5);
    EXPECT_EQ(t.devices[1].offset_ns, -3000);
    EXPECT_EQ(t.devices[1].cable_ns, 50);
    EXPECT_FALSE(t.devices[1].serial.has_value());
    EXPECT_EQ(t.devices[2].parent, 1);
    EXPECT_EQ(t.devices[2].state_dir, "/tmp/c");
    EXPECT_EQ(t.devices[2].line, 6);
    EXPECT_EQ(t.devices[2].port_descriptor(), 0x0F);
    EXPECT_EQ(t.external_device, -1);
}

TEST(Topology, ATreeWithAJunction) {
    const auto t = parse(
        "device j ports=4\n"
        "device a at=j:1\n"
        "device b at=j:3 port=0\n"
        "device c at=j:2\n"
        "device d at=c:1\n"
        "external d:1\n");
    ASSERT_EQ(t.devices.size(), 5u);
    EXPECT_EQ(t.devices[0].port_descriptor(), 0xFF);
    EXPECT_EQ(t.devices[2].parent, 0);
    EXPECT_EQ(t.devices[2].parent_port, 3);
    EXPECT_EQ(t.devices[3].parent_port, 2);
    EXPECT_EQ(t.devices[4].parent, 3);
    EXPECT_EQ(t.external_device, 4);
    EXPECT_EQ(t.external_port, 1);
    EXPECT_EQ(t.find("c"), 3);
    EXPECT_EQ(t.find("4"), 4);
    EXPECT_EQ(t.find("5"), -1);
    EXPECT_EQ(t.find("nope"), -1);
}

TEST(Topology, ForwardReferencesAreResolved) {
    const auto t = parse("device root ports=4\ndevice x at=y:1\ndevice y at=root:3\n");
    EXPECT_EQ(t.devices[1].parent, 2);
    EXPECT_EQ(t.devices[2].parent, 0);
}

TEST(Topology, ErrorsNameFileAndLine) {
    EXPECT_EQ(error_of("device a\ndevice b colour=red\n"),
              "line.topo:2: unknown key 'colour' (device takes config, esi, device, at, port, ports, serial, "
              "drift-ppm, offset-ns, cable-ns, state-dir)");
    EXPECT_EQ(error_of("device a\n\ndevice b at=zz:1\n"), "line.topo:3: at=zz:1: unknown device 'zz'");
    EXPECT_EQ(error_of("device a\ndevice b at=a:1\ndevice c at=a:1\n"),
              "line.topo:3: at=a:1: port 1 of 'a' used twice (also at line 2)");
    EXPECT_EQ(error_of("device a\ndevice b serial=12x\n"),
              "line.topo:2: bad number '12x' for serial (expected an integer 0..4294967295)");
    EXPECT_EQ(error_of("device a\ndevice b drift-ppm=fast\n"),
              "line.topo:2: bad number 'fast' for drift-ppm (expected -1000..1000)");
    EXPECT_EQ(error_of("timing cable-ns=-1\n"),
              "line.topo:1: bad number '-1' for cable-ns (expected an integer 0..100000000)");
    EXPECT_EQ(error_of("wire a b\n"), "line.topo:1: unknown statement 'wire' (timing, device, external)");
}

// esi=FILE [device=SPEC]: a device from its ESI (a mixed line by hand); paths relative to the file's folder.
TEST(Topology, DevicesFromAnEsi) {
    const slave::Topology t = slave::parse_topology(
        "device coupler esi=ex/coupler.xml ports=4\ndevice di esi=/abs/io.xml device=0x03f03052:0x00110000\n"
        "device drive config=d.conf\n",
        "line.topo", "/base");
    EXPECT_EQ(t.devices[0].esi, "/base/ex/coupler.xml");
    EXPECT_EQ(t.devices[0].device_spec, "");
    EXPECT_EQ(t.devices[1].esi, "/abs/io.xml");
    EXPECT_EQ(t.devices[1].device_spec, "0x03f03052:0x00110000");
    EXPECT_EQ(t.devices[2].esi, "");
    EXPECT_EQ(error_of("device a\ndevice b device=EXD1008\n"),
              "line.topo:2: device=EXD1008: without esi=FILE");
    EXPECT_EQ(
        error_of("device a esi=x.xml config=y.conf\n"),
        "line.topo:1: esi= and config= together: config= configures the built-in drive, esi= serves another "
        "device");
}

// A device given by esi= has the ports its ESI's Physics declares (ETG.2000), asked of the caller once per
// such device without ports=; ports= written wins; a port the Physics does not declare cannot be plugged
// into, and a device that cannot be served is an error at its line.
TEST(Topology, AnEsiDeviceHasThePortsItsPhysicsDeclares) {
    int asked = 0;
    const slave::PortsOfEsi ports = [&asked](const slave::TopologyDevice& d) -> uint8_t {
        ++asked;
        if (d.esi.ends_with("bad.xml")) throw std::runtime_error("bad.xml:3: not an ESI");
        if (d.device_spec == "END") return 0x03;     // "Y": port 0 only
        if (d.device_spec == "BRANCH") return 0x8F;  // "YY K": ports 0, 1 and 3 (E-Bus)
        return 0x0A;                                 // "KK": E-Bus in and out
    };
    const auto t = slave::parse_topology(
        "device c esi=c.xml device=BRANCH\n"
        "device k esi=k.xml device=KK at=c:3\n"
        "device e esi=e.xml device=END at=c:1\n"
        "device j esi=e.xml device=END ports=4 at=k:1\n"
        "device m at=j:2\n",
        "line.topo", "/etc/softecat", ports);
    EXPECT_EQ(asked, 3) << "not for a device with ports= or without esi=";
    ASSERT_EQ(t.devices.size(), 5u);
    EXPECT_EQ(t.devices[0].port_descriptor(), 0x8F);
    EXPECT_EQ(t.devices[1].port_descriptor(), 0x0A);
    EXPECT_EQ(t.devices[2].port_descriptor(), 0x03);
    EXPECT_EQ(t.devices[3].port_descriptor(), 0xFF) << "ports= written wins";
    EXPECT_EQ(t.devices[4].port_descriptor(), 0x0F) << "the built-in drive";
    EXPECT_EQ(t.devices[1].parent_port, 3);
    const auto error = [&ports](const std::string& text) {
        try {
            (void)slave::parse_topology(text, "line.topo", "/etc/softecat", ports);
        } catch (const slave::TopologyError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_EQ(error("device c esi=c.xml device=BRANCH\ndevice d at=c:2\n"),
              "line.topo:2: at=c:2: device 'c' has only ports 0, 1, 3 (its ESI's Physics; ports=4 for a "
              "junction)");
    EXPECT_EQ(error("device e esi=e.xml device=END\ndevice d\n"),
              "line.topo:2: at=e:1: device 'e' has only ports 0 (its ESI's Physics; ports=4 for a junction)");
    EXPECT_EQ(error("device a\ndevice b esi=k.xml device=KK port=2 at=a:1\n"),
              "line.topo:2: port=2: the device has only ports 0..1");
    EXPECT_EQ(error("device a\ndevice b esi=bad.xml\n"), "line.topo:2: device b: bad.xml:3: not an ESI");
    // Without a callback (parse_topology's default) an esi= device has two ports, as before.
    EXPECT_EQ(parse("device e esi=e.xml device=END\ndevice d\n").devices[0].port_descriptor(), 0x0F);
}

TEST(Topology, ALoopIsRefused) {
    const std::string e = error_of("device r ports=4\ndevice a at=b:1\ndevice b at=a:1\n");
    EXPECT_EQ(e.rfind("line.topo:2: device 'a' is part of a loop", 0), 0u) << e;
    EXPECT_EQ(error_of("device r\ndevice a at=a:1\n"),
              "line.topo:2: at=: device 'a' plugged into itself (a loop)");
    EXPECT_EQ(error_of("device r at=r:1\n"),
              "line.topo:1: the first device is the root (its port 0 faces the master); it takes no at=");
}

TEST(Topology, PortsMustExistAndBeFree) {
    EXPECT_EQ(error_of("device a\ndevice b at=a:2\n"),
              "line.topo:2: at=a:2: device 'a' has only ports 0..1 (ports=4 for a junction)");
    EXPECT_EQ(error_of("device a\ndevice b at=a:0\n"),
              "line.topo:2: at=a:0: port 0 of 'a' used twice (also at line 1)")
        << "the root's port 0 faces the master";
    EXPECT_EQ(error_of("device a\ndevice b port=1\ndevice c at=b:1\n"),
              "line.topo:3: at=b:1: port 1 of 'b' used twice (also at line 2)");
    EXPECT_EQ(error_of("device a\ndevice b\nexternal a:1\n"),
              "line.topo:3: external: port 1 of 'a' used twice (also at line 2)");
    EXPECT_EQ(error_of("device a\ndevice b port=5\n"),
              "line.topo:2: bad number '5' for port (expected an integer 0..3)");
    EXPECT_EQ(error_of("device a ports=3\n"), "line.topo:1: ports=3: an ESC has 2 or 4 ports");
}

TEST(Topology, NamesAreUnique) {
    EXPECT_EQ(error_of("device a\ndevice a\n"), "line.topo:2: device 'a' declared twice (first at line 1)");
    EXPECT_EQ(error_of("device 3\n"),
              "line.topo:1: device name '3' must not be a number (numbers are device indexes)");
    EXPECT_EQ(error_of("# nothing\n"), "line.topo:1: no device declared");
}

TEST(Topology, LineOfDrives) {
    const auto t = slave::line_topology(4);
    ASSERT_EQ(t.devices.size(), 4u);
    EXPECT_EQ(t.devices[0].name, "drive1");
    EXPECT_EQ(t.devices[0].parent, -1);
    EXPECT_EQ(t.devices[3].name, "drive4");
    EXPECT_EQ(t.devices[3].serial, 4u);
    EXPECT_EQ(t.devices[3].parent, 2);
    EXPECT_EQ(t.devices[3].parent_port, 1);
}

TEST(Topology, MissingFile) {
    try {
        (void)slave::load_topology("/nonexistent/x.topo");
        FAIL() << "no error";
    } catch (const slave::TopologyError& e) {
        EXPECT_EQ(std::string(e.what()).rfind("/nonexistent/x.topo: cannot open the topology file", 0), 0u)
            << e.what();
    }
}

// Issue 24, finding 6: device names became state directory paths (device ../escapeA, device /tmp/x,
// device ./a) and NUL was accepted. Names are of a documented character set, unique; state-dir= values are
// unique.
TEST(Topology, NamesCannotLeaveTheStateDirectory) {
    for (const char* bad :
         {"../escapeA", "/tmp/x", "./a", ".", "..", ".hidden", "a/b", "-a", "\"a b\"", "a\\b"}) {
        const std::string e = error_of(std::string("device ") + bad + "\n");
        EXPECT_NE(e.find("line.topo:1: device name"), std::string::npos) << bad << " -> " << e;
    }
    EXPECT_NE(error_of(std::string("device a\0b\n", 10)).find("line.topo:1: control character"),
              std::string::npos);
    EXPECT_NE(error_of("device " + std::string(65, 'a') + "\n").find("1..64 characters"), std::string::npos);
    EXPECT_EQ(error_of("device drive_1.x-2\ndevice " + std::string(64, 'a') + "\n"), "");
    EXPECT_EQ(
        error_of("device a state-dir=s\ndevice b state-dir=./s\n"),
        "line.topo:2: state-dir=./s: also the state directory of 'a' (line 1); each device needs its own");
}

// Issue 24, finding 7: a topology had no device limit (--slaves stopped at 1000); one limit for both.
TEST(Topology, OneDeviceLimitForTopologyAndSlaves) {
    std::string text;
    for (std::size_t k = 0; k < slave::kMaxDevices; ++k)
        text += "device d" + std::to_string(k) + "\n";
    EXPECT_EQ(parse(text).devices.size(), slave::kMaxDevices);
    text += "device one_more\n";
    EXPECT_EQ(error_of(text), "line.topo:" + std::to_string(slave::kMaxDevices + 1) +
                                  ": more than 1000 devices (the limit of a segment)");
}

// Issue 24, finding 5: the topology reader had no limit and read FIFOs and devices.
TEST(Topology, OnlyARegularFileWithinTheLimitIsRead) {
    test_support::TempDir dir;
    const auto fifo = dir.path / "fifo.topo";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    for (const std::string& f : {fifo.string(), std::string("/dev/zero"), dir.path.string()}) {
        try {
            (void)slave::load_topology(f);
            ADD_FAILURE() << f;
        } catch (const slave::TopologyError& e) {
            EXPECT_NE(std::string(e.what()).find(f + ": not a regular file"), std::string::npos) << e.what();
        }
    }
    const auto big = dir.path / "big.topo";
    std::ofstream(big) << "device a\n";
    std::filesystem::resize_file(big, slave::kMaxTopologyBytes + 1);
    EXPECT_THROW((void)slave::load_topology(big.string()), slave::TopologyError);
}

}  // namespace
