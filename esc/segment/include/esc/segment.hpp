#pragma once
// A segment of ESCs wired together in one process: a line by default, a tree where a device uses ports
// 1/2/3, each cable with its propagation delay, each ESC with its forwarding delay, and the faults a real
// line has (a cable pulled, a device powered off, frames lost or corrupted on a cable, a longer cable).
//
// A frame from the master enters the root device (device 0) at its port 0 and is walked through the
// segment as the ESCs would pass it on (Esc::receive() gives the next port at each device): down every open
// port, back up through the same cable, until the root sends it out of port 0 again. The walk keeps a
// virtual time (arrival time + forwarding and cable delays) that every ESC latches its receive times at, so
// a master measures propagation delays that grow along the line. One port of one device may lead out of the
// process (an "external" port, e.g. `--out-iface`): the walk sends the frame there and stops; when the frame
// comes back on that interface, resume() finishes the walk.
//
// The Segment does not own the ESCs; it holds pointers (replace() swaps one for a power cycle).
// walk()/resume() allocate nothing. Not thread-safe: used from the runtime's thread.
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "esc/esc.hpp"

namespace esc {

// Delays on the wire (ns). Defaults: about what an MII ESC and two metres of cable give.
struct SegmentTiming {
    uint32_t processing_delay_ns = 320;  // port 0 in -> processing unit -> next port out
    uint32_t forwarding_delay_ns = 280;  // any other port in -> next port out
    uint32_t cable_delay_ns = 10;        // each cable, each direction, unless the cable sets its own
};

// Faults on one cable ("hop"). Hop k is the cable into device k from its upstream side (hop 0: the master's
// cable into the root). Fractions in [0, 1]; the random choice is a deterministic generator per hop.
struct HopFaults {
    double drop = 0.0;            // frames lost on this cable (either direction)
    double corrupt = 0.0;         // frames arriving here with a bad FCS (FrameCheck::crc_bad)
    uint32_t extra_delay_ns = 0;  // added to the cable delay in each direction (a longer cable)
    uint64_t hold_ns = 0;         // the reply is held back this long in real time (Segment::Result::hold_ns)
};

struct HopStats {
    uint64_t frames = 0;     // frames that crossed this cable downwards
    uint64_t dropped = 0;    // lost here by HopFaults::drop or because the cable is pulled
    uint64_t corrupted = 0;  // given a bad FCS here
};

class Segment {
  public:
    // Result of walking a frame.
    struct Result {
        enum class Kind : uint8_t {
            Reply,     // the frame leaves the root's port 0: send it back to the master
            External,  // sent out of the external port (external_send was called): resume() finishes it
            Dropped,   // lost (a fault, a closed port, circulating twice)
        } kind = Kind::Dropped;
        uint64_t hold_ns = 0;  // sum of HopFaults::hold_ns of the cables crossed: delay the reply this long
    };

    explicit Segment(SegmentTiming timing = {});
    ~Segment();
    Segment(const Segment&) = delete;
    Segment& operator=(const Segment&) = delete;

    // Adds a device; returns its index (0 = root, whose port 0 faces the master). The ESC must outlive the
    // Segment or be replaced before it is destroyed.
    int add(Esc& esc);
    // Connects port a_port of device a to port b_port of device b. The topology must stay a tree: throws
    // std::invalid_argument (with a readable message) for an unknown device or port, a port used twice, a
    // loop, or a connection to the root's port 0. cable_delay_ns < 0: SegmentTiming::cable_delay_ns.
    // Both ports get a link (Esc::set_link).
    void connect(int a, int a_port, int b, int b_port, int64_t cable_delay_ns = -1);
    // Port `port` of device `device` leads out of the process: frames sent there go to `send` (which must
    // not call back into the Segment). At most one external port. Its link follows set_external_link()
    // (the carrier of the outgoing interface).
    void set_external(int device, int port, std::function<void(std::span<const uint8_t>)> send);
    void set_external_link(bool up);

    std::size_t size() const;
    Esc& esc(int device);
    // The EscSignals of devices 0..size()-1, side by side (valid until the next add()): a runtime finds the
    // ESCs with a timer due and a line the devices with an event without touching the others.
    EscSignals* signals();
    const EscSignals* signals() const;
    // Device at the other end of (device, port), -1 if none (or the master / the external port).
    int neighbour(int device, int port) const;
    // Upstream port of a device (towards the master) and its parent (-1 for the root).
    int upstream_port(int device) const;
    int parent(int device) const;
    // Devices in the order a frame meets their processing units (what a master counts as positions 0..N-1).
    std::vector<int> order() const;

    // ---- frames ----------------------------------------------------------------------------------
    // A frame from the master, received at Clock time rx_clock_ns.
    Result walk(std::span<uint8_t> frame, uint64_t rx_clock_ns);
    // A frame that came back on the external port at Clock time rx_clock_ns.
    Result resume(std::span<uint8_t> frame, uint64_t rx_clock_ns);

    // ---- faults ----------------------------------------------------------------------------------
    // Pulls (up = false) or plugs the cable at (device, port): both ends lose / get their link. For the
    // root's port 0 only the root's side changes (the master's NIC is not ours).
    void set_cable(int device, int port, bool up);
    // Power: off takes the links of all the device's cables down at both ends (its neighbours see the link
    // go) and frames are no longer passed through it; on restores them. replace() swaps in a fresh ESC
    // (the power-cycled one) keeping the wiring.
    void set_power(int device, bool on);
    bool powered(int device) const;
    void replace(int device, Esc& esc);
    void set_hop_faults(int hop, const HopFaults& faults);
    const HopFaults& hop_faults(int hop) const;
    const HopStats& hop_stats(int hop) const;

    const SegmentTiming& timing() const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace esc
