#pragma once
// PcapWriter: records frames to a classic .pcap file (link type DLT_EN10MB, nanosecond time stamps) that
// Wireshark and tshark open directly. Writing a frame does not allocate (stdio buffer of libpcap).
#include <cstdint>
#include <span>
#include <string>

#include "esc/link.hpp"

struct pcap;
struct pcap_dumper;

namespace esc {

class PcapWriter {
  public:
    // Creates (truncates) path. Throws LinkError(System) if it cannot.
    explicit PcapWriter(const std::string& path);
    ~PcapWriter();
    PcapWriter(const PcapWriter&) = delete;
    PcapWriter& operator=(const PcapWriter&) = delete;

    // Appends one frame. realtime_ns: wall-clock time stamp (ns since the epoch); 0 = now.
    void write(std::span<const uint8_t> frame, uint64_t realtime_ns = 0);
    // Pushes buffered frames to the file.
    void flush();
    uint64_t frames_written() const { return frames_; }
    const std::string& path() const { return path_; }

  private:
    std::string path_;
    struct pcap* dead_ = nullptr;
    struct pcap_dumper* dumper_ = nullptr;
    uint64_t frames_ = 0;
};

}  // namespace esc
