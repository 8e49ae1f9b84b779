#include "master/frame.hpp"

#include <algorithm>
#include <cstring>

namespace master {
std::size_t frame_size(std::span<const Datagram> datagrams) {
    std::size_t n = kEthernetHeaderSize + kEcatHeaderSize;
    for (const Datagram& d : datagrams)
        n += kDatagramOverhead + d.data.size();
    return n;
}

std::size_t encode_frame(std::span<const Datagram> datagrams, uint8_t first_index, const MacAddress& source,
                         std::span<uint8_t> out) {
    if (datagrams.empty()) return 0;
    std::size_t chain = 0;
    for (const Datagram& d : datagrams) {
        if (d.data.size() > kMaxDatagramData) return 0;
        chain += kDatagramOverhead + d.data.size();
    }
    if (chain > kMaxDatagramsLength) return 0;
    const std::size_t used = kEthernetHeaderSize + kEcatHeaderSize + chain;
    const std::size_t total = std::max(used, kMinFrameSize);
    if (out.size() < total) return 0;

    uint8_t* p = out.data();
    uint8_t mac[esc::wire::kMacSize];
    std::memcpy(mac, source.data(), sizeof mac);
    esc::wire::put_frame_header(p, mac, chain);
    std::size_t pos = kEthernetHeaderSize + kEcatHeaderSize;
    for (std::size_t i = 0; i < datagrams.size(); ++i) {
        const Datagram& d = datagrams[i];
        uint8_t* h = p + pos;
        esc::wire::put_datagram_header(h, static_cast<uint8_t>(d.command),
                                       static_cast<uint8_t>(first_index + i), d.adp, d.ado, d.data.size(),
                                       i + 1 < datagrams.size());
        if (!d.data.empty()) std::memcpy(h + kDatagramHeaderSize, d.data.data(), d.data.size());
        h[kDatagramHeaderSize + d.data.size()] = 0;  // working counter
        h[kDatagramHeaderSize + d.data.size() + 1] = 0;
        pos += kDatagramOverhead + d.data.size();
    }
    std::memset(p + pos, 0, total - pos);
    return total;
}

FrameReader::FrameReader(std::span<const uint8_t> frame)
    : frame_(frame), reader_(frame), valid_(reader_.valid()) {}

std::optional<DatagramView> FrameReader::next() {
    esc::wire::DatagramView v;
    if (!reader_.next(v)) {
        if (reader_.malformed()) valid_ = false;  // the chain ended without a datagram with M=0, or overran
        return std::nullopt;
    }
    return DatagramView{static_cast<Command>(v.command),
                        v.index,
                        v.adp,
                        v.ado,
                        v.circulating(),
                        v.more(),
                        v.irq,
                        v.data,
                        v.wkc};
}

}  // namespace master
