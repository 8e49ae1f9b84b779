#include <gtest/gtest.h>
#include <pcap/pcap.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <vector>

#include "esc/link_capture.hpp"

namespace {

std::string temp_path(const char* name) {
    return (std::filesystem::temp_directory_path() /
            (std::string(name) + "-" + std::to_string(::getpid()) + ".pcap"))
        .string();
}

struct RemoveFile {
    std::string path;
    ~RemoveFile() { std::remove(path.c_str()); }
};

TEST(PcapWriter, WritesAFileThatLibpcapReadsBackFrameForFrame) {
    RemoveFile file{temp_path("link-capture")};
    std::vector<std::vector<uint8_t>> frames;
    frames.push_back(std::vector<uint8_t>(29, 0x11));  // runt EtherCAT frame as a master may send it
    frames.push_back(std::vector<uint8_t>(60, 0x22));
    frames.push_back(std::vector<uint8_t>(1514, 0x33));
    frames[1][12] = 0x88;
    frames[1][13] = 0xA4;
    {
        esc::PcapWriter writer(file.path);
        writer.write(frames[0], 1'700'000'000'123'456'789ull);
        writer.write(frames[1], 1'700'000'001'000'000'001ull);
        writer.write(frames[2]);  // now
        EXPECT_EQ(writer.frames_written(), 3u);
    }
    char errbuf[PCAP_ERRBUF_SIZE];
    pcap_t* p =
        pcap_open_offline_with_tstamp_precision(file.path.c_str(), PCAP_TSTAMP_PRECISION_NANO, errbuf);
    ASSERT_NE(p, nullptr) << errbuf;
    EXPECT_EQ(pcap_datalink(p), DLT_EN10MB);
    pcap_pkthdr* hdr = nullptr;
    const u_char* data = nullptr;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        ASSERT_EQ(pcap_next_ex(p, &hdr, &data), 1) << "frame " << i;
        EXPECT_EQ(hdr->caplen, frames[i].size());
        EXPECT_EQ(hdr->len, frames[i].size());
        EXPECT_TRUE(std::equal(frames[i].begin(), frames[i].end(), data)) << "frame " << i;
        if (i == 0) {
            EXPECT_EQ(hdr->ts.tv_sec, 1'700'000'000);
            EXPECT_EQ(hdr->ts.tv_usec, 123'456'789);  // nanoseconds with PCAP_TSTAMP_PRECISION_NANO
        }
        if (i == 1) {
            EXPECT_EQ(hdr->ts.tv_usec, 1);
        }
        if (i == 2) {
            EXPECT_GT(hdr->ts.tv_sec, 1'700'000'001);
        }
    }
    EXPECT_EQ(pcap_next_ex(p, &hdr, &data), PCAP_ERROR_BREAK);  // end of file
    pcap_close(p);
}

TEST(PcapWriter, FlushMakesFramesVisibleWhileStillOpen) {
    RemoveFile file{temp_path("link-capture-flush")};
    esc::PcapWriter writer(file.path);
    const std::vector<uint8_t> f(60, 0x42);
    writer.write(f);
    writer.flush();
    // 24-byte file header + 16-byte record header + 60 bytes.
    EXPECT_EQ(std::filesystem::file_size(file.path), 24u + 16u + 60u);
}

TEST(PcapWriter, UnwritablePathIsAClearError) {
    try {
        esc::PcapWriter writer("/nonexistent-dir/x.pcap");
        FAIL() << "expected LinkError";
    } catch (const esc::LinkError& e) {
        EXPECT_EQ(e.kind(), esc::LinkError::Kind::System);
        EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/x.pcap"), std::string::npos);
    }
}

}  // namespace
