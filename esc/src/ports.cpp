// Port unit (ports.hpp): link and loop state, DL control loop settings, DL status port bits, the route of a
// frame through the ports.
#include "ports.hpp"

namespace esc {

namespace {
// The order in which a frame visits the ports: after the receive side of port p it goes to the transmit
// side of kNext[p] (ESC datasheet section I, frame processing order 0 -> 3 -> 1 -> 2 -> 0). Loop settings in
// 0x0101, 2 bits per port: 00 auto, 01 auto close, 10 always open, 11 always closed.
constexpr int kNext[4] = {3, 2, 0, 1};
constexpr uint16_t kLostLinkCounter = 0x0310;
constexpr uint16_t kPortBits = 0xFFF0;  // DL status bits this unit owns (bits 0-3: EEPROM, PDI watchdog)
}  // namespace

Ports::Ports(Memory& m, uint8_t port_descriptor) : mem_(m) {
    for (int p = 0; p < 4; ++p)
        if ((port_descriptor >> (2 * p)) & 0x03)
            exists_mask_ = static_cast<uint8_t>(exists_mask_ | (1u << p));
    link_mask_ &= exists_mask_;
}

void Ports::reset() {
    auto_closed_ = 0;
    update();
}

bool Ports::set_link(int p, bool up) {
    if (p < 0 || p >= 4 || !exists(p) || link(p) == up) return false;
    const uint8_t bit = static_cast<uint8_t>(1u << p);
    if (up) {
        link_mask_ = static_cast<uint8_t>(link_mask_ | bit);
    } else {
        link_mask_ = static_cast<uint8_t>(link_mask_ & ~bit);
        mem_.count_error(static_cast<uint16_t>(kLostLinkCounter + p));
        // Auto close: the loop closes with the link loss and stays closed until the master writes 0x0101.
        if (((mem_.r8(kDlControlLoop) >> (2 * p)) & 0x03) == 0x01)
            auto_closed_ = static_cast<uint8_t>(auto_closed_ | bit);
    }
    update();
    return true;
}

void Ports::dl_control_written() {
    const uint8_t loop = mem_.r8(kDlControlLoop);
    for (int p = 0; p < 4; ++p) {
        const uint8_t bit = static_cast<uint8_t>(1u << p);
        if (((loop >> (2 * p)) & 0x03) != 0x01) {
            auto_closed_ = static_cast<uint8_t>(auto_closed_ & ~bit);
        } else if (link(p)) {
            auto_closed_ = static_cast<uint8_t>(auto_closed_ & ~bit);  // written with a link: reopens
        } else {
            auto_closed_ = static_cast<uint8_t>(auto_closed_ | bit);  // written without: waits for the next
        }
    }
    update();
}

void Ports::update() {
    const uint8_t loop = mem_.r8(kDlControlLoop);
    uint8_t open = 0;
    for (int p = 0; p < 4; ++p) {
        if (!exists(p)) continue;  // a port that is not implemented is always closed
        bool o = false;
        switch ((loop >> (2 * p)) & 0x03) {
            case 0x00:
                o = link(p);
                break;  // auto
            case 0x01:
                o = link(p) && !((auto_closed_ >> p) & 1u);
                break;  // auto close
            case 0x02:
                o = true;
                break;  // always open
            default:
                o = false;
                break;  // always closed
        }
        if (o) open = static_cast<uint8_t>(open | (1u << p));
    }
    open_mask_ = open;

    for (int p = 0; p < 4; ++p) {
        int q = kNext[p];
        bool via0 = false;
        for (int step = 0; step < 4 && !((open >> q) & 1u); ++step) {
            if (q == 0) via0 = true;
            q = kNext[q];
        }
        exit_[static_cast<unsigned>(p)] = static_cast<int8_t>(((open >> q) & 1u) ? q : -1);
        via0_[static_cast<unsigned>(p)] = via0;
    }

    // DL status: bit 4+p physical link, bit 8+2p loop closed, bit 9+2p communication established.
    uint16_t bits = 0;
    for (int p = 0; p < 4; ++p) {
        if (link(p)) bits = static_cast<uint16_t>(bits | (1u << (4 + p)));
        if (!loop_open(p)) bits = static_cast<uint16_t>(bits | (1u << (8 + 2 * p)));
        if (port_open(p)) bits = static_cast<uint16_t>(bits | (1u << (9 + 2 * p)));
    }
    const uint16_t dl = mem_.r16(reg::kDlStatus);
    const uint16_t ndl = static_cast<uint16_t>((dl & ~kPortBits) | bits);
    if (ndl != dl) {
        mem_.w16(reg::kDlStatus, ndl);
        mem_.set_ecat_event(ecev::kDlStatus);
    }
}

}  // namespace esc
