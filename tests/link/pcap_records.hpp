#pragma once
// Test helper: the records of a capture file (pcap), each as the bytes captured, for the tests that check
// what esc::PcapWriter wrote.
#include <cstdint>
#include <string>
#include <vector>

#include <pcap/pcap.h>

namespace linktest {

struct PcapRecords {
    bool opened = false;
    std::string error;  // why the file could not be opened
    std::vector<std::vector<uint8_t>> records;
};

inline PcapRecords read_pcap(const std::string& path) {
    PcapRecords out;
    char errbuf[PCAP_ERRBUF_SIZE] = {};
    pcap_t* p = pcap_open_offline(path.c_str(), errbuf);
    if (p == nullptr) {
        out.error = errbuf;
        return out;
    }
    out.opened = true;
    pcap_pkthdr* hdr = nullptr;
    const u_char* data = nullptr;
    while (pcap_next_ex(p, &hdr, &data) == 1)
        out.records.emplace_back(data, data + hdr->caplen);
    pcap_close(p);
    return out;
}

}  // namespace linktest
