// PcapWriter: .pcap recording. See esc/link_capture.hpp.
#include "esc/link_capture.hpp"

#include <pcap/pcap.h>
#include <time.h>

namespace esc {

PcapWriter::PcapWriter(const std::string& path) : path_(path) {
    dead_ = pcap_open_dead_with_tstamp_precision(DLT_EN10MB, static_cast<int>(kMaxFrameSize),
                                                 PCAP_TSTAMP_PRECISION_NANO);
    if (dead_ == nullptr) throw LinkError(LinkError::Kind::System, "pcap_open_dead failed");
    dumper_ = pcap_dump_open(dead_, path.c_str());
    if (dumper_ == nullptr) {
        const std::string detail = pcap_geterr(dead_);
        pcap_close(dead_);
        dead_ = nullptr;
        throw LinkError(LinkError::Kind::System, "cannot write capture file '" + path + "': " + detail);
    }
}

PcapWriter::~PcapWriter() {
    if (dumper_ != nullptr) pcap_dump_close(dumper_);
    if (dead_ != nullptr) pcap_close(dead_);
}

void PcapWriter::write(std::span<const uint8_t> frame, uint64_t realtime_ns) {
    if (realtime_ns == 0) {
        timespec ts{};
        clock_gettime(CLOCK_REALTIME, &ts);
        realtime_ns = static_cast<uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<uint64_t>(ts.tv_nsec);
    }
    pcap_pkthdr hdr{};
    hdr.ts.tv_sec = static_cast<time_t>(realtime_ns / 1000000000ull);
    // With nanosecond precision libpcap stores tv_usec as nanoseconds.
    hdr.ts.tv_usec = static_cast<suseconds_t>(realtime_ns % 1000000000ull);
    hdr.len = static_cast<bpf_u_int32>(frame.size());
    hdr.caplen = static_cast<bpf_u_int32>(std::min(frame.size(), kMaxFrameSize));
    pcap_dump(reinterpret_cast<u_char*>(dumper_), &hdr, frame.data());
    ++frames_;
}

void PcapWriter::flush() {
    pcap_dump_flush(dumper_);
}

}  // namespace esc
