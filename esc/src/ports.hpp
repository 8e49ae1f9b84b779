#pragma once
// Port unit: ports 0-3 with their physical link and loop state, loop control from DL control 0x0101, the
// port bits of DL status 0x0110, the lost-link counters 0x0310-0x0313 and the frame route through the ESC
// in the fixed order 0 -> 3 -> 1 -> 2 -> 0 (ESC datasheet section I, "Frame processing" and "Loop control";
// ETG.1000.4 DL control / DL status). The route tables are rebuilt on every change, so a frame only looks
// them up.
#include <array>
#include <cstdint>

#include "memory.hpp"

namespace esc {

class Ports {
  public:
    Ports(Memory& m, uint8_t port_descriptor);

    // Power-on / ESC reset: registers already reset (DL control at its reset value). The physical links
    // stay as they are; the auto-close latches are cleared. Writes the port bits of DL status.
    void reset();

    bool exists(int p) const { return (exists_mask_ >> p) & 1u; }
    bool link(int p) const { return (link_mask_ >> p) & 1u; }
    // Loop open: a frame forwarded to the port leaves the ESC there (otherwise it is looped back).
    bool loop_open(int p) const { return (open_mask_ >> p) & 1u; }
    // What Esc::port_open() reports: the port exists, has a link and its loop is open.
    bool port_open(int p) const { return loop_open(p) && link(p); }

    // The port where a frame that passed the receive side of port p leaves the ESC (the first port with an
    // open loop after p in the order 0 -> 3 -> 1 -> 2 -> 0, p itself last), and whether on its way it is
    // looped back at a closed port 0 and so passes the processing unit. Valid for a p whose loop is open.
    int exit_after(int p) const { return exit_[static_cast<unsigned>(p)]; }
    bool via_closed_port0(int p) const { return via0_[static_cast<unsigned>(p)]; }

    // Physical link change. Returns false if nothing changed (same state or no such port).
    bool set_link(int p, bool up);
    // The master wrote DL control 0x0101 (loop settings): auto-close ports with a link reopen.
    void dl_control_written();

  private:
    void update();

    Memory& mem_;
    uint8_t exists_mask_ = 0;
    uint8_t link_mask_ = 0x01;  // after construction port 0 has a link
    uint8_t auto_closed_ = 0;   // loop setting 01 (auto close): closed by a link loss, waiting for 0x0101
    uint8_t open_mask_ = 0;
    std::array<int8_t, 4> exit_{};
    std::array<bool, 4> via0_{};
};

}  // namespace esc
