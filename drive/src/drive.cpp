#include "drive/drive.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <type_traits>

namespace drive {
namespace {

// Where each vendor parameter lives in the axis: its field in Parameters or Feedback (or the resolution).
struct VendorField {
    Param param;
    uint8_t* (*field)(Parameters&, Feedback&, uint32_t& resolution);
    uint8_t size;
    bool feedback;
};
template <typename T>
uint8_t* bytes(T& v) {
    return reinterpret_cast<uint8_t*>(&v);
}
// clang-format off
#define DRIVE_VENDOR_FIELDS(X) \
    X(MotorNominalCurrent,           p.nominal_current) \
    X(MotorOutputCurrentLimit,       p.output_current_limit) \
    X(MotorPolePairs,                p.pole_pairs) \
    X(MotorThermalTimeConstant,      p.thermal_time_constant) \
    X(MotorTorqueConstant,           p.torque_constant) \
    X(EncoderPulses,                 p.encoder_pulses) \
    X(EncoderType,                   p.encoder_type) \
    X(AxisConfigurationMisc,         p.axis_misc) \
    X(CurrentPGain,                  p.current_p) \
    X(CurrentIGain,                  p.current_i) \
    X(CurrentFfGain,                 p.current_ff) \
    X(PositionBandwidth,             p.bandwidth) \
    X(PositionDamping,               p.damping) \
    X(PositionResetTime,             p.reset_time) \
    X(Inertia,                       p.inertia) \
    X(Friction,                      p.friction) \
    X(HomePosition,                  p.home_position) \
    X(HomeOffsetMoveDistance,        p.home_offset_move) \
    X(HomingCurrentThreshold,        p.homing_current_threshold) \
    X(StandstillWindow,              p.standstill_window) \
    X(StandstillWindowTime,          p.standstill_time) \
    X(StandstillWindowTimeout,       p.standstill_timeout) \
    X(DigitalInputPolarity,          p.input_polarity) \
    X(DigitalInput1Configuration,    p.input_function[0]) \
    X(DigitalInput2Configuration,    p.input_function[1]) \
    X(DigitalInput3Configuration,    p.input_function[2]) \
    X(DigitalInput4Configuration,    p.input_function[3]) \
    X(DigitalInput5Configuration,    p.input_function[4]) \
    X(DigitalInput6Configuration,    p.input_function[5]) \
    X(PositionActualValueSensor1,    f.position_actual) \
    X(VelocityActualValueSensor1,    f.velocity_actual) \
    X(VelocityActualAveragedSensor1, f.velocity_averaged) \
    X(VelocityActualValueAveraged,   f.velocity_averaged) \
    X(CurrentDemandValue,            f.current_demand) \
    X(CurrentActualValueAveraged,    f.current_averaged) \
    X(DigitalInputLogicState,        f.input_logic_state) \
    X(EncoderIndexPosition,          f.index_position) \
    X(MainSensorResolution,          resolution)
// clang-format on
#define DRIVE_VENDOR_FIELD(name, expr)                                                             \
    VendorField{Param::name,                                                                       \
                [](Parameters& p, Feedback& f, uint32_t& resolution) -> uint8_t* {                 \
                    (void)p, (void)f, (void)resolution;                                            \
                    static_assert(sizeof(expr) == sizeof(vendor::name.def), #name ": field size"); \
                    return bytes(expr);                                                            \
                },                                                                                 \
                sizeof(vendor::name.def), Role::Feedback == vendor_role(Param::name)},
constexpr Role vendor_role(Param p) {
    switch (p) {
#define DRIVE_PARAM_ROLE(name, T, def, role) \
    case Param::name:                        \
        return Role::role;
        DRIVE_VENDOR_PARAMETERS(DRIVE_PARAM_ROLE)
#undef DRIVE_PARAM_ROLE
    }
    return Role::Parameter;
}
constexpr VendorField kVendorFields[] = {DRIVE_VENDOR_FIELDS(DRIVE_VENDOR_FIELD)};
#undef DRIVE_VENDOR_FIELD
// The table above is in the order of Param.
#define DRIVE_PARAM_COUNT(name, T, def, role) +1
static_assert(std::size(kVendorFields) == 0 DRIVE_VENDOR_PARAMETERS(DRIVE_PARAM_COUNT));
constexpr bool in_param_order() {
    for (std::size_t k = 0; k < std::size(kVendorFields); ++k)
        if (static_cast<std::size_t>(kVendorFields[k].param) != k) return false;
    return true;
}
static_assert(in_param_order());
#undef DRIVE_PARAM_COUNT

}  // namespace

bool Drive::locate(uint16_t index, uint8_t sub, std::size_t size, Link& link) {
    const od::Entry* e = dict_.find(index, sub);
    if (!e || e->byte_size() != size) {
        ++missing_;
        return false;
    }
    try {
        if (size == 1)
            link.r8 = dict_.ref<uint8_t>(index, sub);
        else if (size == 2)
            link.r16 = dict_.ref<uint16_t>(index, sub);
        else
            link.r32 = dict_.ref<uint32_t>(index, sub);
    } catch (const std::exception&) {
        ++missing_;
        return false;
    }
    link.size = static_cast<uint8_t>(size);
    link.index = index;
    link.sub = sub;
    ++bound_;
    return true;
}

template <typename T>
void Drive::load(const std::vector<Link>& links) {
    for (const Link& l : links) {
        T v;
        if constexpr (sizeof(T) == 1)
            v = l.r8.get();
        else if constexpr (sizeof(T) == 2)
            v = l.r16.get();
        else
            v = l.r32.get();
        std::memcpy(l.field, &v, sizeof(T));
    }
}

template <typename T>
void Drive::store(const std::vector<Link>& links) {
    for (Link l : links) {
        T v;
        std::memcpy(&v, l.field, sizeof(T));
        if constexpr (sizeof(T) == 1)
            l.r8.set(v);
        else if constexpr (sizeof(T) == 2)
            l.r16.set(v);
        else
            l.r32.set(v);
    }
}

void Drive::load_inputs() {
    load<uint8_t>(inputs_[0]);
    load<uint16_t>(inputs_[1]);
    load<uint32_t>(inputs_[2]);
}

void Drive::store_outputs() {
    store<uint8_t>(outputs_[0]);
    store<uint16_t>(outputs_[1]);
    store<uint32_t>(outputs_[2]);
}

bool Drive::in_raw(uint16_t index, uint8_t sub, std::size_t size, uint8_t* field) {
    Link l{};
    l.field = field;
    if (!locate(index, sub, size, l)) return false;
    inputs_[group(size)].push_back(l);
    return true;
}

bool Drive::out_raw(uint16_t index, uint8_t sub, std::size_t size, uint8_t* field) {
    Link l{};
    l.field = field;
    if (!locate(index, sub, size, l)) return false;
    outputs_[group(size)].push_back(l);
    return true;
}

template <typename T>
void Drive::in_scaled(const Obj<T>& h, T& field, Unit unit) {
    static_assert(sizeof(T) == 4);
    if (!scaled_ || (unit == Unit::Velocity && !velocity_per_second_)) {
        in(h, field);
        return;
    }
    Link l{};
    l.field = reinterpret_cast<uint8_t*>(&field);
    l.is_signed = std::is_signed_v<T>;
    l.unit = unit;
    if (locate(h.index, h.sub, sizeof(T), l)) position_in_.push_back(l);
}

template <typename T>
void Drive::out_scaled(const Obj<T>& h, const T& field, Unit unit) {
    static_assert(sizeof(T) == 4);
    if (!scaled_ || (unit == Unit::Velocity && !velocity_per_second_)) return out(h, field);
    Link l{};
    l.field = reinterpret_cast<uint8_t*>(const_cast<T*>(&field));
    l.is_signed = std::is_signed_v<T>;
    l.unit = unit;
    if (locate(h.index, h.sub, sizeof(T), l)) position_out_.push_back(l);
}

double Drive::increments_per_rev() const {
    const Parameters& p = axis_.params;
    const double per_rev = p.resolution_increments > 0 && p.resolution_revolutions > 0
                               ? static_cast<double>(p.resolution_increments) / p.resolution_revolutions
                               : 4.0 * p.encoder_pulses;
    return per_rev > 0 ? per_rev : 4.0;
}

double Drive::increments_per_unit() const {
    const Parameters& p = axis_.params;
    const double per_rev = increments_per_rev();
    if (p.feed == 0 || p.feed_shaft_revolutions == 0 || p.gear_motor_revolutions == 0 ||
        p.gear_shaft_revolutions == 0)
        return 1.0;  // not configured: increments
    const double gear = static_cast<double>(p.gear_motor_revolutions) / p.gear_shaft_revolutions;
    const double feed = static_cast<double>(p.feed) / p.feed_shaft_revolutions;
    const double f = per_rev * gear / feed;
    return std::isfinite(f) && f > 0 ? f : 1.0;
}

namespace {
// A position value through the factor, saturated; the extremes (limits off, window off) stay extremes.
uint32_t convert(uint32_t raw, bool is_signed, double factor) {
    if (is_signed) {
        const auto v = static_cast<int32_t>(raw);
        if (v == std::numeric_limits<int32_t>::min() || v == std::numeric_limits<int32_t>::max()) return raw;
        const double x = std::clamp(std::round(v * factor), -2147483647.0, 2147483646.0);
        return static_cast<uint32_t>(static_cast<int32_t>(x));
    }
    if (raw == 0xFFFFFFFFu) return raw;
    return static_cast<uint32_t>(std::clamp(std::round(raw * factor), 0.0, 4294967294.0));
}
}  // namespace

void Drive::load_positions() {
    if (resolution_from_feed_) {
        // No 0x608F: the position unit is the increment, so a revolution has as many increments as the feed
        // constant and gear ratio give it (the encoder's resolution the device implies).
        Parameters& p = axis_.params;
        if (p.feed != 0 && p.feed_shaft_revolutions != 0 && p.gear_shaft_revolutions != 0) {
            const double per_rev = static_cast<double>(p.feed) / p.feed_shaft_revolutions *
                                   p.gear_motor_revolutions / p.gear_shaft_revolutions;
            p.resolution_increments =
                static_cast<uint32_t>(std::clamp(std::round(per_rev), 4.0, 1073741824.0));
            p.resolution_revolutions = 1;
        }
    }
    // Position: increments per unit; velocity (acceleration): rpm per unit/s (rpm/s per unit/s^2).
    const double fp = increments_per_unit();
    const double fv = fp * 60.0 / increments_per_rev();
    for (const Link& l : position_in_) {
        const uint32_t v = convert(l.r32.get(), l.is_signed, l.unit == Unit::Position ? fp : fv);
        std::memcpy(l.field, &v, sizeof v);
    }
}

void Drive::store_positions() {
    const double fp = 1.0 / increments_per_unit();
    const double fv = increments_per_rev() / 60.0 * fp;
    for (Link l : position_out_) {
        uint32_t v;
        std::memcpy(&v, l.field, sizeof v);
        l.r32.set(convert(v, l.is_signed, l.unit == Unit::Position ? fp : fv));
    }
}

template <typename T>
bool Drive::in(const Obj<T>& h, T& field) {
    static_assert(sizeof(T) == 1 || sizeof(T) == 2 || sizeof(T) == 4);
    return in_raw(h.index, h.sub, sizeof(T), reinterpret_cast<uint8_t*>(&field));
}

template <typename T>
void Drive::out(const Obj<T>& h, const T& field) {
    static_assert(sizeof(T) == 1 || sizeof(T) == 2 || sizeof(T) == 4);
    out_raw(h.index, h.sub, sizeof(T), reinterpret_cast<uint8_t*>(const_cast<T*>(&field)));
}

bool Drive::binds(uint16_t index, uint8_t sub) const {
    for (const auto* groups : {&inputs_, &outputs_})
        for (const auto& links : *groups)
            for (const Link& l : links)
                if (l.index == index && l.sub == sub) return true;
    for (const auto* links : {&position_in_, &position_out_})
        for (const Link& l : *links)
            if (l.index == index && l.sub == sub) return true;
    return false;
}

Drive::Drive(od::Dictionary& dictionary, EventSink* sink, const VendorObjects& vendor)
    : dict_(dictionary), axis_(sink) {
    Parameters& p = axis_.params;
    Command& c = axis_.command;
    Feedback& f = fb_copy_;
    // A device with a gear ratio or feed constant states positions in its position units (IEC 61800-7-201
    // factor group); without them the units are the encoder's increments and nothing is converted.
    scaled_ = dict_.find(obj::GearMotorRevolutions.index) != nullptr ||
              dict_.find(obj::FeedConstantFeed.index) != nullptr;
    resolution_from_feed_ = scaled_ && dict_.find(obj::PositionEncoderIncrements.index) == nullptr;
    // Velocities then in position units per second (accelerations per second squared), as 0x60A9/0x60AA
    // default to (IEC 61800-7-201), unless 0x60A9 says revolutions per minute (0x00B447xx).
    if (scaled_) {
        const od::Entry* si = dict_.find(0x60A9, 0);
        velocity_per_second_ =
            !(si && si->byte_size() == 4 && (dict_.get<uint32_t>(0x60A9, 0) & 0xFFFFFF00u) == 0x00B44700u);
    }
    // The CiA 402 objects, by index, wherever they are.
    {
        using namespace obj;
        in(MotorType, p.motor_type);
        in(AbortConnectionOptionCode, p.abort_connection);
        // Without 0x605A the profile's own default, 2 (IEC 61800-7-201: quick stop ramp, then switch on
        // disabled), not the MAXPOS's 6: a vendor's drive whose ESI leaves the object out (Beckhoff EJ7211,
        // Synapticon, Elmo) behaves as the profile says and as a master reading no 0x605A expects.
        if (!in(QuickStopOptionCode, p.quick_stop)) p.quick_stop = kProfileQuickStopOptionCode;
        in(ShutdownOptionCode, p.shutdown);
        in(DisableOperationOptionCode, p.disable_operation);
        in(HaltOptionCode, p.halt);
        in(FaultReactionOptionCode, p.fault_reaction);
        in_scaled(FollowingErrorWindow, p.following_error_window, Unit::Position);
        in(FollowingErrorTimeout, p.following_error_timeout);
        in_scaled(SoftwarePositionLimitMin, p.sw_limit_min, Unit::Position);
        in_scaled(SoftwarePositionLimitMax, p.sw_limit_max, Unit::Position);
        in_scaled(PositionRangeLimitMin, p.range_min, Unit::Position);
        in_scaled(PositionRangeLimitMax, p.range_max, Unit::Position);
        in_scaled(MaxProfileVelocity, p.max_profile_velocity, Unit::Velocity);
        in_scaled(MaxMotorSpeed, p.max_motor_speed, Unit::Velocity);
        in_scaled(ProfileVelocity, p.profile_velocity, Unit::Velocity);
        in_scaled(ProfileAcceleration, p.profile_acceleration, Unit::Velocity);
        in_scaled(ProfileDeceleration, p.profile_deceleration, Unit::Velocity);
        in_scaled(QuickStopDeceleration, p.quick_stop_deceleration, Unit::Velocity);
        in(TorqueSlope, p.torque_slope);
        in(TorqueProfileType, p.torque_profile_type);
        in(InterpolationSubMode, p.interpolation_sub_mode);
        in_scaled(MaxAcceleration, p.max_acceleration, Unit::Velocity);
        in(HomingMethod, p.homing_method);
        in_scaled(HomingSpeedSwitchSearch, p.homing_speed_switch, Unit::Velocity);
        in_scaled(HomingSpeedZeroSearch, p.homing_speed_zero, Unit::Velocity);
        in_scaled(HomingAcceleration, p.homing_acceleration, Unit::Velocity);
        in(InterpolationTimePeriodValue, p.interpolation_value);
        in(InterpolationTimeIndex, p.interpolation_index);
        in(TouchProbe1Source, p.touch_probe_source);
        in(SupportedDriveModes, p.supported_modes);
        in(PositionEncoderIncrements, p.resolution_increments);
        in(PositionEncoderRevolutions, p.resolution_revolutions);
        in(GearMotorRevolutions, p.gear_motor_revolutions);
        in(GearShaftRevolutions, p.gear_shaft_revolutions);
        in(FeedConstantFeed, p.feed);
        in(FeedConstantShaftRevolutions, p.feed_shaft_revolutions);
        in(Controlword, c.controlword);
        in(ModesOfOperation, c.mode);
        in_scaled(TargetPosition, c.target_position, Unit::Position);
        in_scaled(TargetVelocity, c.target_velocity, Unit::Velocity);
        in(TargetTorque, c.target_torque);
        in_scaled(InterpolationDataPosition, c.ip_position, Unit::Position);
        in_scaled(PositionOffset, c.position_offset, Unit::Position);
        in_scaled(VelocityOffset, c.velocity_offset, Unit::Velocity);
        in(TorqueOffset, c.torque_offset);
        in(TouchProbeFunction, c.touch_probe_function);
        out(Statusword, f.statusword);
        out(ModesOfOperationDisplay, f.mode_display);
        out_scaled(PositionDemandValue, f.position_demand, Unit::Position);
        out_scaled(PositionActualValue, f.position_actual, Unit::Position);
        out_scaled(VelocityDemandValue, f.velocity_demand, Unit::Velocity);
        out_scaled(VelocityActualValue, f.velocity_actual, Unit::Velocity);
        out(TorqueDemand, f.torque_demand);
        out(TorqueActualValue, f.torque_actual);
        out(CurrentActualValue, f.current_actual);
        out_scaled(FollowingErrorActualValue, f.following_error, Unit::Position);
        out(MotorRatedTorque, f.motor_rated_torque);
        out(DigitalInputs, f.digital_inputs);
        out(TouchProbeStatus, f.touch_probe_status);
        out_scaled(TouchProbePosition1Positive, f.touch_probe_pos, Unit::Position);
        out_scaled(TouchProbePosition1Negative, f.touch_probe_neg, Unit::Position);
        out(TouchProbe1PositiveEdgeCounter, f.touch_probe_pos_count);
        out(TouchProbe1NegativeEdgeCounter, f.touch_probe_neg_count);
        out(ErrorCode, f.error_code);
        out(ErrorRegister, f.error_register);
    }
    // The vendor parameters where the device keeps them.
    bool bound_params[std::size(kVendorFields)] = {};
    for (const Binding& b : vendor.bindings) {
        const auto k = static_cast<std::size_t>(b.param);
        if (k >= std::size(kVendorFields)) continue;
        const VendorField& vf = kVendorFields[k];
        uint8_t* field = vf.field(p, f, resolution_);
        if (vf.feedback)
            bound_params[k] = out_raw(b.index, b.sub, vf.size, field);
        else
            bound_params[k] = in_raw(b.index, b.sub, vf.size, field);
    }
    // Without the device's motor data and tuning, the motor model's (as commission() writes them).
    // Such a drive (a vendor's CiA 402 drive, tuned by its maker for its motor) follows a CSP trajectory
    // as drives that interpolate the set-points do: with the velocity of its own demand fed forward, so a
    // constant-speed ramp has no lag to speak of (the MAXPOS, whose position regulator the device declares,
    // takes feed-forward only from the master's offsets 0x60B1/0x60B2, as its firmware specification says).
    p.csp_own_feed_forward = !bound_params[static_cast<std::size_t>(Param::PositionBandwidth)];
    const MotorModel& m = axis_.motor();
    for (const auto& [param, value] : commissioned(m))
        if (!bound_params[static_cast<std::size_t>(param)]) {
            uint8_t* field = kVendorFields[static_cast<std::size_t>(param)].field(p, f, resolution_);
            std::memcpy(field, &value, sizeof value);
        }

    // The modes this dictionary can serve: those the drive implements whose set-point object it has
    // (drive::mode_setpoint_entry). 0x6502 announces what is served: the device's announcement without the
    // modes the drive cannot serve here (the interpolated position mode of a dictionary without 0x60C1, a
    // manufacturer-specific mode, the velocity mode); a 0x6502 of 0, which states nothing, announces every
    // mode served (docs/decisions/device.md, "Modes a vendor's 0x6502 announces").
    uint32_t served = 0;
    for (int8_t mo : kModesOfOperation)
        if (const SetpointEntry o = mode_setpoint_entry(mo);
            o.index == 0 || dict_.find(o.index, o.sub) != nullptr)
            served |= mode_bit(mo);
    axis_.serve_modes(served);
    if (const od::Entry* modes_entry =
            dict_.find(obj::SupportedDriveModes.index, obj::SupportedDriveModes.sub);
        modes_entry != nullptr && modes_entry->byte_size() == 4) {
        const uint32_t announced = dict_.get<uint32_t>(obj::SupportedDriveModes.index, 0);
        const uint32_t kept = (announced == 0 ? supported_drive_modes() : announced) & served;
        withheld_modes_ = announced & ~kept;
        if (kept != announced) (void)dict_.set<uint32_t>(obj::SupportedDriveModes.index, 0, kept);
    }
    // Only the linear interpolation (sub-mode 0x60C0 = 0) is served: 0x60C0 says so, and a master's write of
    // another sub-mode is refused ("value range exceeded").
    if (const od::Entry* ism = dict_.find(obj::InterpolationSubMode.index, obj::InterpolationSubMode.sub);
        ism != nullptr && ism->byte_size() == 2) {
        (void)dict_.set<int16_t>(obj::InterpolationSubMode.index, obj::InterpolationSubMode.sub, 0);
        dict_.add_validator(
            obj::InterpolationSubMode.index,
            [](const od::Entry& e, std::span<const uint8_t> v) {
                if (e.subindex != obj::InterpolationSubMode.sub || v.size() != 2) return od::Status::Ok;
                return v[0] == 0 && v[1] == 0 ? od::Status::Ok : od::Status::InvalidValue;
            },
            this);
    }

    // A mode the drive does not implement, cannot serve, or the device does not announce in 0x6502 is refused
    // (IEC 61800-7-201: 0x6061 shows the mode the drive runs; an SDO write answers "value range exceeded").
    // 0 is taken: "no mode change / no mode assigned" (IEC 61800-7-201 0x6060), the value a vendor's
    // dictionary holds before a master chooses a mode; the drive keeps the mode it runs, as with 0 in the
    // process data.
    if (dict_.find(obj::ModesOfOperation.index, obj::ModesOfOperation.sub)) {
        dict_.add_validator(
            obj::ModesOfOperation.index,
            [d = &dict_, served](const od::Entry& e, std::span<const uint8_t> v) {
                if (e.subindex != obj::ModesOfOperation.sub || v.size() != 1 || v[0] == 0)
                    return od::Status::Ok;
                uint32_t announced = supported_drive_modes();
                const od::Entry* sdm = d->find(obj::SupportedDriveModes.index, obj::SupportedDriveModes.sub);
                if (sdm && sdm->byte_size() == 4)
                    announced =
                        d->get<uint32_t>(obj::SupportedDriveModes.index, obj::SupportedDriveModes.sub);
                return mode::supported(static_cast<int8_t>(v[0]), announced, served)
                           ? od::Status::Ok
                           : od::Status::InvalidValue;
            },
            this);
    }

    for (const PowerDisableOnly& lock : vendor.power_disable_only) {
        if (!dict_.find(lock.index)) continue;
        // Owned by this drive (removed by its destructor): a dictionary that outlives its drive, or serves
        // one drive after another, keeps no validator of a drive that is gone.
        dict_.add_validator(
            lock.index,
            [flag = powered_, sub = lock.sub](const od::Entry& e, std::span<const uint8_t>) {
                if (sub >= 0 && e.subindex != sub) return od::Status::Ok;
                return flag->load(std::memory_order_relaxed) ? od::Status::WrongState : od::Status::Ok;
            },
            this);
    }
}

Drive::~Drive() {
    powered_->store(false);
    dict_.remove_hooks(this);
}

std::array<std::pair<Param, uint32_t>, 6> commissioned(const MotorModel& m) {
    const double j = m.rotor_inertia + m.load_inertia;
    return {{
        {Param::MotorTorqueConstant, static_cast<uint32_t>(std::lround(m.torque_constant * 1e6))},  // uNm/A
        {Param::PositionBandwidth, 20000},                                                          // 20 Hz
        {Param::PositionDamping, 1000},                                  // critical damping
        {Param::PositionResetTime, 50000},                               // 50 ms
        {Param::Inertia, static_cast<uint32_t>(std::lround(j * 1e10))},  // mg cm^2
        {Param::Friction,
         static_cast<uint32_t>(std::lround(m.viscous_friction * 1e9 * 6.283185307179586 / 60.0))},
    }};
}

od::Status commission(od::Dictionary& d, const VendorObjects& vendor, const MotorModel& m) {
    for (const auto& [param, value] : commissioned(m)) {
        const Binding* b = vendor.find(param);
        if (b == nullptr || d.find(b->index, b->sub) == nullptr) continue;  // only objects that exist
        const od::Status s = d.set<uint32_t>(b->index, b->sub, value);
        if (s != od::Status::Ok) return s;
    }
    return od::Status::Ok;
}

void Drive::cycle(int64_t now_ns, int64_t dt_ns) {
    load_inputs();
    load_positions();
    axis_.cycle(now_ns, dt_ns);
    fb_copy_ = axis_.feedback();
    resolution_ = static_cast<uint32_t>(axis_.increments_per_rev());
    store_outputs();
    store_positions();
    powered_->store(axis_.power_on(), std::memory_order_relaxed);
}

void Drive::connection_lost() {
    axis_.connection_lost();
    fb_copy_ = axis_.feedback();
    store_outputs();
    store_positions();
}

}  // namespace drive
