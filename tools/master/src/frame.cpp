#include "master/frame.hpp"

#include <algorithm>
#include <cstring>

namespace master {
namespace {

void put16(uint8_t* p, uint16_t v) {
    p[0] = static_cast<uint8_t>(v);
    p[1] = static_cast<uint8_t>(v >> 8);
}
uint16_t get16(const uint8_t* p) {
    return static_cast<uint16_t>(p[0] | (p[1] << 8));
}

}  // namespace

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
    std::memset(p, 0xFF, 6);  // broadcast: ESCs do not evaluate the destination
    std::memcpy(p + 6, source.data(), 6);
    p[12] = static_cast<uint8_t>(kEtherType >> 8);
    p[13] = static_cast<uint8_t>(kEtherType & 0xFF);
    put16(p + 14, static_cast<uint16_t>((chain & 0x07FF) | 0x1000));
    std::size_t pos = kEthernetHeaderSize + kEcatHeaderSize;
    for (std::size_t i = 0; i < datagrams.size(); ++i) {
        const Datagram& d = datagrams[i];
        uint8_t* h = p + pos;
        h[0] = static_cast<uint8_t>(d.command);
        h[1] = static_cast<uint8_t>(first_index + i);
        put16(h + 2, d.adp);
        put16(h + 4, d.ado);
        const bool more = i + 1 < datagrams.size();
        put16(h + 6, static_cast<uint16_t>(d.data.size() | (more ? 0x8000 : 0)));
        put16(h + 8, 0);
        if (!d.data.empty()) std::memcpy(h + kDatagramHeaderSize, d.data.data(), d.data.size());
        put16(h + kDatagramHeaderSize + d.data.size(), 0);
        pos += kDatagramOverhead + d.data.size();
    }
    std::memset(p + pos, 0, total - pos);
    return total;
}

FrameReader::FrameReader(std::span<const uint8_t> frame) : frame_(frame) {
    if (frame.size() < kEthernetHeaderSize + kEcatHeaderSize) return;
    std::size_t off = 12;
    uint16_t type = static_cast<uint16_t>((frame[off] << 8) | frame[off + 1]);
    if (type == 0x8100) {  // one 802.1Q tag
        off += 4;
        if (frame.size() < off + 2 + kEcatHeaderSize) return;
        type = static_cast<uint16_t>((frame[off] << 8) | frame[off + 1]);
    }
    if (type != kEtherType) return;
    off += 2;
    const uint16_t header = get16(frame.data() + off);
    if ((header >> 12) != 1) return;
    const std::size_t length = header & 0x07FF;
    pos_ = off + kEcatHeaderSize;
    end_ = pos_ + length;
    if (end_ > frame.size()) return;
    valid_ = true;
}

std::optional<DatagramView> FrameReader::next() {
    if (!valid_ || done_) return std::nullopt;
    if (pos_ + kDatagramOverhead > end_) {
        done_ = true;
        valid_ = false;  // the chain ended without a datagram with M=0: malformed
        return std::nullopt;
    }
    const uint8_t* h = frame_.data() + pos_;
    const uint16_t len_flags = get16(h + 6);
    const std::size_t len = len_flags & 0x07FF;
    if (pos_ + kDatagramOverhead + len > end_) {
        done_ = true;
        valid_ = false;
        return std::nullopt;
    }
    DatagramView v{static_cast<Command>(h[0]),
                   h[1],
                   get16(h + 2),
                   get16(h + 4),
                   (len_flags & 0x4000) != 0,
                   (len_flags & 0x8000) != 0,
                   get16(h + 8),
                   std::span<const uint8_t>(h + kDatagramHeaderSize, len),
                   get16(h + kDatagramHeaderSize + len)};
    pos_ += kDatagramOverhead + len;
    if (!v.more) done_ = true;
    return v;
}

}  // namespace master
