// The fwimage program: build writes an image verify_image accepts; info verifies and reports.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "foe/image.hpp"
#include "foe_test_support.hpp"

#ifdef FWIMAGE_PATH
namespace {
// Under timeout(1): a program that hangs (a FIFO opened blocking) fails the test with 124, not the run.
int run(const std::string& args) {
    const int status =
        std::system(("timeout 60 " + std::string(FWIMAGE_PATH) + " " + args + " >/dev/null 2>&1").c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}
std::vector<uint8_t> slurp(const std::filesystem::path& p) {
    std::ifstream f(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}
}  // namespace

TEST(Fwimage, BuildThenInfo) {
    foe_test::TempDir d;
    const auto payload = foe_test::payload_bytes(5000, 4);
    std::ofstream(d.path / "fw.bin", std::ios::binary)
        .write(reinterpret_cast<const char*>(payload.data()), static_cast<std::streamsize>(payload.size()));
    const std::string img = (d.path / "image.bin").string();
    ASSERT_EQ(run("build --payload " + (d.path / "fw.bin").string() +
                  " --version 0x01200000 --vendor 0xFB --product 0x30010000 -o " + img),
              0);
    const auto bytes = slurp(img);
    const auto r = foe::verify_image(bytes, foe_test::kMaxpos);
    ASSERT_TRUE(r.ok()) << foe::to_string(r.error);
    EXPECT_EQ(r.header.version, 0x01200000u);
    EXPECT_EQ(bytes, foe::build_image(payload, foe_test::kMaxpos, 0x01200000));

    EXPECT_EQ(run("info " + img), 0);
    EXPECT_EQ(run("info " + img + " --product 0x30010000 --vendor 0xFB"), 0);
    EXPECT_EQ(run("info " + img + " --product 0x30020000"), 1);
    auto bad = bytes;
    bad[1000] ^= 1;
    std::ofstream(d.path / "bad.bin", std::ios::binary)
        .write(reinterpret_cast<const char*>(bad.data()), static_cast<std::streamsize>(bad.size()));
    EXPECT_EQ(run("info " + (d.path / "bad.bin").string()), 1);
    EXPECT_NE(run("info " + (d.path / "missing.bin").string()), 0);
    EXPECT_NE(run("build --payload " + (d.path / "fw.bin").string() + " --version x --product 1 -o " + img),
              0);
    EXPECT_NE(run("build --payload " + (d.path / "fw.bin").string() +
                  " --version 0x100000000 --product 1 -o " + img),
              0);
}

// The --esi file is read as every ESI is (esi::read_esi_file): a FIFO without a writer, a device, a directory
// are refused at once with exit 2 (found by the campaign of issue 24 run again: a FIFO hung fwimage in its
// open, /dev/zero and a 40 MiB file were handed to the XML parser); a small ESI gives the identity.
TEST(Fwimage, EsiFileIsCheckedBeforeItIsRead) {
    foe_test::TempDir d;
    std::ofstream(d.path / "fw.bin") << "payload";
    const std::string build = "build --payload " + (d.path / "fw.bin").string() +
                              " --version 0x01000000 -o " + (d.path / "image.bin").string() + " --esi ";
    const std::string fifo = (d.path / "fifo.xml").string();
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    std::filesystem::create_directory(d.path / "dir.xml");
    std::filesystem::create_symlink("/dev/zero", d.path / "zero.xml");
    {
        std::ofstream big(d.path / "big.xml");
        big << "<EtherCATInfo>";
        big.seekp((std::streamoff{33} << 20));
        big << "</EtherCATInfo>";
    }
    for (const char* bad : {"fifo.xml", "dir.xml", "zero.xml", "big.xml", "missing.xml"})
        EXPECT_EQ(run(build + (d.path / bad).string()), 2) << bad;
    std::ofstream(d.path / "dev.xml")
        << "<?xml version=\"1.0\"?><EtherCATInfo><Vendor><Id>#x2A</Id></Vendor><Descriptions><Devices>"
           "<Device><Type ProductCode=\"#x1234\" RevisionNo=\"1\">T1</Type><Name>Dev</Name></Device>"
           "</Devices></Descriptions></EtherCATInfo>";
    ASSERT_EQ(run(build + (d.path / "dev.xml").string()), 0);
    EXPECT_EQ(run("info " + (d.path / "image.bin").string() + " --vendor 0x2A --product 0x1234"), 0);
}
#endif
