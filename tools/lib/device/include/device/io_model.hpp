#pragma once
// The process data of a device without an application (od::Application::None: couplers, IO terminals,
// anything an ESI describes that softecat has no model of). Outputs the master writes land in the
// dictionary (ecat::ProcessData) and are shown as they are; the inputs follow this default, per cycle:
//
//   - an input entry with the name and the data type of an output entry mirrors it (the k-th input of
//     that name mirrors the k-th output of that name, in mapping order);
//   - an input entry whose name says it is a counter ("counter", any case) counts up by one, wrapping
//     at its bit length;
//   - every other input keeps its value (its default, or what was set).
//
// An input set at run time (Device::set_value, the control socket's `set`) is held: it keeps the value
// set and is no longer mirrored or counted. The plan is built when the mapping is fixed (Pre-Op ->
// Safe-Op) and cleared when process data stops; a cycle only copies and counts (no allocation).
//
// When the outputs are lost (process-data watchdog, sync loss, leaving Op by any path) every output goes to
// its safe state, 0, as an IO terminal's outputs do (EL2xxx: "outputs are switched off" on watchdog; the
// ESC datasheet's process-data watchdog: the output SM is no longer updated and the PDI side sets the
// outputs to a safe state; ETG.1000.6: Safe-Op keeps the outputs in their safe state). They stay 0 until
// the master writes outputs again in Op.
#include <cstdint>
#include <set>
#include <span>
#include <vector>

#include "ecat/process_data.hpp"
#include "od/dictionary.hpp"

namespace device {

struct IoEntry {
    const od::Entry* entry = nullptr;
    uint8_t* storage = nullptr;
};

class IoModel {
  public:
    IoModel();
    // From the stack's copy plans (the mapping taken over at Pre-Op -> Safe-Op).
    void build(const ecat::ProcessData& pd, const std::set<uint32_t>& held);
    void clear();
    // Mirrors and counters of one cycle.
    void cycle();
    // Every mapped output to its safe state, 0 (outputs lost). No allocation.
    void safe_outputs();
    // An entry was set at run time: it is neither mirrored nor counted from now on.
    void hold(uint16_t index, uint8_t sub);

    std::span<const IoEntry> outputs() const { return {outputs_.data(), outputs_.size()}; }
    std::span<const IoEntry> inputs() const { return {inputs_.data(), inputs_.size()}; }
    std::size_t mirrors() const { return mirrors_.size(); }
    std::size_t counters() const { return counters_.size(); }

    // Whether a name says the entry counts.
    static bool is_counter_name(std::string_view name);

  private:
    struct Mirror {
        const uint8_t* src;
        uint8_t* dst;
        uint16_t bits;
        uint32_t key;
    };
    struct Counter {
        uint8_t* value;
        uint16_t bits;
        uint32_t key;
    };
    std::vector<IoEntry> outputs_;
    std::vector<IoEntry> inputs_;
    std::vector<Mirror> mirrors_;
    std::vector<Counter> counters_;
};

inline uint32_t io_key(uint16_t index, uint8_t sub) {
    return (static_cast<uint32_t>(index) << 8) | sub;
}

}  // namespace device
