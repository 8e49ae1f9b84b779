// (8) The master library's parsing of what comes back (tools/lib/master): frame and datagram parsing, the
// SII reader, the mailbox, CoE (SDO upload/download, segmented, SDO information, emergencies) and FoE
// (read, write, busy, errors), diagnosis messages. The master talks to a link that answers each frame it
// sends from the input: a control byte, then
//   mode 0  the request echoed with every datagram's data replaced by input bytes and working counter
//           (control >> 2) & 3 (a slave that answered with these bytes)
//   mode 1  a whole frame from the input (16-bit length + bytes): anything on the wire
//   mode 2  no reply (a lost frame: timeouts, retries, mailbox repeat requests)
//   mode 3  the request echoed unchanged with working counter (control >> 2) & 3 (a write that took)
// Once the input is used up nothing answers any more. The first input byte picks the operation; 10 and 11
// feed the rest of the input straight to the diagnosis message decoder and the frame reader. All timeouts
// are zero, so nothing waits.
#include <chrono>
#include <deque>
#include <vector>

#include "esc/link.hpp"
#include "fuzz_support.hpp"
#include "harnesses.hpp"
#include "master/coe.hpp"
#include "master/diag.hpp"
#include "master/foe.hpp"
#include "master/frame.hpp"
#include "master/mailbox.hpp"
#include "master/master.hpp"
#include "util/le.hpp"

namespace fuzz::master_reply {
namespace {

class ReplyLink final : public esc::Link {
  public:
    explicit ReplyLink(Input& in) : in_(in) {}
    int fd() const override { return -1; }
    std::size_t receive(std::span<uint8_t> buf) override {
        if (!have_) return 0;
        have_ = false;
        const std::size_t n = std::min(buf.size(), reply_.size());
        std::copy_n(reply_.begin(), n, buf.begin());
        return n;
    }
    bool send(std::span<const uint8_t> frame) override {
        have_ = false;
        if (in_.empty()) return true;
        const uint8_t c = in_.u8();
        const uint8_t wkc = static_cast<uint8_t>((c >> 2) & 3);
        switch (c & 3) {
            case 0:
            case 3:
                reply_.assign(frame.begin(), frame.end());
                if (reply_.size() > 6) reply_[6] |= 0x02;  // passed a slave
                echo((c & 3) == 0, wkc);
                break;
            case 1: {
                const auto r = in_.record();
                reply_.assign(r.begin(), r.end());
                break;
            }
            default:
                return true;
        }
        have_ = true;
        return true;
    }

  private:
    // Walks the datagram chain of the echoed request: new data (from the input) and working counters.
    void echo(bool new_data, uint8_t wkc) {
        std::size_t at = 16;
        for (int n = 0; n < 255 && at + 12 <= reply_.size(); ++n) {
            const unsigned lf = util::get16(&reply_[at + 6]);
            const std::size_t len = lf & 0x07FF;
            if (at + 10 + len + 2 > reply_.size()) break;
            if (new_data) {
                const auto d = in_.take(len);
                std::copy(d.begin(), d.end(), reply_.begin() + static_cast<std::ptrdiff_t>(at + 10));
            }
            reply_[at + 10 + len] = wkc;
            reply_[at + 11 + len] = 0;
            if ((lf & 0x8000) == 0) break;
            at += 10 + len + 2;
        }
    }

    Input& in_;
    std::vector<uint8_t> reply_;
    bool have_ = false;
};

master::MasterOptions options() {
    master::MasterOptions o;
    o.timeout = std::chrono::microseconds(0);
    o.retries = 1;
    o.sii_timeout = std::chrono::milliseconds(0);
    o.al_timeout = std::chrono::milliseconds(0);
    return o;
}

}  // namespace

int fuzz_one(const uint8_t* data, std::size_t size) {
    Input in(data, size);
    const uint8_t op = in.u8();
    if (op % 12 == 10) {
        const auto r = in.rest();
        if (const auto e = master::decode_diag_message(r, static_cast<uint8_t>(op >> 4))) {
            (void)master::format_diag_line(*e);
            (void)master::diag_text(*e);
        }
        return 0;
    }
    if (op % 12 == 11) {
        master::FrameReader reader(in.rest());
        for (int n = 0; n < 300 && reader.valid(); ++n) {
            const auto v = reader.next();
            if (!v) break;
            uint8_t x = 0;
            for (uint8_t b : v->data)
                x = static_cast<uint8_t>(x ^ b);
            (void)x;
        }
        return 0;
    }
    ReplyLink link(in);
    master::Master m(link, options());
    master::Mailbox mbx(m, master::Address::station(0x1001), std::chrono::milliseconds(0));
    master::SdoClient sdo(mbx);
    master::FoeClient foe(mbx);
    const auto use_mailbox = [&] {
        const master::MailboxConfig c{0x1000, 128, 0x1080, 128, 0x000C};
        return mbx.configure(c) == master::Error::Ok;
    };
    std::vector<uint8_t> buf(1024);
    switch (op % 12) {
        case 0:
            if (auto n = m.count_slaves()) (void)m.assign_station_addresses(std::min<uint16_t>(*n, 4));
            break;
        case 1:
            (void)m.sii_read_image(master::Address::position(0), (op & 0x80) != 0);
            break;
        case 2:
            (void)mbx.configure_from_sii((op & 0x80) != 0);
            break;
        case 3:
            if (use_mailbox()) (void)sdo.upload(0x1008, 0, buf, (op & 0x80) != 0);
            break;
        case 4:
            if (use_mailbox())
                (void)sdo.download(0x2000, 1, std::span<const uint8_t>(buf).first(op & 0x80 ? 300 : 4));
            break;
        case 5:
            if (use_mailbox()) (void)sdo.od_list(static_cast<uint16_t>(1 + (op >> 5)));
            break;
        case 6:
            if (use_mailbox()) (void)sdo.object_description(0x1018);
            break;
        case 7:
            if (use_mailbox()) (void)sdo.entry_description(0x1018, 1, 0x7F);
            break;
        case 8:
            if (use_mailbox()) (void)foe.read("MAXPOS", 0, 1u << 16);
            break;
        case 9:
            if (use_mailbox())
                (void)foe.write("MAXPOS", std::span<const uint8_t>(buf).first(op & 0x80 ? 700 : 50));
            break;
        default: {
            master::AlStatus st;
            (void)m.al_status(master::Address::station(0x1001));
            (void)m.request_state(master::Address::station(0x1001), master::AlState::PreOp, &st);
            (void)m.identify(master::Address::station(0x1001));
            break;
        }
    }
    return 0;
}

}  // namespace fuzz::master_reply
