#pragma once
// The CiA 402 drive on top of the object dictionary. The process-data cycle (or a test) writes the outputs
// (0x6040, 0x607A, ...) into the dictionary, then calls Drive::cycle(now, dt) once per cycle; the drive reads
// its configuration and commands from the dictionary, runs the axis for dt and writes the inputs (0x6041,
// 0x6064, ...) back. Objects the dictionary does not declare keep the Axis defaults (Parameters), so the
// drive also runs on a partial dictionary.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "drive/axis.hpp"
#include "drive/event_sink.hpp"
#include "drive/objects.hpp"
#include "od/dictionary.hpp"

namespace drive {

// The parameters a commissioning tool would store for the simulated motor: torque constant (uNm/A; a
// dictionary default of 0, as the MAXPOS firmware specification's 0x3001:05, refuses to enable with 0x8331),
// and a position/velocity tuning matched to the motor and load (20 Hz bandwidth, critical damping, 50 ms
// reset time, the model's inertia and viscous friction). The drive runs on these where the device keeps no
// such parameter.
std::array<std::pair<Param, uint32_t>, 6> commissioned(const MotorModel& motor);

// Writes commissioned(motor) into the objects `vendor` names for them, those that exist. Device-side writes,
// range-checked; returns the first failure or Ok.
od::Status commission(od::Dictionary& dictionary, const VendorObjects& vendor,
                      const MotorModel& motor = MotorModel{});

class Drive {
  public:
    // Binds the CiA 402 objects (drive/objects.hpp) the dictionary has, by index, and the vendor parameters
    // where `vendor` says; the rest run on the drive's defaults (the motor model's tuning, commissioned()).
    // Serves the modes the drive implements whose set-point object the dictionary has: 0x6502 is set to
    // what it announced of them (withheld_modes()). Registers a validator on 0x6060 that refuses a mode the
    // drive does not serve or 0x6502 does not announce (InvalidValue, SDO abort 0x06090030), one on 0x60C0
    // that refuses an interpolation sub-mode other than linear (0), and one on each of
    // `vendor.power_disable_only`: such writes answer WrongState (SDO abort 0x08000022) while the power stage
    // is on.
    explicit Drive(od::Dictionary& dictionary, EventSink* sink = nullptr, const VendorObjects& vendor = {});
    Drive(const Drive&) = delete;
    Drive& operator=(const Drive&) = delete;
    ~Drive();

    void cycle(int64_t now_ns, int64_t dt_ns);
    // The master is gone: error 0x8180 with the reaction of 0x6007.
    void connection_lost();

    Axis& axis() { return axis_; }
    const Axis& axis() const { return axis_; }
    Environment& environment() { return axis_.environment(); }
    MotorModel& motor() { return axis_.motor(); }
    // How many (index, subindex) pairs the drive found in the dictionary, and how many it had to run without.
    std::size_t bound() const { return bound_; }
    std::size_t missing() const { return missing_; }
    // Whether the drive found and bound this entry (a drive/objects.hpp handle or a vendor binding).
    bool binds(uint16_t index, uint8_t sub) const;
    // The bits of the dictionary's 0x6502 the drive took out because it cannot serve those modes on this
    // dictionary (0x6502 now announces the rest); 0: it serves every mode announced.
    uint32_t withheld_modes() const { return withheld_modes_; }

  private:
    // What a scaled link converts: a position, or a velocity or acceleration.
    enum class Unit : uint8_t { Position, Velocity };
    struct Link {
        od::Ref<uint8_t> r8;
        od::Ref<uint16_t> r16;
        od::Ref<uint32_t> r32;
        uint8_t* field;
        uint16_t index;
        uint8_t sub;
        uint8_t size;
        bool is_signed;
        Unit unit;  // of a scaled link
    };
    template <typename T>
    bool in(const Obj<T>& object, T& field);
    template <typename T>
    void out(const Obj<T>& object, const T& field);
    // A position (velocity, acceleration) object: through the factor group where the device has one
    // (0x6091/0x6092), else a raw copy.
    template <typename T>
    void in_scaled(const Obj<T>& object, T& field, Unit unit);
    template <typename T>
    void out_scaled(const Obj<T>& object, const T& field, Unit unit);
    double increments_per_rev() const;
    double increments_per_unit() const;
    void load_positions();
    void store_positions();
    bool in_raw(uint16_t index, uint8_t sub, std::size_t size, uint8_t* field);
    bool out_raw(uint16_t index, uint8_t sub, std::size_t size, uint8_t* field);
    bool locate(uint16_t index, uint8_t sub, std::size_t size, Link& link);
    // The copies of a cycle, one loop per entry size (no test of the size per entry).
    template <typename T>
    static void load(const std::vector<Link>& links);
    template <typename T>
    static void store(const std::vector<Link>& links);
    void load_inputs();
    void store_outputs();
    static std::size_t group(std::size_t size) { return size == 1 ? 0 : size == 2 ? 1 : 2; }

    od::Dictionary& dict_;
    Axis axis_;
    std::vector<Link> inputs_[3];   // dictionary -> axis (parameters, commands), by size: 1, 2, 4 bytes
    std::vector<Link> outputs_[3];  // axis -> dictionary (feedback), by size
    std::vector<Link> position_in_, position_out_;  // position objects in position units (scaled_ only)
    bool scaled_ = false;
    bool velocity_per_second_ = false;
    bool resolution_from_feed_ = false;  // a factor group without 0x608F: increments per unit 1
    Feedback fb_copy_;
    uint32_t resolution_ = 0;
    std::size_t bound_ = 0, missing_ = 0;
    uint32_t withheld_modes_ = 0;
    // Read by the validators (the mailbox side); shared so a validator outliving the Drive stays safe.
    std::shared_ptr<std::atomic<bool>> powered_ = std::make_shared<std::atomic<bool>>(false);
};

}  // namespace drive
